"""Helpers for the commissioning tests: plc_project built once per backend and process, and runs of the
commissioning of examples/two_axes.pvl against emulated drives (docs/commissioning.md, "Tests")."""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .project import REPO, build_project, prepare

EXAMPLE = REPO / "examples" / "two_axes.pvl"
_builds: dict[str, Any] = {}




def example():
    from linmot_st.pvl import load_pvl
    return load_pvl(EXAMPLE)


def project_build(backend: str = "auto"):
    """plc_project with the dataset of examples/two_axes.pvl, built once per backend ("auto": MatIEC when
    installed, else builtin; COMMISSION_BACKEND=matiec|builtin forces one)."""
    if backend == "auto":
        backend = os.environ.get("COMMISSION_BACKEND", "auto")
    if backend not in _builds:
        _builds[backend] = build_project(prepare(example(), EXAMPLE.name), backend)
    return _builds[backend]


@dataclass
class Outcome:
    pvl: Any
    result: Any
    verification: Any
    report: Any

    def axis(self, node: int = 1):
        return next(a for a in self.result.axes if a.node_id == node)


def commission(backend: str = "auto", pvl=None, **kw) -> Outcome:
    """Run the commissioning of `pvl` (default the example) and verify it. Keyword arguments: RunOptions
    fields (timings default "fast", reset default False, force default True: the full write, whose exchanges
    the tests count; the re-commissioning tests pass force=False), and run()'s hooks drive_factory, prepare_bus,
    prepare_plc."""
    from linmot_st.pvl.dataset import from_pvl
    from .report import Context, Report
    from .runner import RunOptions, run
    from .verify import verify_run

    pvl = pvl or example()
    hooks = {k: kw.pop(k) for k in ("drive_factory", "prepare_bus", "prepare_plc", "progress") if k in kw}
    kw.setdefault("timings", "fast")
    kw.setdefault("reset", False)
    kw.setdefault("force", True)
    opts = RunOptions(**kw)
    res = project_build(backend)
    result = run(pvl, opts, res, **hooks)
    verification = verify_run(pvl, result)
    ds = from_pvl(pvl)
    path = str(EXAMPLE.relative_to(REPO)) if pvl.filename is None or Path(pvl.filename) == EXAMPLE else pvl.filename
    ctx = Context(path, f"linmot-st commission {path} (test run)", res.backend, 0.0, True, "plc_project/plc.st", ds.words)
    report = Report(ctx, result, ds, verification, pvl)
    report.compute()
    return Outcome(pvl, result, verification, report)
