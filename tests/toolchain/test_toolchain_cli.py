"""`linmot-st build` and `linmot-st run` (and `linmot-st bench`'s table helpers)."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from linmot_st.cli import main
from linmot_st.toolchain.testing import BACKEND_PARAMS, write_st
from linmot_st_bench.runner import verdict

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
    assert "integer division by zero or overflow (MIN / -1) in POU MAIN" in captured.err


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_bad_watch_and_compile_error(project, backend, capsys, tmp_path):
    assert main(["run", str(project), "--backend", backend, "--cycles", "1", "--watch", "INST0.NOPE"]) == 2
    assert "NOPE" in capsys.readouterr().err
    bad = write_st("PROGRAM Main\nVAR X : INT; END_VAR\nX := ;\nEND_PROGRAM\n", tmp_path / "bad")
    assert main(["build", str(bad), "--backend", backend]) == 1
    assert "prog.st:3:" in capsys.readouterr().err


def test_auto_says_which_backend(project, capsys):
    from linmot_st.toolchain import choose_backend
    chosen = choose_backend("auto")
    assert main(["build", str(project)]) == 0
    captured = capsys.readouterr()
    assert f"backend: {chosen} (auto: iec2c {'found' if chosen == 'matiec' else 'not found'})" in captured.err
    assert f"compiled with {chosen}" in captured.out or f"cached with {chosen}" in captured.out


def test_console_script_help():
    proc = subprocess.run([sys.executable, "-m", "linmot_st.cli", "run", "--help"], capture_output=True, text=True)
    assert proc.returncode == 0 and "--cycles" in proc.stdout and "--watch" in proc.stdout


def _installed_script() -> str:
    """The `linmot-st` console script of the environment running the tests (pip installs it beside python)."""
    beside = Path(sys.executable).parent / "linmot-st"
    found = str(beside) if beside.is_file() else shutil.which("linmot-st")
    if not found:
        pytest.skip("no installed linmot-st script (the package is not pip-installed here)")
    return found


def test_installed_console_script_builds_and_runs(project, tmp_path):
    script = _installed_script()
    env = dict(os.environ, LINMOT_ST_CACHE=str(tmp_path / "cache"))
    proc = subprocess.run([script, "run", str(project), "--backend", "builtin", "--cycles", "3", "--watch", "INST0.N"],
                          capture_output=True, text=True, env=env)
    assert proc.returncode == 0, proc.stderr
    assert "CONFIG0.RES0.INST0.N = 3" in proc.stdout


def test_a_bad_path_exits_2_with_a_plain_message(tmp_path, capsys):
    missing = tmp_path / "nonexistent.st"
    assert main(["build", str(missing), "--backend", "builtin"]) == 2
    err = capsys.readouterr().err
    assert f"error: {missing}: no such file or folder" in err
    assert ":1:1:" not in err                 # no made-up source position
    assert main(["run", str(tmp_path), "--backend", "builtin", "--cycles", "1"]) == 2
    assert "needs an entry file plc.st" in capsys.readouterr().err
    proc = subprocess.run([_installed_script(), "build", str(missing), "--backend", "builtin"],
                          capture_output=True, text=True)
    assert proc.returncode == 2 and "Traceback" not in proc.stderr


def test_internal_compiler_error_is_reported_not_raised(project, monkeypatch, capsys, tmp_path):
    """An unexpected exception inside a backend is a clear message naming the file; the traceback is shown
    with --verbose (or LINMOT_ST_TRACEBACK=1)."""
    from linmot_st.toolchain import builtin

    def broken(*args, **kwargs):
        raise ZeroDivisionError("a bug in the compiler")

    monkeypatch.setattr(builtin, "compile_to_c", broken)
    monkeypatch.delenv("LINMOT_ST_TRACEBACK", raising=False)
    assert main(["build", str(project), "--backend", "builtin", "--no-cache"]) == 1
    err = capsys.readouterr().err
    assert "plc.st: error: internal compiler error of the builtin backend: ZeroDivisionError: a bug in the compiler" in err
    assert "--verbose" in err and "Traceback" not in err
    assert main(["build", str(project), "--backend", "builtin", "--no-cache", "--verbose"]) == 1
    err = capsys.readouterr().err
    assert "Traceback (most recent call last)" in err and "in broken" in err
    monkeypatch.setenv("LINMOT_ST_TRACEBACK", "1")
    assert main(["run", str(project), "--backend", "builtin", "--cycles", "1"]) == 1
    assert "Traceback (most recent call last)" in capsys.readouterr().err


def test_bench_verdicts():
    assert verdict(2_000_000, ">= 1000000") == "ok"
    assert verdict(6.0, "<= 5") == "MISS"
    assert verdict(1, None) == ""
    assert verdict("failed: commissioned 14 of 16", ">= 50") == "MISS"     # a run that failed misses its target


def test_missing_c_compiler_and_unwritable_cache_are_plain_errors(project, monkeypatch, capsys, tmp_path):
    from linmot_st.toolchain import cc
    cc.find_compiler.cache_clear()
    monkeypatch.setenv("CC", "no-such-c-compiler")
    try:
        assert main(["build", str(project), "--backend", "builtin", "--no-cache"]) == 1
        err = capsys.readouterr().err
        assert "error: no C compiler: 'no-such-c-compiler' is not on PATH" in err and "Traceback" not in err
    finally:
        monkeypatch.delenv("CC")
        cc.find_compiler.cache_clear()
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("")
    monkeypatch.setenv("LINMOT_ST_CACHE", str(blocker / "cache"))
    assert main(["build", str(project), "--backend", "builtin"]) == 1
    err = capsys.readouterr().err
    assert err.count("error: ") == 1 and "not-a-folder" in err and "Traceback" not in err
