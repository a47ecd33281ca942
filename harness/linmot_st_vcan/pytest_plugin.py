"""pytest plugin: the tests marked `socketcan` run on a real Linux SocketCAN stack, inside a guest if need be.

    @pytest.mark.socketcan                                  # needs vcan0
    @pytest.mark.socketcan(interfaces=("vcan0", "vcan1"), timeout_s=300)

Where this kernel has the interfaces (a Linux machine after `modprobe vcan` and `ip link add`, or inside the
guest) such a test runs as usual. Elsewhere the plugin runs it inside a User-Mode Linux guest
(`linmot_st_vcan.Machine`, one guest per test, vcan0 and vcan1 up): `python -m pytest NODEID` with the same
checkout and venv, whose reports (pass, failure with its traceback, skip with its reason) come back as this
test's reports, like pytest-forked does for a forked process. A failing test's report gets a section with the
guest's output and kernel log. When the guest cannot be had here (no apt, no network to Debian's archive, a
kernel that cannot run UML...), the tests skip with the reason; once a guest has started in this process, a
guest that does not start is a failure.

LINMOT_ST_VCAN=off skips them; LINMOT_ST_VCAN=native never starts a guest (they skip without the interfaces).
Registered by tests/conftest.py.
"""

from __future__ import annotations

import json
import os
import re
import shutil
import sys
import tempfile
from pathlib import Path

import pytest

REPORTS_ENV = "LINMOT_ST_VCAN_REPORTS"      # set in the guest: where its pytest writes the reports
DEFAULT_TIMEOUT_S = 300


def interfaces_of(item) -> tuple[str, ...]:
    marker = item.get_closest_marker("socketcan")
    return tuple(marker.kwargs.get("interfaces", ("vcan0",))) if marker else ()


class _ReportWriter:
    """In the guest: every report of the run, serialised as one JSON line (read back by the host)."""

    def __init__(self, config, path: str) -> None:
        self.config = config
        self.file = open(path, "a", encoding="utf-8")

    def pytest_runtest_logreport(self, report) -> None:
        data = self.config.hook.pytest_report_to_serializable(config=self.config, report=report)
        self.file.write(json.dumps(data) + "\n")
        self.file.flush()

    def pytest_unconfigure(self) -> None:
        self.file.close()


def pytest_configure(config) -> None:
    path = os.environ.get(REPORTS_ENV)
    if path:
        config.pluginmanager.register(_ReportWriter(config, path), "linmot-st-vcan-report-writer")


class _Guests:
    """This process's access to guests: the machine once the tools are there, or why there is none."""

    def __init__(self) -> None:
        self.machine = None
        self.unavailable: str | None = None
        self.started = False

    def get(self):
        if self.machine is None and self.unavailable is None:
            from .fetch import Unavailable
            from .uml import Machine
            try:
                self.machine = Machine()
            except Unavailable as exc:
                self.unavailable = str(exc)
        return self.machine


_guests = _Guests()


def _mode() -> str:
    return os.environ.get("LINMOT_ST_VCAN", "auto").strip().lower() or "auto"


def pytest_collection_modifyitems(items) -> None:
    """The socketcan tests spread evenly over the run, the first one first: each takes a guest and tens of
    seconds, so with pytest -n 2 (which hands out consecutive runs of tests) they fall to both workers and
    none is left running alone at the end."""
    long = [item for item in items if interfaces_of(item)]
    if not long:
        return
    short = [item for item in items if not interfaces_of(item)]
    # where a new module starts: a socketcan test goes there, so that no module's fixtures are set up twice
    starts = [k for k in range(len(short)) if k == 0 or short[k].path != short[k - 1].path]
    at = {}
    for j, item in enumerate(long):
        target = j * len(short) // len(long)
        at.setdefault(next((k for k in starts if k >= target), len(short)), []).append(item)
    items[:] = [x for k in range(len(short) + 1) for x in (at.get(k, []) + short[k:k + 1])]


