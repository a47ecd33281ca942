"""B1100 value lists: the drive series a PVL file is for (tree file names, docs/pvl.md), the B1100's mixed UPID
ranges, stringlets from the string UPID itself, its tree-identity UPIDs, and what a B1100 file may not hold."""

from __future__ import annotations

import pytest

from linmot_st.cli import main
from linmot_st.emulator.linmot.profile import B1100_PROFILE, load_profile
from linmot_st.pvl import PvlError, demo, load_pvl, parse_pvl, write_pvl
from linmot_st.pvl.drive_types import B1100, E1100, drive_type, drive_type_of_tree_file
from linmot_st.pvl.model import Parameter, ParameterObject, PvlFile
from linmot_st.pvl.to_st import read_st
from repo_paths import EXAMPLES

EXAMPLE = EXAMPLES / "b1100_axis.pvl"


def test_series_from_the_tree_file_name():
    assert drive_type_of_tree_file("OSTREE1100OS__V3S0_b1") is E1100          # the seeds' example
    assert drive_type_of_tree_file("MCTREE1100DSW4_HC_V3S0_b1") is E1100
    assert drive_type_of_tree_file("OSTREEB1100OS_V3S0_b1") is B1100
    assert drive_type("b1100") is B1100 and drive_type("E1100") is E1100
    with pytest.raises(ValueError, match="C1250"):
        drive_type("C1250")
    assert load_pvl(EXAMPLE).drive_type is B1100
    assert load_pvl(EXAMPLE.with_name("two_axes.pvl")).drive_type is E1100


def test_seed_stringlets_on_both_series():
    """Seed 000 2.5: 'X Axis Left' as User Comment is 03F3h..03F5h on the E1100 and 7078h..707Ah on the B1100,
    with the same values."""
    values = (0x78412058, 0x4C207369, 0x00746665)
    assert [E1100.stringlet_upid(0x03F2, k) for k in (1, 2, 3)] == [0x03F3, 0x03F4, 0x03F5]
    assert [B1100.stringlet_upid(0x7078, k) for k in (1, 2, 3)] == [0x7078, 0x7079, 0x707A]
    for tree, upid in (("OSTREE1100OS__V3S0_b1", 0x03F2), ("OSTREEB1100OS_V3S0_b1", 0x7078)):
        first = upid + (1 if tree.startswith("OSTREE1100") else 0)
        rows = tuple(Parameter(first + i, v, f"OS\\User Comment_{i + 1}", t)
                     for i, (v, t) in enumerate(zip(values, ("X Ax", "is L", "eft"))))
        obj = ParameterObject(tree, 1, 1, 3, 0, "b1", rows)
        assert obj.string(upid) == "X Axis Left"
        (s,) = obj.strings()
        assert (s.upid, s.name, s.text) == (upid, "OS\\User Comment", "X Axis Left")


def test_example_file():
    pvl = load_pvl(EXAMPLE)
    assert write_pvl(pvl) == EXAMPLE.read_text("latin-1")
    assert not pvl.curves and not pvl.command_table
    os_layer, mc = pvl.layer(1), pvl.layer(2)
    assert {s.upid: s.text for s in os_layer.strings()} == {0x7070: "LinMot-ST B1100", 0x7078: "Y Axis Right"}
    assert os_layer.strings()[1].stringlets[0].upid == 0x7078               # stringlet 1 at UPID + 0
    # mixed ranges: MC parameters at 6xxxh and Exxxh, outside the E1100's 1000h..1EFFh
    assert {p.upid for p in mc.parameters} >= {0x6198, 0x6300, 0xE19C}
    assert mc.get(0xE19C).value == 3000                                      # the CANopen manual's example (p.33)
    assert os_layer.identity_upids == (0x2CA1, 0x2C96, 0x2C97) and mc.identity_upids == (0x2FA1, 0x2F96, 0x2F97)


