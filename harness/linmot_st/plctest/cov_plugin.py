"""Coverage of the ST code in pytest: `--linmot-cov` (or the ini option linmot_st_cov = true) makes every
build of the session a coverage build (toolchain.build reads $LINMOT_ST_COVERAGE), writes the counters of
the PLCs the tests loaded at the end of the session (each pytest-xdist worker its own, summed by libgcov)
and reports line and branch coverage of the ST: a table in the terminal, Cobertura XML and HTML with the
ST annotated (docs/coverage.md).

Registered by plugin.py (pytest_configure); its options are added by plugin.pytest_addoption.
"""

from __future__ import annotations

import os
import shutil
from pathlib import Path

# ini name -> (help, default)
INI = {
    "linmot_st_cov": ("true: line and branch coverage of the ST code the tests ran (as --linmot-cov)", "false"),
    "linmot_st_cov_dir": ("folder of the coverage reports (coverage.xml, html/), relative to the rootdir",
                          "build/st-coverage"),
    "linmot_st_cov_pous": ("true: the terminal table has a row per POU under each file", "true"),
}


def addoption(parser, group) -> None:
    group.addoption("--linmot-cov", dest="linmot_cov", action="store_true", default=False,
                    help="line and branch coverage of the ST code the tests ran: a table, Cobertura XML and "
                         "HTML under linmot_st_cov_dir (default build/st-coverage)")
    group.addoption("--linmot-cov-dir", dest="linmot_cov_dir", default=None,
                    help="folder of the coverage reports (default: ini linmot_st_cov_dir)")
    for name, (text, default) in INI.items():
        parser.addini(name, f"{text} (default {default})", default="")


def _ini(config, name: str) -> str:
    value = config.getini(name)
    return (value if isinstance(value, str) else " ".join(value)).strip() or INI[name][1]


def enabled(config) -> bool:
    return bool(config.getoption("linmot_cov", False)) or _ini(config, "linmot_st_cov").lower() in ("1", "true", "yes", "on")


def report_dir(config) -> Path:
    folder = config.getoption("linmot_cov_dir", None) or _ini(config, "linmot_st_cov_dir")
    return (Path(str(config.rootpath)) / folder).resolve()


def _is_worker(config) -> bool:
    return hasattr(config, "workerinput")


def pytest_configure(config):
    from linmot_st.toolchain import COVERAGE_ENV
    if not enabled(config):
        return
    data = report_dir(config) / "data"
    if not _is_worker(config):
        # a fresh folder per session; the workers (started later) inherit the environment
        shutil.rmtree(data, ignore_errors=True)
        data.mkdir(parents=True, exist_ok=True)
        config._linmot_cov_env = os.environ.get(COVERAGE_ENV)
        os.environ[COVERAGE_ENV] = str(data)


def pytest_sessionfinish(session, exitstatus):
    from linmot_st.plc import coverage as collect
    from linmot_st.toolchain import COVERAGE_ENV
    config = session.config
    if not enabled(config):
        return
    data = Path(os.environ.get(COVERAGE_ENV) or report_dir(config) / "data")
    collect.dump(data)
    if _is_worker(config):
        return
    from linmot_st.stcov import report
    files = report.read(data)
    root = Path(str(config.rootpath))
    text = report.summary(files, root, per_pou=_ini(config, "linmot_st_cov_pous").lower() in ("1", "true", "yes", "on"))
    try:
        written = report.write_reports(files, report_dir(config), root) if files else {}
    except RuntimeError as exc:
        written, text = {}, text + f"\n(no reports: {exc})"
    config._linmot_cov_text = (text, written)
    previous = getattr(config, "_linmot_cov_env", None)
    if previous is None:
        os.environ.pop(COVERAGE_ENV, None)
    else:
        os.environ[COVERAGE_ENV] = previous


def pytest_terminal_summary(terminalreporter, exitstatus, config):
    got = getattr(config, "_linmot_cov_text", None)
    if not got:
        return
    text, written = got
    terminalreporter.section("linmot-st: ST coverage")
    terminalreporter.write_line(text if text.count("\n") > 1 else "no coverage build was loaded")
    for kind in ("cobertura", "html"):
        if kind in written:
            terminalreporter.write_line(f"{kind}: {written[kind]}")
