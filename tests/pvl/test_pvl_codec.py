"""The PVL codecs against the shared vectors (tests/vectors/), which the ST library's codecs use too."""

from __future__ import annotations

import json
import struct

import pytest

from linmot_st.pvl import CtEntryBlock, Curve, CurveInfo, PvlFile, codec, parse_pvl, write_pvl
from linmot_st.pvl.drive_types import drive_type
from repo_paths import VECTORS

CURVES = json.loads((VECTORS / "curve_info.json").read_text())["curves"]
STRINGS = json.loads((VECTORS / "stringlets.json").read_text())["strings"]


@pytest.mark.parametrize("vec", CURVES, ids=[c["fields"]["name"] for c in CURVES])
def test_curve_info_vectors(vec):
    words = tuple(int(w, 16) for w in vec["info_words"])
    block, pad = codec.words_to_bytes(words, vec["info_block_size"])
    assert block.hex().upper() == vec["info_block"] and pad.hex().upper() == vec["pad_bytes"]
    info = CurveInfo.from_bytes(block)
    f = vec["fields"]
    assert info == CurveInfo(curve_id=f["curve_id"], name=f["name"], setpoints=f["setpoints"], x_length=f["x_length"],
                             object_type=f["object_type"], x_dim_uuid=f["x_dim_uuid"], y_dim_uuid=f["y_dim_uuid"],
                             data_offset=f["data_offset"], type_size=f["type_size"], wizard_type=f["wizard_type"],
                             wizard_params=tuple(f["wizard_params"]))
    assert info.to_bytes() == block
    assert codec.bytes_to_words(block) == words
    assert codec.curve_info_problems(block, len(vec["setpoints"])) == []
    data = [int(w, 16) for w in vec["data_words"]]
    assert [codec.to_signed32(w) for w in data] == vec["setpoints"]
    assert len(data) * 4 == vec["data_block_size"]
    # the layout table of the vector file agrees with the struct the codec uses
    offsets = {name: off for name, off, _ in json.loads((VECTORS / "curve_info.json").read_text())["layout"]}
    assert struct.unpack_from("<H", block, offsets["curve_id"])[0] == f["curve_id"]
    assert struct.unpack_from("<I", block, offsets["x_length"])[0] == f["x_length"]


@pytest.mark.parametrize("vec", CURVES, ids=[c["fields"]["name"] for c in CURVES])
def test_curve_vectors_through_pvl_text(vec):
    block, _ = codec.words_to_bytes([int(w, 16) for w in vec["info_words"]], 70)
    curve = Curve(block, tuple(vec["setpoints"]))
    text = write_pvl(PvlFile((curve,)))
    assert "\n".join(w + "h" for w in vec["info_words"]) in text
    assert "\n".join(w + "h" for w in vec["data_words"]) in text
    assert parse_pvl(text).curves == (curve,)


@pytest.mark.parametrize("vec", STRINGS, ids=[s["text"] or "empty" for s in STRINGS])
def test_stringlet_vectors(vec):
    values = tuple(int(s["value"], 16) for s in vec["stringlets"])
    assert codec.encode_stringlets(vec["text"], vec["count"]) == values
    assert codec.decode_stringlets(values) == vec["text"]
    base = int(vec["string_upid"], 16)
    for k, s in enumerate(vec["stringlets"], start=1):
        assert int(s["upid"], 16) == drive_type(vec.get("drive", "E1100")).stringlet_upid(base, k)
        assert codec.stringlet_text(int(s["value"], 16)) == s["text"]


def test_stringlet_first_character_is_least_significant():
    assert codec.encode_stringlets("X Ax") == (0x78412058,)
    assert codec.encode_stringlets("eft") == (0x00746665,)
    assert codec.decode_stringlets([0x78412058, 0x4C207369, 0x00746665, 0x41414141]) == "X Axis Left"


def test_signed_setpoints():
    assert codec.to_signed32(0xFFFFFFFF) == -1 and codec.to_signed32(0x80000000) == -(1 << 31)
    assert codec.to_unsigned32(-1) == 0xFFFFFFFF and codec.to_signed32(0x7FFFFFFF) == (1 << 31) - 1


def test_ct_entry_block_layout():
    params = struct.pack("<iIII", -50_000, 200_000, 500_000, 500_000)
    block = CtEntryBlock(name="Go_Below_Zero", motion_header=0x0100, parameters=params, linked_entry=7).to_bytes()
    assert len(block) == 64
    assert block[0:2] == b"\x01\xA7"                     # version ID A701h, little-endian
    assert block[2:4] == b"\x07\x00"                     # linked entry 7
    assert block[4:6] == b"\x00\x01"                     # motion command header 0100h
    assert block[6:22] == params and block[22:38] == bytes(16)
    assert block[0x26:0x26 + 13] == b"Go_Below_Zero" and block[0x26 + 13:] == bytes(64 - 0x26 - 13)
    back = CtEntryBlock.from_bytes(block)
    assert (back.name, back.motion_header, back.linked_entry, back.version_id) == ("Go_Below_Zero", 0x0100, 7, 0xA701)
    assert codec.ct_entry_problems(block) == []


def test_ct_name_may_fill_all_16_bytes():
    block = CtEntryBlock(name="A" * 16, motion_header=0).to_bytes()
    assert CtEntryBlock.from_bytes(block).name == "A" * 16
