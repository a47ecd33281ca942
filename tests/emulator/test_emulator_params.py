"""The parameter store and the drive profile: data file loading, types, masking, access rules, strings,
firmware layers, set-to-default, UPID lists, derived drives."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from linmot_st.emulator import E1100Drive, ProfileError, load_profile
from linmot_st.emulator.linmot.params import NotWritable, NoValueAccess, OutOfRange, ParameterStore, UnknownUpid
from linmot_st.emulator.linmot.paramtypes import TYPES, stringlets_of, text_of
from linmot_st.emulator.linmot.profile import (
    AU_LIVE,
    AU_RAM_READ,
    AU_RAM_WRITE,
    AU_ROM_READ,
    AU_ROM_WRITE,
    load_parameters,
)

PROFILE = load_profile()


def store() -> ParameterStore:
    return ParameterStore(PROFILE.all_definitions())


def test_default_profile_is_the_seeds_example():
    layers = {lay.number: lay for lay in PROFILE.layers}
    assert (layers[1].tree_file, layers[1].tree_id, layers[1].main_version, layers[1].sub_version) == \
        ("OSTREE1100OS__V3S0_b1", 1, 3, 0)
    assert (layers[2].tree_file, layers[2].tree_id, layers[2].main_version, layers[2].sub_version) == \
        ("MCTREE1100DSW4_HC_V3S0_b1", 4612, 3, 0)
    # UPID ranges and tree-info UPIDs of seeds tables 3 and 4
    assert [(lay.upid_first, lay.upid_last) for lay in PROFILE.layers] == \
        [(0x0000, 0x0EFF), (0x1000, 0x1EFF), (0x2000, 0x2EFF), (0x3000, 0x3EFF)]
    assert [(lay.tree_id_upid, lay.main_version_upid, lay.sub_version_upid) for lay in PROFILE.layers] == \
        [(0x0539, 0x0532, 0x0533), (0x0561, 0x055A, 0x055B), (0x0589, 0x0582, 0x0583), (0x05B1, 0x05AA, 0x05AB)]
    s = store()
    assert s.read(0x0561, "ram") == 4612 and s.read(0x055A, "rom") == 3 and s.read(0x055B, "ram") == 0
    assert s[0x1194].name.endswith("Motor Type") and s[0x1194].layer == 2
    mc_params = [p for p in s if p.layer == 2 and p.kind == "par"]
    assert len(mc_params) >= 30          # "a few dozen" MC parameters
    assert PROFILE.identity.vendor_id == 0x156


def test_strings_of_the_pvl_example_exist_with_their_stringlets():
    s = store()
    for string, first in ((0x03E8, 0x03E9), (0x03F2, 0x03F3)):
        assert s[string].kind == "string" and s[string].address_usage == 0
        for k in range(8):
            p = s[first + k]
            assert p.type.name == "STRINGLET" and p.access == "rw"
        assert first + 8 not in s


def test_seeds_string_example():
    # 'X Axis Left' (the seeds' prose writes 'X-Axis Left', but its table encodes a space: 58h 20h 41h 78h)
    assert stringlets_of("X Axis Left", 3) == [0x78412058, 0x4C207369, 0x00746665]
    assert text_of([0x78412058, 0x4C207369, 0x00746665]) == "X Axis Left"
    s = store()
    s.set_string(0x03F2, "X Axis Left", "rom")
    assert [s[u].rom for u in (0x03F3, 0x03F4, 0x03F5, 0x03F6)] == [0x78412058, 0x4C207369, 0x00746665, 0]
    assert s.string(0x03F2, "rom") == "X Axis Left" and s.string(0x03F2, "ram") == ""


@given(st.integers(0, 0xFFFFFFFF))
def test_every_type_masks_and_sign_extends(raw):
    for t in TYPES.values():
        if t.bits == 0:
            continue
        v = t.from_raw(raw)
        assert t.lowest <= v <= t.highest
        assert t.to_raw(v) & t.mask == raw & t.mask            # the bits the drive keeps
        if t.signed:
            assert t.to_raw(v) >> (t.bits - 1) in (0, (1 << (33 - t.bits)) - 1)   # sign-extended to 32 bits


def test_access_rules():
    s = store()
    s.write(0x13A2, 123, ram=True, rom=False)            # live: RAM write allowed
    assert (s[0x13A2].ram, s[0x13A2].rom) == (123, 9)
    s.write(0x1194, 2, ram=False, rom=True)              # non-live: ROM write allowed while running
    assert (s[0x1194].ram, s[0x1194].rom) == (0, 2)
    with pytest.raises(NotWritable):
        s.write(0x1194, 3, ram=True, rom=False)          # non-live RAM: refused
    with pytest.raises(NotWritable):
        s.write(0x1194, 3, ram=True, rom=True)           # 06h: refused as a whole, nothing written
    assert s[0x1194].rom == 2
    with pytest.raises(NotWritable):
        s.write(0x0539, 2, ram=False, rom=True)          # tree ID read only
    with pytest.raises(NotWritable):
        s.write(0x1D51, 1, ram=True, rom=False)          # variable
    with pytest.raises(OutOfRange):
        s.write(0x1005, 99, ram=True, rom=False)         # min 100
    with pytest.raises(NoValueAccess):
        s.read(0x03E8, "ram")
    with pytest.raises(NoValueAccess):
        s.read(0x1D51, "rom")
    with pytest.raises(UnknownUpid):
        s.read(0x1001, "ram")


def test_address_usage_words():
    s = store()
    assert s[0x13A2].address_usage == AU_RAM_READ | AU_RAM_WRITE | AU_ROM_READ | AU_ROM_WRITE | AU_LIVE == 0x010F
    assert s[0x1004].address_usage == 0x000D          # [CO1100] example: first UPID >= 1000h, AU 000Dh
    assert s[0x2008].address_usage == 0x000D          # LinRS example
    assert s[0x2136].address_usage == 0x1001          # LinRS example (variable)
    assert s[0x0539].address_usage == 0x0005


def test_types_the_sources_give():
    # LinRS "get next UPID": UPID 2008h, AU 000Dh, type 000Ah (RADIO_DIR_BIT); LinRS "get parameter type" of
    # 13A2h: 03h (UINT16)
    s = store()
    assert (s[0x2008].type.name, s[0x2008].type.code) == ("RADIO_DIR_BIT", 0x0A)
    assert (s[0x13A2].type.name, s[0x13A2].type.code) == ("UINT16", 0x03)
    assert {t.code for t in TYPES.values()} >= {0x00, 0x01, 0x02, 0x03, 0x04, 0x05, 0x06, 0x08, 0x0A, 0x0B, 0x0C,
                                                 0x0D, 0x0E}


def test_set_layer_default_touches_only_that_layer_rom():
    s = store()
    s.write(0x13A2, 50, ram=True, rom=True)
    s.write(0x0420, 1, ram=False, rom=True)
    assert s.set_layer_default(2) >= 1
    assert (s[0x13A2].rom, s[0x13A2].ram) == (9, 50)     # RAM unchanged until the firmware starts again
    assert s[0x0420].rom == 1                            # OS layer untouched
    assert s[0x0561].rom == 4612                          # read-only tree info untouched


def test_upid_list_walk_and_modified_list():
    s = store()
    upids = []
    p = s.next_entry(0)
    while p is not None:
        upids.append(p.upid)
        p = s.next_entry(p.upid + 1)
    assert upids == sorted(upids) == s.upids()
    assert s.next_entry(0x1000).upid == 0x1004
    assert s.next_entry(0, modified_only=True) is None
    s.write(0x03F3, 0x78412058, ram=False, rom=True)
    s.write(0x146E, -100000 & 0xFFFFFFFF, ram=False, rom=True)
    assert [s.next_entry(0, True).upid, s.next_entry(0x0400, True).upid] == [0x03F3, 0x146E]


def test_with_tree_and_with_defaults_make_other_drives():
    other = PROFILE.with_tree(2, tree_id=4613, sub_version=1)
    d = E1100Drive(1, other)
    assert d.params.read(0x0561, "ram") == 4613 and d.params.read(0x055B, "ram") == 1
    assert d.params.read(0x055A, "ram") == 3
    assert E1100Drive(1).params.read(0x0561, "ram") == 4612     # the default profile is unchanged
    d2 = E1100Drive(1, PROFILE.with_defaults({0x1194: 2, 0x03F2: "Axis"}))
    assert d2.params[0x1194].default == 2 and d2.string(0x03F2, "rom") == "Axis"
    with pytest.raises(ProfileError):
        PROFILE.with_defaults({0x1194: 0x8000})
    with pytest.raises(ProfileError):
        PROFILE.with_tree(5, tree_id=1)


@pytest.mark.parametrize("row, message", [
    ("zz12,par,UINT16,1,rw,0,,,,X", "upid"),
    ("1100,par,UINT17,1,rw,0,,,,X", "unknown type"),
    ("1100,par,UINT16,1,rw,70000,,,,X", "does not fit"),
    ("1100,par,UINT16,1,rw,5,10,20,,X", "outside min"),
    ("1100,foo,UINT16,1,rw,5,,,,X", "kind"),
    ("1100,par,UINT16,1,wr,5,,,,X", "access"),
    ("1100,string,STRING,1,rw,this text is far too long for it,,,2,X", "longer"),
])
def test_parameter_file_errors_name_the_line(tmp_path, row, message):
    path = tmp_path / "p.csv"
    path.write_text("# comment\nupid,kind,type,live,access,default,min,max,stringlets,name\n" + row + "\n")
    with pytest.raises(ProfileError, match=message) as exc:
        load_parameters(path, PROFILE.layer_of)
    assert "p.csv:3" in str(exc.value)


def test_duplicate_upid_is_refused():
    from linmot_st.emulator.linmot.profile import ParamDef
    dup = ParamDef(0x03E9, "clash", "par", TYPES["UINT16"], 0, 0, 1, False, "rw", 1)  # a stringlet of 03E8h
    with pytest.raises(ProfileError, match="defined twice"):
        PROFILE.with_parameters([dup]).all_definitions()
