"""`make bench`: the cost of ST coverage on the user project's test run (a copy of examples/user_project,
what `linmot-st init` makes): its pytest run without and with --linmot-cov, builds cached (the run a
developer repeats), best of a few runs each, in a folder and build cache of its own."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

RUNS = 3


def _pytest(project: Path, env: dict, *args: str) -> float:
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *args], cwd=project,
                          env=env, capture_output=True, text=True, check=False)
    seconds = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"the user project's tests failed ({' '.join(args) or 'plain'}):\n{proc.stdout[-2000:]}")
    return seconds


def run() -> list[dict]:
    from linmot_st.resources import project_template
    with tempfile.TemporaryDirectory(prefix="linmot-st-covbench-") as tmp:
        project = Path(tmp) / "project"
        shutil.copytree(project_template(), project)
        env = {**os.environ, "LINMOT_ST_CACHE": str(Path(tmp) / "cache")}
        env.pop("LINMOT_ST_COVERAGE", None)
        cold_plain = _pytest(project, env)
        cold_cov = _pytest(project, env, "--linmot-cov")
        plain = min(_pytest(project, env) for _ in range(RUNS))
        cov = min(_pytest(project, env, "--linmot-cov") for _ in range(RUNS))
    return [
        dict(name="user project tests, builds cached", value=plain, unit="s", target=None),
        dict(name="... with --linmot-cov (reports included)", value=cov, unit="s", target=None),
        dict(name="coverage overhead, builds cached", value=cov / plain, unit="x", target="<= 2"),
        dict(name="first run (builds compiled)", value=cold_plain, unit="s", target=None),
        dict(name="first run with --linmot-cov (coverage builds compiled)", value=cold_cov, unit="s", target=None),
    ]
