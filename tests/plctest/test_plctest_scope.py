"""The scope of the pytest plugin: a project of its own run by pytest (pytester, in a subprocess) whose failed
tests name their PNG, VCD and CSV; the VCD read back with pyvcd's reader, the CSV with csv; the marker, the
ini options, a scope on request, an ST test's scope; the emulated drive's signals beside the PLC's."""

from __future__ import annotations

import csv
import io

import pytest
from vcd.reader import TokenKind, tokenize

PLC_ST = """
TYPE E_Phase : (PH_IDLE, PH_RUN, PH_DONE); END_TYPE
PROGRAM Prog
  VAR
    N : INT;
    Q : BOOL;
    S : E_Phase;
    R : REAL;
    D : DINT := -3;
  END_VAR
  N := N + 1;
  Q := NOT Q;
  IF N > 20 THEN S := PH_DONE; ELSIF N > 5 THEN S := PH_RUN; END_IF;
  R := R + 0.5;
END_PROGRAM
CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK Cyclic(INTERVAL := T#1ms, PRIORITY := 0);
    PROGRAM MAIN WITH Cyclic : Prog;
  END_RESOURCE
END_CONFIGURATION
"""

TESTS_PY = """
import pytest

@pytest.mark.scope("MAIN.N", "MAIN.Q", "MAIN.S", "MAIN.R", "MAIN.D", "drive1.nmt", "drive1.position")
def test_fails_at_scan_50(rig):
    rig.step_until("MAIN.N >= 50", scans=100)
    assert rig["MAIN.N"] == 0, "the counter is not zero"

def test_passes_without_a_scope(rig):
    rig.step(5)

def test_a_scope_on_request(rig):
    rig.scope("MAIN.N", every=10, write=True)
    rig.step(30)
"""

TESTS_ST = """
FUNCTION_BLOCK Test_CountsToThree
  VAR_OUTPUT
    Done : BOOL;
  END_VAR
  VAR
    StUnit : T_StUnit;
    Ok : BOOL;
    K : INT;
    Name : STRING;
  END_VAR
  K := K + 1;
  Done := K = 5;
  Ok := AssertTrue(StUnit, K < 4, 'K stays below four');
END_FUNCTION_BLOCK
"""


@pytest.fixture(scope="module")
def project(tmp_path_factory):
    folder = tmp_path_factory.mktemp("scope_project")
    (folder / "pytest.ini").write_text("[pytest]\nlinmot_st_backend = builtin\nlinmot_st_timings = fast\n"
                                       "linmot_st_st_scope = *\n")
    (folder / "plc.st").write_text(PLC_ST)
    (folder / "test_scope.py").write_text(TESTS_PY)
    (folder / "test_counts.st").write_text(TESTS_ST)
    return folder


@pytest.fixture(scope="module")
def run(project):
    import subprocess
    import sys
    proc = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q"], cwd=project,
                          capture_output=True, text=True, timeout=600)
    return proc


def read_vcd(path) -> tuple[dict, dict]:
    """{name: VarDecl} and {name: [(time, value)]} of a VCD file, by pyvcd's tokenizer."""
    decls, changes, scopes, by_id, t = {}, {}, [], {}, 0
    with open(path, "rb") as f:
        for tok in tokenize(f):
            if tok.kind is TokenKind.SCOPE:
                scopes.append(tok.data.ident)
            elif tok.kind is TokenKind.UPSCOPE:
                scopes.pop()
            elif tok.kind is TokenKind.VAR:
                name = ".".join([*scopes, tok.data.reference])
                decls[name], by_id[tok.data.id_code] = tok.data, name
                changes[name] = []
            elif tok.kind is TokenKind.CHANGE_TIME:
                t = tok.data
            elif tok.kind in (TokenKind.CHANGE_SCALAR, TokenKind.CHANGE_VECTOR, TokenKind.CHANGE_REAL,
                              TokenKind.CHANGE_STRING):
                changes[by_id[tok.data.id_code]].append((t, tok.data.value))
    return decls, changes


