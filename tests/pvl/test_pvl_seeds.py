"""The seed documents' examples (chapter 7, Figures 13 and 14) decode to what the documents say, and the
shipped example files are what linmot_st.pvl.demo builds."""

from __future__ import annotations

import pytest

from linmot_st.pvl import LAYERS, TreeIdentity, codec, demo, load_pvl, parse_pvl, write_pvl
from repo_paths import EXAMPLES, REPO

# Figure 14 as printed in the older document (001, LinMot Talk1100): trailing blanks after most lines
SEED_CURVE_001 = """@FileType,PVL \n@FormatVersion,1 \n \n@StartObject,Curve \n@CurveName,Example_Curve \n\
@CurveID,23 \n@InfoBlockByteSize,70 \n@DataBlockByteSize,40 \n@StartInfo  \n@Col1:Value \n00030046h \n\
0004000Ah \n6D617845h \n5F656C70h \n76727543h \n00000065h \n00000000h \n00170000h \n00004E20h \n0005001Ah \n\
4E200301h \n00000000h \n42400000h \n0000000Fh \n00000000h \n00000000h \n00000000h \n00000000h \n@EndInfo \n\
@StartData \n@Col1:Value \n00000000h \n000075CAh \n0001C8F2h \n0003D090h \n00064DF8h \n0008F448h \n000B71B0h \n\
000D794Eh \n000ECC76h \n000F4240h \n@EndData  \n@EndObject \n"""


def test_seed_curve_decodes_as_documented():
    pvl = load_pvl(EXAMPLES / "seed_curve.pvl")
    (curve,) = pvl.curves
    info = curve.info
    assert (info.curve_id, info.name) == (23, "Example_Curve")
    assert info.data_offset == 70 == len(curve.info_block)
    assert info.object_type == 0x0003 and info.kind == "position vs time"
    assert (info.setpoints, info.type_size) == (10, 4)
    assert info.x_length == 20000                                  # 200 ms in 10 us units
    assert (info.x_dim_uuid, info.y_dim_uuid) == (0x001A, 0x0005)
    assert len(curve.data_block) == 40
    assert curve.setpoints[0] == 0 and curve.setpoints[-1] == 1_000_000     # 100 mm in 0.1 um
    assert curve.setpoints == tuple(sorted(curve.setpoints))


def test_seed_curve_byte_order():
    # 00030046h = data offset 0046h then object type 0003h: each word is little-endian over the block
    curve = load_pvl(EXAMPLES / "seed_curve.pvl").curves[0]
    assert curve.info_block[:4] == bytes([0x46, 0x00, 0x03, 0x00])
    assert curve.info_block[8:21] == b"Example_Curve"
    assert curve.info_block[30:32] == bytes([0x17, 0x00])
    assert curve.info_words[0] == 0x00030046


def test_seed_curve_file_is_the_document_text():
    # the writer reproduces Figure 14 exactly, and reads the older document's copy (trailing blanks) alike
    text = (EXAMPLES / "seed_curve.pvl").read_text("latin-1")
    assert write_pvl(parse_pvl(text)) == text
    assert parse_pvl(SEED_CURVE_001) == parse_pvl(text)
    assert write_pvl(parse_pvl(SEED_CURVE_001)) == text


def test_seed_curve_with_windows_line_ends():
    text = (EXAMPLES / "seed_curve.pvl").read_text("latin-1")
    assert parse_pvl(text.replace("\n", "\r\n").encode("latin-1")) == parse_pvl(text)


def test_seed_parameters_decode_as_documented():
    pvl = load_pvl(EXAMPLES / "seed_parameters.pvl")
    os_layer, mc_layer = pvl.parameter_objects
    assert os_layer.identity == TreeIdentity(layer=1, tree_id=1, main_version=3, sub_version=0)
    assert (os_layer.tree_file_name, os_layer.revision) == ("OSTREE1100OS__V3S0_b1", "b1")
    assert mc_layer.identity == TreeIdentity(layer=2, tree_id=4612, main_version=3, sub_version=0)
    assert mc_layer.tree_file_name == "MCTREE1100DSW4_HC_V3S0_b1"
    # stringlets 'X Ax' / 'is L' / 'eft' at 03F3h..03F5h: User Comment (UPID 03F2h) = 'X Axis Left'
    assert [os_layer.get(u).value for u in (0x03F3, 0x03F4, 0x03F5)] == [0x78412058, 0x4C207369, 0x00746665]
    assert [codec.stringlet_text(os_layer.get(u).value) for u in (0x03F3, 0x03F4, 0x03F5)] == ["X Ax", "is L", "eft"]
    assert os_layer.string(0x03F2) == "X Axis Left"
    assert os_layer.string(0x03E8) == "MyController"
    assert [(s.upid, s.name, s.text) for s in os_layer.strings()] == [
        (0x03E8, r"OS\Controller Name", "MyController"), (0x03F2, r"OS\User Comment", "X Axis Left")]
    motor_type = mc_layer.get(0x1194)
    assert (motor_type.value, motor_type.caption, motor_type.scaled_value) == (
        2, r"Motion Control SW\Motor Configuration\Motor Type", "P01")