def test_example_matches_the_emulated_b1100():
    """Every row is a writable parameter of the emulated B1100's data with a value of its type, and every
    layer's tree is the one that drive has installed, so the file can be commissioned onto it."""
    profile = load_profile(B1100_PROFILE)
    defs = {d.upid: d for d in profile.all_definitions()}
    pvl = load_pvl(EXAMPLE)
    for obj in pvl.parameter_objects:
        lay = profile.layer(obj.layer)
        assert (lay.tree_file, lay.tree_id, lay.main_version, lay.sub_version) == \
               (obj.tree_file_name, obj.tree_id, obj.main_version, obj.sub_version)
        for p in obj.parameters:
            d = defs[p.upid]
            assert d.kind == "par" and d.access == "rw" and d.layer == obj.layer, hex(p.upid)
            assert d.type.lowest <= (p.signed_value if d.type.signed else p.value) <= d.type.highest
            assert p.value != d.default or d.type.name == "STRINGLET", hex(p.upid)


def _b1100(rows, layer=2, tree="MCTREEB1100DSW4_V3S0_b1"):
    return ParameterObject(tree, layer, 4868, 3, 0, "b1", tuple(rows))


def test_mixed_ranges_only_on_the_b1100():
    row = Parameter(0xE19C, 3000, "Motion Control SW\\Motor Configuration\\Max Current", "3 A")
    text = write_pvl(PvlFile((_b1100([row]),)))
    assert parse_pvl(text).layer(2).get(0xE19C).value == 3000
    e1100 = text.replace("MCTREEB1100DSW4_V3S0_b1", "MCTREE1100DSW4_HC_V3S0_b1")
    with pytest.raises(PvlError, match=r"UPID E19Ch is outside the Motion Control SW range 1000h..1EFFh"):
        parse_pvl(e1100)


def test_one_series_per_file():
    text = write_pvl(demo.seed_parameters_file())
    mixed = text.replace("MCTREE1100DSW4_HC_V3S0_b1", "MCTREEB1100DSW4_V3S0_b1")
    with pytest.raises(PvlError) as err:
        parse_pvl(mixed)
    msg = str(err.value)
    assert "is for a B1100" in msg and "for an E1100" in msg and "one file is for one drive series" in msg


def test_no_curves_or_command_table_in_a_b1100_file():
    b1100 = load_pvl(EXAMPLE)
    e1100 = demo.two_axes_file()
    text = write_pvl(PvlFile(b1100.objects + e1100.curves[:1] + e1100.command_table[:1]), check=False)
    with pytest.raises(PvlError) as err:
        parse_pvl(text, "b.pvl")
    msg = str(err.value)
    assert "a curve object in a file for a B1100: the B1100 has no curves" in msg
    assert "a command-table object in a file for a B1100: the B1100 has no command table" in msg
    with pytest.raises(PvlError, match="no curves"):
        write_pvl(PvlFile(b1100.objects + e1100.curves[:1]))


def test_pvl_show(capsys):
    assert main(["pvl", "show", str(EXAMPLE)]) == 0
    out = capsys.readouterr().out
    assert "0 command-table entries, for a B1100" in out
    assert "compatibility: the drive's UPID 2CA1h must read 257, 2C96h 3, 2C97h 0 or more" in out
    assert "compatibility: the drive's UPID 2FA1h must read 4868, 2F96h 3, 2F97h 0 or more" in out
    assert "string 7078h OS\\User Comment = 'Y Axis Right' (stringlets 7078h..707Fh)" in out
    assert "E19Ch  00000BB8h" in out


def test_pvl_to_st(tmp_path):
    out = tmp_path / "b.st"
    assert main(["pvl", "to-st", str(EXAMPLE), "-o", str(out)]) == 0
    text = out.read_text()
    assert "For a B1100 drive" in text
    _, words = read_st(text)
    pvl = load_pvl(EXAMPLE)
    # every row is a parameter record at its 16-bit UPID (02h << 24 | UPID), the stringlets at UPID + 0
    records = {(words[i] & 0xFFFF, words[i + 1]) for i in range(len(words) - 1) if words[i] >> 16 == 0x0200}
    assert records == {(p.upid, p.value) for o in pvl.parameter_objects for p in o.parameters}
    assert (0x7078, 0x78412059) in records
