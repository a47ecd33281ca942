"""The scope in pytest: ini options and the `scope` marker give every rig of a test a scope; the files of
the scopes of a failed test (PNG, VCD, CSV) are written and named in its failure report.

Registered by plugin.py (pytest_configure); its ini options are added by plugin.pytest_addoption.
"""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from . import scope as scope_mod

# ini name -> (help, default)
INI = {
    "linmot_st_scope": ("PLC variables (IEC paths) and drive signals (driveN.position, .velocity, .state, "
                        ".status_word, .nmt) that every rig of a Python test records per scan", ""),
    "linmot_st_scope_every": ("the scope samples every n-th scan", "1"),
    "linmot_st_scope_drives": ("true: the scope also records position, velocity and state of every drive", "false"),
    "linmot_st_scope_dir": ("folder of the scope files (PNG, VCD, CSV), relative to the rootdir", "build/scope"),
    "linmot_st_scope_write": ("when the scope files are written: failure or always", "failure"),
    "linmot_st_st_scope": ("variables of an ST test's instance its scope records (names, or * for all its "
                           "elementary variables)", ""),
}
MARKER = ("scope(*paths, every=1, drives=False, write=False): every rig of the test records these variables "
          "(replaces the ini option linmot_st_scope); the PNG, VCD and CSV are written when it fails "
          "(write=True: always)")


def addoption(parser) -> None:
    for name, (text, default) in INI.items():
        parser.addini(name, f"{text} (default {default or 'none'})", default="")


def _ini(config, name: str) -> str:
    value = config.getini(name)
    return (value if isinstance(value, str) else " ".join(value)).strip() or INI[name][1]


def _truthy(text: str) -> bool:
    return text.strip().lower() in ("1", "true", "yes", "on")


def defaults_of(item) -> dict:
    """What the rigs of this test record: the `scope` marker, else the ini options."""
    config = item.config
    d = dict(paths=tuple(_ini(config, "linmot_st_scope").replace(",", " ").split()),
             every=int(_ini(config, "linmot_st_scope_every")),
             drives=_truthy(_ini(config, "linmot_st_scope_drives")),
             write=_ini(config, "linmot_st_scope_write").lower() == "always")
    mark = item.get_closest_marker("scope")
    if mark:
        d.update(paths=tuple(mark.args), **{k: mark.kwargs[k] for k in ("every", "drives", "write")
                                              if k in mark.kwargs})
    return d


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    """The scopes made while this test runs are collected for its report, and forgotten after it."""
    scope_mod.ACTIVE = []
    scope_mod.DEFAULTS = None if item.get_closest_marker("st_test") else defaults_of(item)
    try:
        yield
    finally:
        scope_mod.ACTIVE, scope_mod.DEFAULTS = None, None


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    report = outcome.get_result()
    scopes = scope_mod.ACTIVE
    if not scopes or report.when != "call":
        return
    failed = report.failed
    chosen = [s for s in scopes if failed or s.write_always]
    if not chosen:
        return
    text = write_scopes(item, chosen, mark=failed)
    if failed:
        add_to_failure(report, text)
    else:
        report.sections.append(("linmot-st scope", text))


def write_scopes(item, scopes: list, mark: bool) -> str:
    folder = Path(str(item.config.rootpath)) / _ini(item.config, "linmot_st_scope_dir")
    stem = f"{Path(str(item.path)).stem}.{item.name}"
    lines = []
    for k, s in enumerate(scopes, 1):
        plc = s.rig.plc
        where = (plc.time_ns, plc.scan_count) if mark else None
        files = s.write(folder, stem if len(scopes) == 1 else f"{stem}-{k}", where)
        what = ", ".join(sig.name for sig in s.signals)
        lines.append(f"scope of {what} ({len(s.rows)} samples"
                     + (f", failed at scan {plc.scan_count}, PLC time {plc.time_ns / 1e6:g} ms" if mark else "")
                     + "):")
        lines += [f"  {kind.upper()}: {_shown(p)}" for kind, p in files.items()]
    return "\n".join(lines)


def _shown(path: Path) -> str:
    try:
        return os.path.relpath(path)
    except ValueError:                   # another drive (Windows)
        return str(path)


def add_to_failure(report, text: str) -> None:
    """The scope's files in the failure text itself (so --show-capture=no and JUnit XML keep them)."""
    longrepr = report.longrepr
    if hasattr(longrepr, "addsection"):
        longrepr.addsection("linmot-st scope", text)
    elif isinstance(longrepr, str):
        report.longrepr = f"{longrepr}\n\n{text}"
    else:
        report.sections.append(("linmot-st scope", text))


def st_scope(item, rig, base: str) -> None:
    """An ST test's scope (ini linmot_st_st_scope): names of variables of its instance `base`, or *."""
    names = _ini(item.config, "linmot_st_st_scope").replace(",", " ").split()
    drives = _truthy(_ini(item.config, "linmot_st_scope_drives"))
    if not names and not drives:
        return
    if names == ["*"]:                   # the elementary variables the scope can draw (no STRING, no struct)
        names = [k for k in rig.plc[base]
                 if k.upper() not in ("STUNIT", "EN", "ENO") and _drawable(rig.plc, f"{base}.{k}")]
    paths = [f"{base}.{n}" for n in names]
    rig.scope(*paths, every=int(_ini(item.config, "linmot_st_scope_every")), drives=drives and bool(rig.drives),
              write=_ini(item.config, "linmot_st_scope_write").lower() == "always")


def _drawable(plc, path: str) -> bool:
    try:
        scope_mod.plc_signal(plc, path)
        return True
    except TypeError:
        return False
