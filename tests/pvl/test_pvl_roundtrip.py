"""Round trips: files this package writes read back to the same model and are rewritten byte for byte;
the text details the reader accepts (CRLF, trailing blanks, Latin-1, commas in the last column)."""

from __future__ import annotations

import pytest

from linmot_st.pvl import PvlError, demo, load_pvl, parse_pvl, save_pvl, write_pvl
from linmot_st.pvl.model import CommandTableEntry, Curve, Parameter, ParameterObject, PvlFile


@pytest.mark.parametrize("name", sorted(demo.EXAMPLES))
def test_examples_round_trip(name, tmp_path):
    model = demo.EXAMPLES[name]()
    text = write_pvl(model)
    assert parse_pvl(text) == model
    assert write_pvl(parse_pvl(text)) == text
    save_pvl(model, tmp_path / name)
    assert load_pvl(tmp_path / name) == model
    assert load_pvl(tmp_path / name).filename == str(tmp_path / name)


def test_object_order_is_kept():
    model = demo.two_axes_file()
    shuffled = PvlFile(tuple(reversed(model.objects)))
    assert parse_pvl(write_pvl(shuffled)) == shuffled
    assert parse_pvl(write_pvl(shuffled)) != model


def test_empty_file():
    assert write_pvl(PvlFile()) == "@FileType,PVL\n@FormatVersion,1\n"
    assert parse_pvl("@FileType,PVL\n@FormatVersion,1\n") == PvlFile()


MC = ParameterObject("MCTREE1100DSW4_HC_V3S0_b1", 2, 4612, 3, 0, "b1",
                     (Parameter(0x1385, 0x00000BB8, r"Motion Control SW\Max Current", "3,0 A"),))


def test_commas_in_the_scaled_value_are_kept():
    # the scaled value is the last column: it keeps every comma (German LinMot-Talk writes '3,0 A')
    text = write_pvl(PvlFile((MC,)))
    assert "1385,00000BB8,Motion Control SW\\Max Current,3,0 A\n" in text
    assert parse_pvl(text).parameter_objects[0].parameters[0].scaled_value == "3,0 A"


def test_foreign_text_details():
    text = write_pvl(PvlFile((MC,)))
    crlf_blanks = text.replace("\n", " \t\r\n").replace("@StartObject", "\n\n@StartObject")
    assert parse_pvl(crlf_blanks) == parse_pvl(text)
    lower = text.replace("00000BB8", "00000bb8").replace("1385,", "1385,")
    assert parse_pvl(lower) == parse_pvl(text)
    no_final_newline = text.rstrip("\n")
    assert parse_pvl(no_final_newline) == parse_pvl(text)


def test_latin1_bytes_round_trip(tmp_path):
    # LinMot-Talk is a Windows program: units such as 'µm' arrive as single bytes (B5h); a cp1252 ellipsis (85h)
    # inside a caption must not split the line
    obj = ParameterObject("MCTREE1100DSW4_HC_V3S0_b1", 2, 4612, 3, 0, "b1",
                          (Parameter(0x1472, 0x0000C350, "Max Pos Following Error\x85", "5000 \u00b5m"),))
    model = PvlFile((obj,))
    save_pvl(model, tmp_path / "u.pvl")
    raw = (tmp_path / "u.pvl").read_bytes()
    assert b"5000 \xb5m" in raw and b"Error\x85," in raw
    assert load_pvl(tmp_path / "u.pvl") == model


def test_leading_blanks_in_text_columns_are_kept():
    obj = ParameterObject(" tree", 2, 4612, 3, 0, " b1", (Parameter(0x1194, 2, "  Motor Type  ", "  P01"),))
    model = PvlFile((obj,))
    assert parse_pvl(write_pvl(model)) == model


def test_signed_setpoints_round_trip():
    curve = Curve.make(5, "Below_Zero", (-(1 << 31), -1, 0, 1, (1 << 31) - 1), 1000)
    text = write_pvl(PvlFile((curve,)))
    assert "80000000h\nFFFFFFFFh\n00000000h\n00000001h\n7FFFFFFFh\n" in text
    assert parse_pvl(text).curves[0].setpoints == (-(1 << 31), -1, 0, 1, (1 << 31) - 1)


def test_curve_name_is_written_from_the_info_block():
    curve = Curve.make(100, "", (0, 10), 1)      # machine generated: the name field is all 00h
    text = write_pvl(PvlFile((curve,)))
    assert "@CurveName,\n@CurveID,100\n" in text
    assert parse_pvl(text).curves == (curve,)


def test_command_table_entry_round_trip():
    entry = CommandTableEntry.make(0, "A" * 16, 0x0100, bytes(range(32)), linked_entry=255)
    text = write_pvl(PvlFile((entry,)))
    assert "@StartObject,CommandTableEntry\n@EntryID,0\n@EntryName,AAAAAAAAAAAAAAAA\n@DataBlockByteSize,64\n" in text
    assert parse_pvl(text).command_table == (entry,)


def test_utf8_with_byte_order_mark():
    # an editor may save the file as UTF-8 with a BOM: read it as UTF-8
    text = write_pvl(PvlFile((MC,))).replace("3,0 A", "3,0 \u00b5A")
    assert parse_pvl(b"\xef\xbb\xbf" + text.encode("utf-8")) == parse_pvl(text.encode("latin-1"))
    bad = b"\xef\xbb\xbf" + text.encode("latin-1")
    with pytest.raises(PvlError) as info:
        parse_pvl(bad, filename="b.pvl")
    assert str(info.value) == "b.pvl:13: the file starts with a UTF-8 byte-order mark but this line is not UTF-8"
