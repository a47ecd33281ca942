"""Helpers for the commissioning tests: plc_project built once per backend and process, and runs of the
commissioning of examples/two_axes.pvl against emulated drives (docs/commissioning.md, "Tests")."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from linmot_st.pvl import PvlFile, load_pvl
from linmot_st.pvl.dataset import from_pvl

from .project import REPO, TASK_INTERVAL_NS, build_project, parse_task_interval, prepare
from .report import Context, Report
from .runner import RunOptions, RunResult, run
from .verify import Verification, verify_run

EXAMPLE = REPO / "examples" / "two_axes.pvl"
_builds: dict[str, Any] = {}




def example():
    return load_pvl(EXAMPLE)


def project_build(backend: str = "auto", task_interval: str | int | None = None):
    """plc_project with the dataset of examples/two_axes.pvl, built once per backend ("auto": MatIEC when
    installed, else builtin; COMMISSION_BACKEND=matiec|builtin forces one) and task interval (ns or a text
    such as "250us": project.parse_task_interval; None: plc_project's 1 ms)."""
    if backend == "auto":
        backend = os.environ.get("COMMISSION_BACKEND", "auto")
    interval_ns = task_interval_ns(task_interval)
    if (backend, interval_ns) not in _builds:
        _builds[backend, interval_ns] = build_project(
            prepare(example(), EXAMPLE.name, task_interval_ns=interval_ns), backend)
    return _builds[backend, interval_ns]


def task_interval_ns(task_interval: str | int | None) -> int:
    if task_interval is None:
        return TASK_INTERVAL_NS
    return parse_task_interval(task_interval) if isinstance(task_interval, str) else int(task_interval)


@dataclass
class Outcome:
    pvl: PvlFile
    result: RunResult
    verification: Verification
    report: Report

    def axis(self, node: int = 1):
        return next(a for a in self.result.axes if a.node_id == node)


def commission(backend: str = "auto", pvl=None, **kw) -> Outcome:
    """Run the commissioning of `pvl` (default the example) and verify it. Keyword arguments: RunOptions
    fields (timings default "fast", reset default False, force default True: the full write, whose exchanges
    the tests count; the re-commissioning tests pass force=False), task_interval (project_build), and run()'s
    hooks drive_factory, prepare_bus, prepare_plc."""
    pvl = pvl or example()
    hooks = {k: kw.pop(k) for k in ("drive_factory", "prepare_bus", "prepare_plc", "progress") if k in kw}
    kw.setdefault("timings", "fast")
    kw.setdefault("reset", False)
    kw.setdefault("force", True)
    task_interval = kw.pop("task_interval", None)
    opts = RunOptions(**kw)
    res = project_build(backend, task_interval)
    result = run(pvl, opts, res, **hooks)
    verification = verify_run(pvl, result)
    ds = from_pvl(pvl)
    path = str(EXAMPLE.relative_to(REPO)) if pvl.filename is None or Path(pvl.filename) == EXAMPLE else pvl.filename
    ctx = Context(path, f"linmot-st commission {path} (test run)", res.backend, 0.0, True, "plc_project/plc.st", ds.words)
    report = Report(ctx, result, ds, verification, pvl)
    report.compute()
    return Outcome(pvl, result, verification, report)
