"""Users' iec2c differ in what FOR means (spec/matiec.md 7.1): the probe that measures it, the warnings
for a program's FOR loops under each variant, and what `linmot-st build --backend matiec` says."""

from __future__ import annotations

from pathlib import Path

import pytest

from linmot_st.cli import main
from linmot_st.plc import Plc
from linmot_st.toolchain import build
from linmot_st.toolchain.matiec import for_semantics
from linmot_st.toolchain.matiec.for_loops import warnings
from linmot_st.toolchain.matiec.for_semantics import ForSemantics
from linmot_st.toolchain.testing import requires_matiec, write_st

HEAD = ForSemantics(once=False, past_end=False, spins=False, spins_by=True)
OPENPLC = ForSemantics(once=True, past_end=True, spins=True, spins_by=True)
FIXED = ForSemantics(once=True, past_end=True, spins=False, spins_by=False)

LOOPS = """
PROGRAM p_loops
  VAR i, j, n, e : INT; u : USINT; d : DINT; END_VAR
  FOR i := 5 TO 5 DO n := n + 1; END_FOR;
  FOR j := 1 TO e DO n := n + j; END_FOR;
  n := n + i;
  FOR u := 250 TO 255 DO n := n + 1; END_FOR;
  FOR d := 1 TO 2147483647 BY 1000 DO n := n + 1; END_FOR;
  FOR d := 1 TO 10 BY 2 DO n := n + 1; END_FOR;
END_PROGRAM
"""


def test_variant_names():
    assert (HEAD.name, OPENPLC.name, FIXED.name) == ("head", "openplc", "fixed")
    assert ForSemantics(once=True, past_end=False, spins=False, spins_by=False).name == "other"
    assert FIXED.iec and not HEAD.iec and not OPENPLC.iec
    assert "zero times" in HEAD.describe() and "never ends" in OPENPLC.describe()


def _warnings(tmp_path: Path, sem: ForSemantics) -> dict[int, list[str]]:
    path = write_st(LOOPS, tmp_path)
    by_line: dict[int, list[str]] = {}
    for w in warnings([path], tmp_path, [], sem):
        file, line, _col, rest = w.split(":", 3)
        assert file == "prog.st" and rest.startswith(" warning: FOR ")
        by_line.setdefault(int(line), []).append(rest)
    return by_line


def test_head_warnings(tmp_path):
    w = _warnings(tmp_path, HEAD)
    assert sorted(w) == [3, 4, 7]
    assert "runs exactly once" in w[3][0] and "read outside the loop" in w[3][1]   # i is read at line 5
    assert "can run exactly once" in w[4][0]                                       # e may be 1
    assert "steps past the limit of DINT" in w[7][0]       # BY on a DINT: HEAD's test overflows
    # line 6 (USINT up to 255, no BY) ends under HEAD; line 8 runs 5 times and ends


def test_openplc_warnings(tmp_path):
    w = _warnings(tmp_path, OPENPLC)
    assert sorted(w) == [4, 6, 7]
    assert "can step past the limit of INT" in w[4][0]    # e may be 32767
    assert "steps past the limit of USINT" in w[6][0]
    assert "steps past the limit of DINT" in w[7][0]


def test_fixed_has_no_warnings(tmp_path):
    assert _warnings(tmp_path, FIXED) == {}


@requires_matiec
def test_probe_agrees_with_a_run_and_is_cached(tmp_path, monkeypatch):
    monkeypatch.setattr(for_semantics, "_memo", {})      # measured here, not remembered from another test
    sem = for_semantics.probe(tmp_path)
    assert sem.name in ("head", "openplc", "fixed", "other")
    prog = write_st("""
        PROGRAM p_once
          VAR i, n : INT; END_VAR
          n := 0;
          FOR i := 5 TO 5 DO n := n + 1; END_FOR;
        END_PROGRAM
        CONFIGURATION c RESOURCE r ON PLC TASK t(INTERVAL := T#10ms, PRIORITY := 0);
          PROGRAM main WITH t : p_once; END_RESOURCE END_CONFIGURATION
        """, tmp_path / "once")
    plc = Plc(build(prog, backend="matiec", cache_dir=tmp_path / "cache"))
    plc.step(1)
    assert (plc["MAIN.N"] == 1) == sem.once and (plc["MAIN.I"] == 6) == sem.past_end
    # a new process reads the record beside the cache: nothing is built or run again
    assert list((tmp_path / "for-probe").glob("*.json"))
    monkeypatch.setattr(for_semantics, "_memo", {})
    monkeypatch.setattr(for_semantics, "_measure", lambda *a: pytest.fail("measured again"))
    assert for_semantics.probe(tmp_path) == sem


@requires_matiec
def test_build_says_which_variant_and_warns(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("LINMOT_ST_CACHE", str(tmp_path / "cache"))
    prog = write_st(LOOPS + """
        CONFIGURATION c RESOURCE r ON PLC TASK t(INTERVAL := T#10ms, PRIORITY := 0);
          PROGRAM main WITH t : p_loops; END_RESOURCE END_CONFIGURATION
        """, tmp_path / "proj")
    assert main(["build", str(prog), "--backend", "matiec"]) == 0
    captured = capsys.readouterr()
    sem = for_semantics.probe(tmp_path / "cache")
    assert f"FOR semantics of this iec2c: {sem.name}" in captured.out
    expected = warnings([prog], prog.parent, [], sem)
    for line in expected:
        assert line in captured.err
    assert bool(expected) == (not sem.iec)


def test_builtin_build_says_nothing_about_for(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("LINMOT_ST_CACHE", str(tmp_path / "cache"))
    prog = write_st(LOOPS + """
        CONFIGURATION c RESOURCE r ON PLC TASK t(INTERVAL := T#10ms, PRIORITY := 0);
          PROGRAM main WITH t : p_loops; END_RESOURCE END_CONFIGURATION
        """, tmp_path / "proj")
    assert main(["build", str(prog), "--backend", "builtin"]) == 0
    captured = capsys.readouterr()
    assert "FOR semantics" not in captured.out and "warning: FOR" not in captured.err