def pytest_runtest_setup(item) -> None:
    """A socketcan test that runs here (not sent to a guest) needs its interfaces on this kernel."""
    needed = interfaces_of(item)
    if not needed:
        return
    from . import native
    if _mode() == "off":
        pytest.skip("LINMOT_ST_VCAN=off")
    if not native(needed):
        pytest.skip(f"no {' / '.join(needed)} on this kernel (LINMOT_ST_VCAN={_mode()}; docs/bus.md says how "
                    "to add vcan interfaces)")


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_protocol(item, nextitem):
    needed = interfaces_of(item)
    if not needed or os.environ.get("LINMOT_ST_VCAN_GUEST") or _mode() in ("off", "native"):
        return None
    from . import native
    if native(needed):
        return None
    ihook = item.ihook
    ihook.pytest_runtest_logstart(nodeid=item.nodeid, location=item.location)
    for report in _reports_from_guest(item):
        ihook.pytest_runtest_logreport(report=report)
    ihook.pytest_runtest_logfinish(nodeid=item.nodeid, location=item.location)
    return True


def _synthetic(item, when: str, outcome: str, message: str = ""):
    from _pytest.reports import TestReport
    from _pytest.runner import CallInfo

    def act():
        if outcome == "skipped":
            pytest.skip(message)
        if outcome == "failed":
            pytest.fail(message, pytrace=False)

    return TestReport.from_item_and_call(item, CallInfo.from_call(act, when=when))


def _skipped(item, reason: str) -> list:
    setup = _synthetic(item, "setup", "skipped", reason)
    path, line, _ = item.reportinfo()
    setup.longrepr = (str(path), (line or 0) + 1, f"Skipped: {reason}")     # the test's place, not this file's
    return [setup, _synthetic(item, "teardown", "passed")]


def _failed(item, message: str) -> list:
    return [_synthetic(item, "setup", "passed"), _synthetic(item, "call", "failed", message),
            _synthetic(item, "teardown", "passed")]


def _work_dir(item) -> Path:
    name = re.sub(r"[^A-Za-z0-9_.-]+", "_", item.nodeid)[-120:]
    folder = Path(tempfile.gettempdir()) / "linmot-st-vcan" / name
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    return folder


def _reports_from_guest(item) -> list:
    from .uml import GuestStartError

    machine = _guests.get()
    if machine is None:
        return _skipped(item, f"no SocketCAN guest here: {_guests.unavailable}")
    marker = item.get_closest_marker("socketcan")
    timeout_s = marker.kwargs.get("timeout_s", DEFAULT_TIMEOUT_S)
    work = _work_dir(item)
    reports_file = work / "reports.jsonl"
    config = item.config
    # one process, no cache; without hypothesis's plugin, whose start costs 4-5 s in the guest (each system
    # call there is dear); a test that uses hypothesis still imports it
    argv = [sys.executable, "-m", "pytest", "-p", "no:xdist", "-p", "no:cacheprovider", "-p", "no:hypothesispytest",
            "-q", "-o", "addopts=", f"--tb={config.getoption('tbstyle', 'auto')}", item.nodeid]
    from linmot_st.toolchain.cache import default_dir
    try:
        run = machine.run(argv, cwd=config.rootpath, env={REPORTS_ENV: str(reports_file)}, timeout_s=timeout_s,
                          work_dir=work, writable=(default_dir(Path(config.rootpath)),))
    except GuestStartError as exc:
        if not _guests.started:
            _guests.unavailable = str(exc)
            return _skipped(item, f"no SocketCAN guest here: {exc}")
        return _failed(item, f"{exc}\n--- kernel log ---\n{exc.kernel_log}")
    _guests.started = True
    reports = []
    if reports_file.exists():
        for line in reports_file.read_text(encoding="utf-8").splitlines():
            rep = config.hook.pytest_report_from_serializable(config=config, data=json.loads(line))
            if rep is not None and getattr(rep, "nodeid", None) == item.nodeid and hasattr(rep, "when"):
                if isinstance(rep.longrepr, list):       # a skip's (path, line, reason): JSON made it a list
                    rep.longrepr = tuple(rep.longrepr)
                reports.append(rep)
    if not any(r.when == "teardown" for r in reports):
        return _failed(item, "the test did not complete in the guest\n" + run.describe())
    for rep in reports:
        if rep.failed:
            rep.sections.append(("SocketCAN guest", run.describe()))
    if not any(r.failed for r in reports):
        shutil.rmtree(work, ignore_errors=True)
    return reports
