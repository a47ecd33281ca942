"""linmot-st as a user gets it: a wheel built from the sources, installed into a fresh venv, every command
run there from an empty folder, and a project made by `linmot-st init` tested with its own pytest.

Slow (about 40 s: the wheel build, pip installing the dependencies from its cache or PyPI, then the
commands); it needs pip >= 22.3 in the test environment (`pip --python`) and the package registry.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from linmot_st import resources

REPO = resources.CHECKOUT
pytestmark = [pytest.mark.slow]

HELP_ALL = """
import argparse, contextlib, io
from linmot_st.cli import build_parser
sub = next(a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction))
for name in sub.choices:
    if name == "bench":
        continue
    with contextlib.redirect_stdout(io.StringIO()) as text:
        try:
            build_parser().parse_args([name, "--help"])
        except SystemExit as exc:
            assert exc.code == 0 and "usage:" in text.getvalue(), name
    print(name)
"""


def _run(argv, cwd, env, timeout=600, check=True):
    proc = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
    if check and proc.returncode != 0:
        raise AssertionError(f"{' '.join(map(str, argv))} exited {proc.returncode}\n{proc.stdout}\n{proc.stderr}")
    return proc


def _source_copy(target: Path) -> Path:
    """The files git would commit (tracked and new, not ignored), as a fresh clone would have them."""
    listed = subprocess.run(["git", "ls-files", "--cached", "--others", "--exclude-standard", "-z"], cwd=REPO,
                            capture_output=True, check=True).stdout.decode().split("\0")
    for rel in filter(None, listed):
        src = REPO / rel
        if src.is_file():
            (target / rel).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(src, target / rel)
    return target


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """(venv bin folder, environment) of a fresh venv with the wheel installed."""
    if shutil.which("git") is None or not (REPO / ".git").exists():
        pytest.skip("needs a git checkout of linmot-st (the wheel is built from the files git tracks)")
    base = tmp_path_factory.mktemp("wheel")
    src = _source_copy(base / "src")
    env = {k: v for k, v in os.environ.items() if k not in ("IEC2C", "MATIEC_HOME", "LINMOT_ST_CACHE", "PYTHONPATH")}
    env["XDG_CACHE_HOME"] = str(base / "xdg")                      # the builds of this test only
    env["PIP_CACHE_DIR"] = os.environ.get("PIP_CACHE_DIR", str(Path.home() / ".cache" / "pip"))
    _run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", str(base / "dist"), str(src)], base, env)
    wheel = next((base / "dist").glob("linmot_st-*.whl"))
    _run([sys.executable, "-m", "venv", "--without-pip", str(base / "venv")], base, env)
    _run([sys.executable, "-m", "pip", "--python", str(base / "venv" / "bin" / "python"), "install", "-q",
          str(wheel)], base, env)
    env["PATH"] = f"{base / 'venv' / 'bin'}{os.pathsep}{env.get('PATH', '')}"
    return base / "venv" / "bin", env, wheel


def test_the_wheel_carries_the_library_the_project_and_the_template(installed):
    names = set(zipfile.ZipFile(installed[2]).namelist())
    for tree in ("st_lib", "plc_project", "examples/user_project"):
        for f in (REPO / tree).rglob("*"):
            if f.is_file() and "__pycache__" not in f.parts and ".pytest_cache" not in f.parts:
                assert f"linmot_st/{f.relative_to(REPO).as_posix()}" in names, f
    assert "linmot_st/plctest/plugin.py" in names
    # the benches and the SocketCAN test environment are development code: not in the wheel (issue 26)
    dev = sorted(n for n in names if n.endswith(".py") and (n.split("/")[0] in ("linmot_st_bench", "linmot_st_vcan")
                                                             or "bench" in n.rsplit("/", 1)[-1] or "/vcan/" in n))
    assert dev == []


def test_every_command_works_from_an_empty_folder(installed, tmp_path):
    bin_, env, _ = installed
    exe = str(bin_ / "linmot-st")
    work = tmp_path / "empty"
    work.mkdir()
    # every subcommand's --help, in one process (bench is the checkout's)
    helped = _run([str(bin_ / "python"), "-c", HELP_ALL], work, env).stdout.split()
    assert {"build", "run", "emulate", "commission", "motion", "export", "init"} <= set(helped), helped

    _run([exe, "export", "st", "lib.st"], work, env)
    assert "FUNCTION_BLOCK FB_LmCommission" in (work / "lib.st").read_text()
    _run([exe, "export", "plcopen", "lib.xml"], work, env)
    assert b"FB_LmCommission" in (work / "lib.xml").read_bytes()

    for pvl in ("two_axes.pvl", "seed_parameters.pvl"):      # the committed dataset, and a generated one
        shutil.copy(REPO / "examples" / pvl, work / pvl)
        out = _run([exe, "commission", pvl, "--drive-timings", "fast"], work, env).stdout
        assert "result: PASSED" in out, out
    out = _run([exe, "motion", "two_axes.pvl", "--drive-timings", "fast", "--report", "motion"], work, env).stdout
    assert "PASSED" in out, out
    assert (work / "motion" / "motion.md").is_file()

    _run([exe, "emulate", "--interface", "virtual", "--channel", "wheel-test", "--fast", "--duration", "0.2"], work, env)

    site = next((bin_.parent / "lib").glob("python*/site-packages/linmot_st"))
    assert not (site / "build").exists()                     # nothing was written into the installed package
    assert sorted(p.name for p in work.iterdir()) == ["lib.st", "lib.xml", "motion", "seed_parameters.pvl",
                                                      "two_axes.pvl"]


def test_init_build_run_and_pytest_of_a_new_project(installed, tmp_path):
    """`linmot-st init`, then the project builds, runs and passes its own tests with only the package."""
    bin_, env, _ = installed
    exe = str(bin_ / "linmot-st")
    _run([exe, "init", "station"], tmp_path, env)
    station = tmp_path / "station"
    built = _run([exe, "build", "."], station, env)
    assert "compiled with builtin" in built.stdout + built.stderr, built.stdout + built.stderr
    out = _run([exe, "run", ".", "--cycles", "5", "--watch", "MAIN.STATION.STATE"], station, env).stdout
    assert "MAIN.STATION.STATE = 'ST_BOOT'" in out, out
    proc = _run([str(bin_ / "pytest"), "-q", "--junitxml=report.xml"], station, env, check=False)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    tail = proc.stdout.strip().splitlines()[-1]
    assert " passed" in tail and "failed" not in tail, proc.stdout
    report = (station / "report.xml").read_text()
    assert 'name="Test_StationCommissionsThenRunsItsJob"' in report           # the ST tests ran as pytest items
