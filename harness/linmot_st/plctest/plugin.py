"""The linmot-st pytest plugin (entry point pytest11 `linmot_st`): test a PLC program in ST with pytest.

Fixtures
  linmot_project   the project (ini options, linmot_st.plctest.project)          session
  linmot_backend   the backend of this test ("auto" resolved; each_backend parametrizes it)
  st_build         st_build(entry=None, backend=None) -> BuildResult (cached per session and on disk)
  plc_build        the project's entry file built;  plc: a fresh Plc of it
  make_rig         make_rig(**Rig options) -> Rig: the PLC on a simulated bus with emulated drives
  rig              make_rig() with the drives of the `drives` marker (else of the ini options)
  make_pycan_rig   make_rig's python-can variant (RealTimeRig, closed after the test); pycan_rig: one of
                   them on `virtual`, or on socketcan:vcan0 under the needs_vcan marker
Markers
  each_backend     run the test once per backend (matiec skips where iec2c is missing)
  needs_iec2c      skip where MatIEC's iec2c is missing;  needs_vcan(channel="vcan0"): skip without it
  drives(*node_ids, **Rig options)   the drives of the `rig` fixture
Tests written in ST: files matching linmot_st_st_files (default test_*.st), see stunit.py.
Coverage of the ST: --linmot-cov (cov_plugin.py, docs/coverage.md).
docs/testing.md is the guide.
"""

from __future__ import annotations

import fnmatch
import os
from pathlib import Path

import pytest

from linmot_st.toolchain.backends import CHOICES

from . import cov_plugin, scope_plugin
from .project import INI, Project, project_of
from .stunit import StFile

MARKERS = [
    "each_backend: run the test once per available ST backend (matiec skipped where iec2c is missing)",
    "needs_iec2c: skip the test where MatIEC's iec2c is not installed",
    "needs_vcan(channel='vcan0'): skip the test where that SocketCAN interface does not exist",
    "drives(*node_ids, bitrate=, timings=, protocol=, profile=, latency_ns=, drive_factory=): the rig's drives",
    "matiec: needs MatIEC's iec2c (set by each_backend on its matiec run)",
    "linmot_st: a test run by the linmot-st plugin",
    "st_test: a test written in ST",
    scope_plugin.MARKER,
]


def pytest_addoption(parser):
    group = parser.getgroup("linmot-st", "testing PLC code with linmot-st")
    group.addoption("--linmot-backend", dest="linmot_backend", default=None, choices=CHOICES,
                    help="ST compiler for the project's builds (default: ini linmot_st_backend, else auto)")
    for name, (text, default) in INI.items():
        parser.addini(name, f"{text} (default {default})", default="")
    scope_plugin.addoption(parser)
    cov_plugin.addoption(parser, group)


def pytest_configure(config):
    for line in MARKERS:
        config.addinivalue_line("markers", line)
    if not config.pluginmanager.has_plugin("linmot_st_scope"):
        config.pluginmanager.register(scope_plugin, "linmot_st_scope")
    if not config.pluginmanager.has_plugin("linmot_st_cov"):
        config.pluginmanager.register(cov_plugin, "linmot_st_cov")     # its pytest_configure runs (historic)


# ---- markers -------------------------------------------------------------------------------------------

def matiec_missing() -> str | None:
    from linmot_st.toolchain import matiec_available
    from linmot_st.toolchain.testing import MATIEC_MISSING
    return None if matiec_available() else MATIEC_MISSING


def vcan_missing(channel: str = "vcan0") -> str | None:
    if os.path.exists(f"/sys/class/net/{channel}"):
        return None
    return (f"no SocketCAN interface {channel} (a Linux kernel with CAN support and `ip link add dev {channel} "
            "type vcan; ip link set up " + channel + "` are needed)")


def pytest_runtest_setup(item):
    if item.get_closest_marker("needs_iec2c") and matiec_missing():
        pytest.skip(matiec_missing())
    mark = item.get_closest_marker("needs_vcan")
    if mark:
        reason = vcan_missing(*mark.args, **mark.kwargs)
        if reason:
            pytest.skip(reason)


def pytest_generate_tests(metafunc):
    if metafunc.definition.get_closest_marker("each_backend") and "linmot_backend" in metafunc.fixturenames:
        from linmot_st.toolchain.testing import BACKEND_PARAMS
        metafunc.parametrize("linmot_backend", BACKEND_PARAMS, indirect=True)


# ---- ST tests ------------------------------------------------------------------------------------------

def pytest_collect_file(file_path: Path, parent):
    if file_path.suffix.lower() != ".st":
        return None
    patterns = project_of(parent.config).st_files
    if any(fnmatch.fnmatch(file_path.name, p) for p in patterns):
        return StFile.from_parent(parent, path=file_path)
    return None


# ---- fixtures ------------------------------------------------------------------------------------------

@pytest.fixture(scope="session")
def linmot_project(pytestconfig) -> Project:
    return project_of(pytestconfig)


@pytest.fixture
def linmot_backend(request, linmot_project) -> str:
    return linmot_project.backend_of(getattr(request, "param", None))


@pytest.fixture
def st_build(linmot_project, linmot_backend):
    def build(entry: str | Path | None = None, backend: str | None = None):
        return linmot_project.build(entry, backend or linmot_backend)
    return build


@pytest.fixture
def plc_build(st_build):
    return st_build()


@pytest.fixture
def plc(plc_build):
    from linmot_st.plc import Plc
    return Plc(plc_build)


def _rig_options(request, project: Project, timings: str | None = None) -> dict:
    """The ini options, then the `drives` marker's; `timings` replaces the ini's (not the marker's)."""
    opts = dict(nodes=project.nodes, bitrate=project.bitrate, timings=timings or project.timings,
                mailbox=project.mailbox)
    mark = request.node.get_closest_marker("drives")
    if mark:
        if mark.args:
            opts["nodes"] = tuple(mark.args)
        opts.update(mark.kwargs)
    return opts


@pytest.fixture
def make_rig(request, linmot_project, st_build):
    from .rig import Rig

    def make(entry: str | Path | None = None, backend: str | None = None, **options):
        opts = {**_rig_options(request, linmot_project), **options}
        return Rig(st_build(entry, backend), **opts)
    return make


@pytest.fixture
def rig(make_rig):
    return make_rig()


@pytest.fixture
def make_pycan_rig(request, linmot_project, st_build):
    from .rig import RealTimeRig
    rigs = []

    def make(entry: str | Path | None = None, backend: str | None = None, **options):
        opts = {**_rig_options(request, linmot_project, timings="fast"), **options}   # nothing waits seconds
        mark = request.node.get_closest_marker("needs_vcan")
        if mark and "bus" not in opts:
            opts["bus"] = "socketcan:" + (mark.args[0] if mark.args else mark.kwargs.get("channel", "vcan0"))
        r = RealTimeRig(st_build(entry, backend), **opts)
        rigs.append(r)
        return r
    yield make
    for r in rigs:
        r.close()


@pytest.fixture
def pycan_rig(make_pycan_rig):
    return make_pycan_rig()
