"""docs/upids.md against the code: every UPID the emulated drive, the harness, st_lib, the user project and the
example PVL files use has one row there with the same meaning, and no INVENTED UPID is one a source names."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from linmot_st.emulator import load_profile
from linmot_st.emulator.cia301 import pdo
from linmot_st.protocol import upids
from linmot_st.pvl import load_pvl
from repo_paths import REPO

DOC = REPO / "docs" / "upids.md"
ROW = re.compile(r"^\|\s*([0-9A-F]{4})h\s*\|(.*)\|\s*$")
PVL_FILES = {"two_axes.pvl": REPO / "examples" / "two_axes.pvl",
             "seed_parameters.pvl": REPO / "examples" / "seed_parameters.pvl",
             "drive.pvl": REPO / "examples" / "user_project" / "drive.pvl"}
# the places ST code names a UPID: an SDO to 2000h+UPID, a Write Interface Parameter (002xh), a Upid input
ST_UPID = re.compile(r"16#2000\s*\+\s*16#([0-9A-F]{4})|F_LmMotionIssue\(16#002,\s*16#([0-9A-F]{4})"
                     r"|Upid\s*:=\s*16#([0-9A-F]{4})")
ST_SOURCES = sorted((REPO / "st_lib").rglob("*.st")) + sorted((REPO / "examples" / "user_project").rglob("*.st"))


def _section(title: str) -> dict[int, list[str]]:
    """The table rows under the `## title` heading: UPID -> the other cells."""
    rows: dict[int, list[str]] = {}
    inside = False
    for line in DOC.read_text().splitlines():
        if line.startswith("## "):
            inside = line[3:].strip() == title
            continue
        m = ROW.match(line) if inside else None
        if m:
            upid = int(m.group(1), 16)
            assert upid not in rows, f"{upid:04X}h has two rows in '{title}'"
            rows[upid] = [c.strip() for c in m.group(2).split("|")]
    assert rows, f"no table under '## {title}'"
    return rows


USED = _section("Every UPID used")              # constant, name (kind), type/unit, used by, source
FREE = _section("Named by a source, not used by the project (kept free)")   # meaning, source


def _constants() -> dict[str, int]:
    names = {k: v for k, v in vars(upids).items() if re.match(r"^[PV]_[A-Z0-9_]+$", k)}
    for k in ("P_TX_MODE", "P_TX_UPIDS", "P_RX1_MODE", "P_RX3_MODE", "P_RX_ON_SYNC", "P_DIRECT_PAR_UPIDS"):
        names["pdo." + k] = getattr(pdo, k)
    return names


def _values(v) -> set[int]:
    if isinstance(v, tuple):
        return set().union(*(_values(x) for x in v))
    return set() if v is None else {v}


def _invented(upid: int) -> bool:
    return USED[upid][4].startswith("INVENTED")


def test_every_upid_has_one_row_and_a_source_or_invented():
    assert not set(USED) & set(FREE), "a UPID both used and listed as free"
    for upid, cells in USED.items():
        source = cells[4]
        assert source.startswith("INVENTED") or "[" in source or "/" in source, f"{upid:04X}h: no source: {source!r}"


def test_no_invented_upid_is_one_a_source_names():
    sourced = {u for u in USED if not _invented(u)} | set(FREE)
    assert not {u for u in USED if _invented(u)} & sourced
    # the collisions issue 20 names stay recorded as the sources' UPIDs, so the check above has teeth
    assert {0x1010} <= set(FREE)
    assert {0x1393, 0x13A6, 0x1710, 0x13C7, 0x146E, 0x146F, 0x1473, 0x1475, 0x14BE, 0x14BF, 0x14C0, 0x6300} <= sourced


def test_every_constant_has_its_row():
    consts = _constants()
    assert len(consts) > 40
    for name, value in consts.items():
        for upid in _values(value):
            assert upid in USED, f"{name} = {upid:04X}h is not in docs/upids.md"
            assert f"`{name}`" in USED[upid][0], f"{upid:04X}h: the row does not name {name}"
    for upid, cells in USED.items():                       # and no row names a constant with another value
        for name in re.findall(r"`([^`]+)`", cells[0]):
            assert upid in _values(consts[name]), f"{upid:04X}h: row names {name} = {consts[name]}"


def test_the_drive_profile_matches_the_table():
    defs = [d for d in load_profile().all_definitions() if d.type.name != "STRINGLET"]
    assert {d.upid for d in defs} == set(USED)
    for d in defs:
        name = d.name.split("\\", 1)[1]
        assert USED[d.upid][1].startswith(f"{name} ({d.kind}"), f"{d.upid:04X}h: {USED[d.upid][1]!r} vs {name!r}"
        assert USED[d.upid][2].split(",")[0] == d.type.name, f"{d.upid:04X}h: type"


def _st_literals() -> dict[Path, set[int]]:
    found: dict[Path, set[int]] = {}
    for path in ST_SOURCES:
        for m in ST_UPID.finditer(path.read_text()):
            found.setdefault(path, set()).add(int(next(g for g in m.groups() if g), 16))
    return found


def test_st_upid_literals_are_in_the_table_with_their_file():
    found = _st_literals()
    for path, values in found.items():
        rel = path.relative_to(REPO).as_posix()
        for upid in values:
            assert upid in USED and f"`{rel}`" in USED[upid][3], f"{rel}: {upid:04X}h not listed as used there"
    for upid, cells in USED.items():                       # the reverse: a file a row names uses the UPID
        for rel in re.findall(r"`([^`]+\.st)`", cells[3]):
            assert upid in found.get(REPO / rel, set()), f"{upid:04X}h: {rel} does not use it"


def test_st_literals_mean_what_the_python_constants_mean():
    found = _st_literals()
    assert found[REPO / "st_lib/motion/move.st"] == {upids.P_PREDEF_VMAX, upids.P_PREDEF_ACC, upids.P_PREDEF_DEC}
    assert found[REPO / "st_lib/motion/pdo.st"] == {upids.P_SCALE_POS, upids.P_SCALE_VEL, upids.P_SCALE_ACC}
    assert found[REPO / "examples/user_project/src/station.st"] == {upids.P_LIMIT_NEGATIVE, upids.P_LIMIT_POSITIVE}


@pytest.mark.parametrize("name", sorted(PVL_FILES))
def test_pvl_parameters_are_in_the_table(name):
    pvl = load_pvl(PVL_FILES[name])
    strings = {u for u, c in USED.items() if "(string)" in c[1]}
    rows = [p for obj in pvl.parameter_objects for p in obj.parameters]
    assert rows
    for p in rows:
        if any(s < p.upid <= s + 8 for s in strings):       # a stringlet of a string parameter
            continue
        assert p.upid in USED, f"{name}: {p.upid:04X}h"
        caption = p.caption.split("\\", 1)[1]
        assert USED[p.upid][1].startswith(f"{caption} ("), f"{name}: {p.upid:04X}h {caption!r}"
        listed = "two_axes.pvl" if name == "drive.pvl" else name   # the user project's drive.pvl is a copy
        assert listed in USED[p.upid][3], f"{p.upid:04X}h: {name} not in 'used by'"