def test_seed_parameters_os_object_is_the_document_text():
    # Figure 13's OS object is kept verbatim; only the MC object's elided rows are filled in
    text = (EXAMPLES / "seed_parameters.pvl").read_text("latin-1")
    figure_13_os = r"""@StartObject,Parameter
@TreeFileName,OSTREE1100OS__V3S0_b1
@TreeLayer,1
@TreeID,1
@MainVersion,3
@SubVersion,0
@Revision,b1
@StartData
@Col1:UPID,@Col2:Value,@Col3:Caption,@Col4:ScaledValue Unit
03E9,6F43794D,OS\Controller Name_1,MyCo
03EA,6F72746E,OS\Controller Name_2,ntro
03EB,72656C6C,OS\Controller Name_3,ller
03EC,00000000,OS\Controller Name_4,
03ED,00000000,OS\Controller Name_5,
03EE,00000000,OS\Controller Name_6,
03EF,00000000,OS\Controller Name_7,
03F0,00000000,OS\Controller Name_8,
03F3,78412058,OS\User Comment_1,X Ax
03F4,4C207369,OS\User Comment_2,is L
03F5,00746665,OS\User Comment_3,eft
03F6,00000000,OS\User Comment_4,
03F7,00000000,OS\User Comment_5,
03F8,00000000,OS\User Comment_6,
03F9,00000000,OS\User Comment_7,
03FA,00000000,OS\User Comment_8,
@EndData
@EndObject
"""
    assert text.startswith("@FileType,PVL\n@FormatVersion,1\n\n" + figure_13_os)
    assert "1194,00000002,Motion Control SW\\Motor Configuration\\Motor Type,P01\n" in text


def test_seed_parameters_with_elided_rows_are_rejected():
    text = (EXAMPLES / "seed_parameters.pvl").read_text("latin-1")
    lines = text.split("\n")
    i = next(n for n, ln in enumerate(lines) if ln.startswith("11A0,"))
    lines[i:i + 5] = ["……", "……"]     # the document's Figure 13 as printed
    with pytest.raises(Exception) as info:
        parse_pvl("\n".join(lines), filename="fig13.pvl")
    assert str(info.value).startswith(f"fig13.pvl:{i + 1}: a parameter row has 4 columns")


@pytest.mark.parametrize("name", sorted(demo.EXAMPLES))
def test_example_files_are_generated(name):
    assert (EXAMPLES / name).read_bytes() == write_pvl(demo.EXAMPLES[name]()).encode("latin-1")


def test_two_axes_example():
    pvl = load_pvl(EXAMPLES / "two_axes.pvl")
    os_layer, mc_layer = pvl.parameter_objects
    assert os_layer.identity == TreeIdentity(1, 1, 3, 0) and mc_layer.identity == TreeIdentity(2, 4612, 3, 0)
    assert os_layer.string(0x03E8) == "LinMot-ST Demo" and os_layer.string(0x03F2) == "X Axis Left"
    assert mc_layer.get(0x1194).value == 2 and pvl.layer(2) is mc_layer and pvl.layer(3) is None
    assert mc_layer.get(0x146E).signed_value == -100_000
    assert len(mc_layer.parameters) >= 12
    assert all(LAYERS[2].holds(p.upid) for p in mc_layer.parameters)
    assert pvl.curve(23) == demo.seed_curve()
    long = max(pvl.curves, key=lambda c: len(c.setpoints))
    assert len(long.setpoints) >= 200 and long.info.kind == "position vs time"
    steps = [b - a for a, b in zip(long.setpoints, long.setpoints[1:])]
    assert min(steps) >= 0 and long.setpoints[-1] == 1_000_000          # a smooth 0 -> 100 mm move
    assert max(steps) < 3 * 1_000_000 / len(steps)
    assert {e.entry_id for e in pvl.command_table} == {1, 2, 3}
    assert pvl.entry(1).block.linked_entry == 2


def test_two_axes_parameters_exist_on_the_emulated_drive():
    # the demo commissions the emulated drive: every UPID of the example must be a writable parameter there,
    # with its value inside the drive's limits
    import csv
    table = REPO / "harness/linmot_st/emulator/data/e1100_parameters.csv"
    assert table.exists(), f"{table}: the emulator's parameter table is missing"
    rows = csv.DictReader(ln for ln in table.read_text().splitlines() if not ln.startswith("#"))
    drive = {int(r["upid"], 16): r for r in rows}
    pvl = load_pvl(EXAMPLES / "two_axes.pvl")
    for layer in pvl.parameter_objects:
        strings = {s.upid: s for s in layer.strings()}
        for p in layer.parameters:
            if p.upid in drive:
                row = drive[p.upid]
                assert row["kind"] == "par" and row["access"] == "rw", (hex(p.upid), row)
                value = p.signed_value if row["type"].startswith("SINT") else p.value
                if row["min"]:
                    assert int(row["min"], 0) <= value <= int(row["max"], 0), (hex(p.upid), value, row)
            else:  # a stringlet of a string parameter the drive has
                owner = next(s for s in strings.values() if p in s.stringlets)
                assert drive[owner.upid]["kind"] == "string"
                assert p.upid - owner.upid <= int(drive[owner.upid]["stringlets"])


def test_tree_identity_rules():
    file_id = TreeIdentity(layer=2, tree_id=4612, main_version=3, sub_version=1)
    assert file_id.problems_against(4612, 3, 1) == []
    assert file_id.problems_against(4612, 3, 2) == []                     # newer sub version on the drive
    assert "sub version" in file_id.problems_against(4612, 3, 0)[0]
    assert "main version" in file_id.problems_against(4612, 4, 1)[0]
    assert "tree ID" in file_id.problems_against(4613, 3, 1)[0]
    assert len(file_id.problems_against(1, 2, 0)) == 3
