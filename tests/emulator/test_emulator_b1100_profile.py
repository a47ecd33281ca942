"""The emulated B1100's parameter data (emulator/data/b1100_default.json, b1100_parameters.csv) and the loader's
support for a drive that stores no defaults, limits or access rights and mixes its layers' UPIDs (seed 000 2.4,
2.5, 3). The drive model itself comes with the drive-model seam."""

from __future__ import annotations

import csv
import json
import shutil

import pytest

from linmot_st.emulator.linmot.profile import B1100_PROFILE, DATA_DIR, ProfileError, load_profile


@pytest.fixture(scope="module")
def b1100():
    return load_profile(B1100_PROFILE)


def test_definitions_flags(b1100):
    d = b1100.definitions
    assert (d.series, d.stringlet_offset, d.upid_max, d.layer_ranges) == ("B1100", 0, 0xFFFF, False)
    assert not (d.stores_defaults or d.stores_limits or d.stores_access_rights)
    e = load_profile().definitions                     # the E1100 keeps its behaviour
    assert (e.series, e.stringlet_offset, e.upid_max, e.layer_ranges) == ("E1100", 1, 0x3FFF, True)
    assert e.stores_defaults and e.stores_limits and e.stores_access_rights


def test_tree_identity_upids_of_table_4(b1100):
    expected = {1: (0x2CA1, 0x2C96, 0x2C97), 2: (0x2FA1, 0x2F96, 0x2F97), 3: (0x2EA1, 0x2E96, 0x2E97),
                4: (0x2DA1, 0x2D96, 0x2D97)}
    defs = {d.upid: d for d in b1100.all_definitions()}
    for lay in b1100.layers:
        assert (lay.tree_id_upid, lay.main_version_upid, lay.sub_version_upid) == expected[lay.number]
        assert "B1100" in lay.tree_file and lay.upid_first is None
        assert defs[lay.tree_id_upid].default == lay.tree_id and defs[lay.tree_id_upid].layer == 1
        assert defs[lay.sub_version_upid].default == lay.sub_version


def test_stringlets_start_at_the_string_upid(b1100):
    defs = {d.upid: d for d in b1100.all_definitions()}
    comment = [defs[0x7078 + i] for i in range(8)]
    assert [d.name for d in comment] == [f"OS\\User Comment_{k}" for k in range(1, 9)]
    assert all(d.type.name == "STRINGLET" and d.kind == "par" for d in comment)
    assert 0x7080 not in defs
    name = [defs[0x7070 + i].default for i in range(8)]
    assert b"".join(v.to_bytes(4, "little") for v in name).rstrip(b"\0").decode() == "LinMot B1100"


def test_mixed_layers_and_sourced_upids(b1100):
    defs = {d.upid: d for d in b1100.all_definitions()}
    # the sourced UPIDs (spec/linmot-b1100.md 1.7) with their layers: OS and MC both in 6xxxh..7xxxh
    assert {u: defs[u].layer for u in (0x6081, 0x6085, 0x7078, 0x6061, 0x6198, 0xE19C, 0xE9E7, 0xF4D9)} == \
           {0x6081: 1, 0x6085: 1, 0x7078: 1, 0x6061: 2, 0x6198: 2, 0xE19C: 2, 0xE9E7: 2, 0xF4D9: 2}
    assert defs[0x6081].default == 63                     # default MACID 63 (CANopen manual p.10, p.37)
    assert defs[0xE9E7].type.signed                       # -292 comes back sign-extended (p.31)
    for u in (0x6061, 0x6062, 0x6068, 0x6968, 0x6976, 0xE9A4, 0xE9A5, 0xE9E7, 0xF4D9):
        assert defs[u].kind == "var" and defs[u].access == "ro"
    layers = {d.layer for d in b1100.all_definitions() if 0x6000 <= d.upid <= 0x7FFF}
    assert layers == {1, 2}
    assert max(defs) > 0x3FFF                             # beyond what 2000h + UPID could address


def test_no_stored_limits_or_access_rights(b1100):
    for d in b1100.all_definitions():
        if d.kind == "par" and d.type.name != "STRINGLET" and "Parameter Tree Info" not in d.name:
            assert (d.min, d.max) == (d.type.lowest, d.type.highest), d.name
            assert d.access == "rw" and d.live, d.name


def test_every_row_names_its_source_and_e1100_row():
    path = DATA_DIR / "b1100_parameters.csv"
    rows = list(csv.DictReader(line for line in path.open() if not line.startswith("#")))
    e1100 = {d.upid for d in load_profile().all_definitions()}
    for r in rows:
        assert r["source"], r
        if r["e1100_upid"]:
            assert int(r["e1100_upid"], 16) in e1100, r
        if r["source"].startswith("INVENTED") and r["kind"] != "string" and r["e1100_upid"] \
                and not r["upid"].startswith("846"):
            offset = {"1": 0x8000, "2": 0xC000, "3": 0xA000, "4": 0x8000}[r["layer"]]
            assert int(r["upid"], 16) == int(r["e1100_upid"], 16) + offset, r


def _copy(tmp_path, edit_csv=None, edit_json=None):
    for name in ("b1100_default.json", "b1100_parameters.csv"):
        shutil.copy(DATA_DIR / name, tmp_path / name)
    if edit_csv:
        p = tmp_path / "b1100_parameters.csv"
        p.write_text(edit_csv(p.read_text()))
    if edit_json:
        p = tmp_path / "b1100_default.json"
        spec = json.loads(p.read_text())
        edit_json(spec)
        p.write_text(json.dumps(spec))
    return tmp_path / "b1100_default.json"


def test_loader_refusals(tmp_path):
    with pytest.raises(ProfileError, match="stores no min/max"):
        load_profile(_copy(tmp_path, edit_csv=lambda t: t.replace("upid,kind,type,layer,", "upid,kind,type,layer,min,")
                           .replace("6198,par,UINT16,2,", "6198,par,UINT16,2,0,")))
    with pytest.raises(ProfileError, match="layer 7 is not 1..4"):
        load_profile(_copy(tmp_path, edit_csv=lambda t: t.replace("6198,par,UINT16,2,", "6198,par,UINT16,7,")))
    with pytest.raises(ProfileError, match="unknown definitions key"):
        load_profile(_copy(tmp_path, edit_json=lambda s: s["definitions"].update(stores_curves=False)))
    with pytest.raises(ProfileError, match="defined twice"):
        load_profile(_copy(tmp_path, edit_csv=lambda t: t + "7079,par,UINT16,1,0,,,INVENTED,Clash\n"))

    def e1100_ranges(spec):
        spec["definitions"]["upid_max"] = "3FFF"
    with pytest.raises(ProfileError, match="outside 0000h..3FFFh"):
        load_profile(_copy(tmp_path, edit_json=e1100_ranges))