def test_a_failed_test_names_its_scope_files(project, run):
    out = run.stdout
    assert "2 failed, 2 passed" in out.splitlines()[-1], out
    assert "linmot-st scope" in out
    assert ("scope of MAIN.N, MAIN.Q, MAIN.S, MAIN.R, MAIN.D, drive1.nmt, drive1.position (51 samples, "
            "failed at scan 50, PLC time 50 ms):") in out, out
    for kind in ("png", "vcd", "csv"):
        assert f"{kind.upper()}: build/scope/test_scope.test_fails_at_scan_50.{kind}" in out
    png = (project / "build/scope/test_scope.test_fails_at_scan_50.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000
    assert not list((project / "build/scope").glob("test_scope.test_passes_without_a_scope.*"))


def test_the_vcd_reads_back_with_the_plc_values(project, run):
    decls, changes = read_vcd(project / "build/scope/test_scope.test_fails_at_scan_50.vcd")
    assert {n: (d.type_.value, d.size) for n, d in decls.items()} == {
        "MAIN.N": ("integer", 16), "MAIN.Q": ("wire", 1), "MAIN.S": ("string", 1), "MAIN.R": ("real", 64),
        "MAIN.D": ("integer", 32), "drive1.nmt": ("string", 1), "drive1.position": ("real", 64)}
    assert changes["MAIN.N"] == [(k * 1_000_000, k) for k in range(51)]        # one scan per ms of PLC time
    assert [v for _, v in changes["MAIN.Q"]] == [str(k % 2) for k in range(51)]   # scalar changes: "0", "1"
    assert changes["MAIN.S"] == [(0, "PH_IDLE"), (6_000_000, "PH_RUN"), (21_000_000, "PH_DONE")]
    assert changes["MAIN.D"] == [(0, (-3) & 0xFFFFFFFF)]                       # DINT: its 32-bit pattern
    assert changes["MAIN.R"][-1] == (50_000_000, 25.0)
    # this PLC has no CAN mailbox: the bus is not stepped and the drive stays where power-on left it
    assert changes["drive1.nmt"] == [(0, "BOOTING")] and changes["drive1.position"] == [(0, 0.0)]


def test_the_csv_has_one_row_per_sample(project, run):
    rows = list(csv.reader(io.StringIO((project / "build/scope/test_scope.test_fails_at_scan_50.csv").read_text())))
    assert rows[0] == ["time_ms", "scan", "MAIN.N", "MAIN.Q", "MAIN.S", "MAIN.R", "MAIN.D", "drive1.nmt",
                       "drive1.position [mm]"]
    assert len(rows) == 52 and rows[-1][:3] == ["50.000000", "50", "50"]


def test_a_scope_on_request_is_written_when_the_test_passes(project, run):
    rows = list(csv.reader(io.StringIO((project / "build/scope/test_scope.test_a_scope_on_request.csv").read_text())))
    assert [r[1] for r in rows[1:]] == ["0", "10", "20", "30"]                 # every=10
    assert (project / "build/scope/test_scope.test_a_scope_on_request.png").is_file()


def test_an_st_test_records_its_variables(project, run):
    out = run.stdout
    case = "CONFIG0.RES0.STUNIT.StUnitCase1"
    assert (f"scope of {case}.DONE, {case}.OK, {case}.K (5 samples, failed at scan 4, PLC time 4 ms):\n"
            "  PNG: build/scope/test_counts.Test_CountsToThree.png") in out, out
    decls, changes = read_vcd(project / "build/scope/test_counts.Test_CountsToThree.vcd")
    k = next(n for n in decls if n.endswith(".K"))
    assert [v for _, v in changes[k]] == [0, 1, 2, 3, 4]
    assert not any(n.endswith(".NAME") for n in decls)                          # a STRING is not drawn


def test_the_ini_options_give_every_test_a_scope(pytester):
    pytester.makeini("[pytest]\nlinmot_st_backend = builtin\nlinmot_st_timings = fast\n"
                     "linmot_st_scope = MAIN.N MAIN.S\nlinmot_st_scope_every = 5\nlinmot_st_scope_dir = out\n"
                     "linmot_st_scope_write = always\n")
    pytester.makefile(".st", plc=PLC_ST)
    pytester.makepyfile(test_ini="def test_passes(rig):\n    rig.step(20)\n\n"
                                 "def test_fails(rig):\n    rig.step(7)\n    assert False\n")
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", "-rP")
    result.assert_outcomes(passed=1, failed=1)
    result.stdout.fnmatch_lines(["scope of MAIN.N, MAIN.S (2 samples, failed at scan 7, PLC time 7 ms):",
                                 "  VCD: out/test_ini.test_fails.vcd",
                                 "*PASSES*",                                      # -rP shows a passed one's
                                 "scope of MAIN.N, MAIN.S (5 samples):",
                                 "  PNG: out/test_ini.test_passes.png"])
    _, changes = read_vcd(pytester.path / "out/test_ini.test_passes.vcd")
    assert changes["MAIN.N"] == [(k * 5_000_000, k * 5) for k in range(5)]       # scans 0, 5, ... 20
    assert (pytester.path / "out/test_ini.test_fails.png").read_bytes()[:4] == b"\x89PNG"


def test_the_drive_beside_the_plc_and_a_scope_changes_nothing(station):
    """The station moves its axis to 20 mm, then runs a 100 mm curve: the drive's signals show it. Recording
    every scan (scan-by-scan stepping, the drives brought to each scan's time) leaves the CAN trace as it is."""
    from linmot_st.plctest import Rig
    plain, scoped = Rig(station), Rig(station)
    scope = scoped.scope("MAIN.STATION.STATE", "MAIN.STATION.READY", drives=True)
    for rig in (plain, scoped):
        rig.step_until("MAIN.STATION.READY", ms=90_000)
    assert plain.plc.scan_count == scoped.plc.scan_count
    assert [(e.end_ns, e.sender, str(e.frame)) for e in plain.trace] == \
           [(e.end_ns, e.sender, str(e.frame)) for e in scoped.trace]
    assert [s.name for s in scope.signals] == ["MAIN.STATION.STATE", "MAIN.STATION.READY", "drive1.position",
                                               "drive1.velocity", "drive1.state"]
    assert len(scope.rows) == scoped.plc.scan_count + 1
    position, state = scope.column("drive1.position"), scope.column("drive1.state")
    assert abs(position[-1] - 120) < 0.01 and max(scope.column("drive1.velocity")) > 100       # mm, mm/s
    assert "Operation Enabled" in state and state[0] == "Not Ready To Switch On"
    assert scope.column("MAIN.STATION.STATE")[-1] == "ST_READY"
