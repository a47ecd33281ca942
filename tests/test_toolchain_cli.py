"""`linmot-st build` and `linmot-st run` (and `linmot-st bench`'s table helpers)."""

from __future__ import annotations

import subprocess
import sys

import pytest

from linmot_st.bench import verdict
from linmot_st.cli import main
from linmot_st.toolchain.testing import BACKEND_PARAMS, write_st

PROGRAM = """
TYPE
  T_Pair : ARRAY[1..2] OF INT;
END_TYPE

PROGRAM Main
  VAR
    Gain : INT := 2;
    N : INT;
    Out : T_Pair;
    Fault : BOOL;
    Zero : INT;
  END_VAR
  N := N + 1;
  Out[1] := N * Gain;
  IF Fault THEN
    N := N / Zero;
  END_IF;
END_PROGRAM

CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK T1(INTERVAL := T#10ms, PRIORITY := 0);
    PROGRAM Inst0 WITH T1 : Main;
  END_RESOURCE
END_CONFIGURATION
"""


@pytest.fixture
def project(tmp_path, monkeypatch):
    monkeypatch.setenv("LINMOT_ST_CACHE", str(tmp_path / "cache"))
    return write_st(PROGRAM, tmp_path / "proj", "plc.st").parent


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_build_then_cached(project, backend, capsys, tmp_path):
    assert main(["build", str(project), "--backend", backend, "--out", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    assert f"compiled with {backend}" in out and "libplc.so" in out
    assert (tmp_path / "out" / "manifest.json").is_file()
    assert main(["build", str(project / "plc.st"), "--backend", backend]) == 0
    assert f"cached with {backend}" in capsys.readouterr().out


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_run_prints_watched_variables(project, backend, capsys):
    code = main(["run", str(project), "--backend", backend, "--cycles", "25", "--set", "INST0.GAIN=3",
                 "--watch", "INST0.N", "INST0.OUT"])
    out = capsys.readouterr().out
    assert code == 0
    assert "scan 25  t = 250 ms" in out
    assert "CONFIG0.RES0.INST0.N = 25" in out
    assert "CONFIG0.RES0.INST0.OUT = [75, 0]" in out


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_run_every_and_fault(project, backend, capsys):
    assert main(["run", str(project), "--backend", backend, "--cycles", "4", "--every", "2",
                 "--watch", "INST0.N"]) == 0
    out = capsys.readouterr().out
    assert out.count("INST0.N = ") == 2 and "N = 2" in out and "N = 4" in out
    assert main(["run", str(project), "--backend", backend, "--cycles", "4", "--set", "INST0.FAULT=True",
                 "--watch", "INST0.N"]) == 3
    captured = capsys.readouterr()
    assert "division by zero in POU MAIN" in captured.err


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_bad_watch_and_compile_error(project, backend, capsys, tmp_path):
    assert main(["run", str(project), "--backend", backend, "--cycles", "1", "--watch", "INST0.NOPE"]) == 2
    assert "NOPE" in capsys.readouterr().err
    bad = write_st("PROGRAM Main\nVAR X : INT; END_VAR\nX := ;\nEND_PROGRAM\n", tmp_path / "bad")
    assert main(["build", str(bad), "--backend", backend]) == 1
    assert "prog.st:3:" in capsys.readouterr().err


def test_auto_says_which_backend(project, capsys):
    main(["build", str(project)])
    assert "backend: " in capsys.readouterr().err


def test_console_script_help():
    proc = subprocess.run([sys.executable, "-m", "linmot_st.cli", "run", "--help"], capture_output=True, text=True)
    assert proc.returncode == 0 and "--cycles" in proc.stdout and "--watch" in proc.stdout


def test_bench_verdicts():
    assert verdict(2_000_000, ">= 1000000") == "ok"
    assert verdict(6.0, "<= 5") == "MISS"
    assert verdict(1, None) == ""
