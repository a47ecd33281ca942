"""The PLC project that commissions a given PVL file: plc_project with the file's dataset, built.

`plc_project/` holds the program (commission.st), the configuration (config.st) and the dataset generated
from examples/two_axes.pvl (dataset.st). For a PVL file whose dataset text equals the committed one,
plc_project itself is built (so `make demo` runs the committed project, and the build cache serves the
tests and the demo alike); for any other file an entry file is generated in a folder of its own
(build/commission/<hash>/ in a checkout, the user's cache folder for an installed linmot-st) that includes
the same program and configuration with the file's dataset. That folder is the build's include root, so
st_lib/ and plc_project/ come from the library tree on its include path (linmot_st.resources).

The task interval (`--task-interval`) is fixed when the program is built: MatIEC and the builtin backend take
the scan period from the CONFIGURATION's TASK. Another interval than plc_project's 1 ms puts a copy of
plc_project/config.st with that INTERVAL into the generated folder (the one place the configuration is
written remains config.st; the copy changes only the interval literal).
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass
from decimal import Decimal
from pathlib import Path

from linmot_st import resources, toolchain
from linmot_st.pvl.to_st import to_st

REPO = resources.CHECKOUT              # examples/ and build/ of a source checkout
INSTANCE = "CONFIG0.RES0.MAIN"         # the program instance (plc_project/config.st)
MAILBOX = "CONFIG0.RES0.CAN0"
MAX_AXES = 32                          # FB_PlcAxis instances A1..A32 in plc_project/commission.st
TASK_INTERVAL_NS = 1_000_000           # plc_project/config.st: TASK Cyclic(INTERVAL := T#1ms)
# below 50 us a scan gains nothing (the shortest frame takes 47 us at 1 Mbit/s) and a real PLC would have to run
# the 32-axis scan in it (docs/commissioning.md, "Task interval"); above 10 ms, the flash polls
# (FB_LmCommission.PollInterval, 10 ms) and every exchange wait for the scan
MIN_TASK_INTERVAL_NS, MAX_TASK_INTERVAL_NS = 50_000, 10_000_000
_TASK = re.compile(r"(TASK\s+Cyclic\s*\(\s*INTERVAL\s*:=\s*)T#[0-9A-Za-z_.]+")
_UNITS_NS = {"us": 1_000, "ms": 1_000_000, "s": 1_000_000_000}


@dataclass
class Project:
    entry: Path                        # the .st entry file built
    dataset_text: str
    committed: bool                    # True: plc_project itself
    root: Path | None = None           # the include root, when it is not the entry's library tree
    task_interval_ns: int = TASK_INTERVAL_NS


def parse_task_interval(text: str) -> int:
    """A task interval such as "250us", "1ms", "0.5ms" or "T#250us", in ns: a whole number of microseconds in
    MIN_TASK_INTERVAL_NS..MAX_TASK_INTERVAL_NS. Raises ValueError with the reason."""
    m = re.fullmatch(r"(?:T#)?\s*(\d+(?:\.\d+)?)\s*(us|ms|s)", text.strip(), re.IGNORECASE)
    if not m:
        raise ValueError(f"{text!r}: not a task interval (a number with us, ms or s: 250us, 1ms)")
    ns = Decimal(m.group(1)) * _UNITS_NS[m.group(2).lower()]          # exact: 0.0005s is 500 us
    if ns != int(ns) or int(ns) % 1_000:
        raise ValueError(f"{text}: the task interval must be a whole number of microseconds")
    ns = int(ns)
    if not MIN_TASK_INTERVAL_NS <= ns <= MAX_TASK_INTERVAL_NS:
        raise ValueError(f"{text}: the task interval must be {MIN_TASK_INTERVAL_NS // 1000} us.."
                         f"{MAX_TASK_INTERVAL_NS // 1_000_000} ms")
    return ns


def configuration_text(config: str, interval_ns: int) -> str:
    """plc_project/config.st's text with the Cyclic task's INTERVAL set to interval_ns (whole microseconds)."""
    # milliseconds with a decimal fraction: MatIEC (IEC 61131-3 ed. 2) knows no us or ns unit
    ms, us = divmod(interval_ns // 1_000, 1_000)
    literal = f"T#{ms}ms" if us == 0 else f"T#{ms}.{us:03d}".rstrip("0") + "ms"
    text, n = _TASK.subn(lambda m: m.group(1) + literal, config)
    if n != 1:
        raise ValueError(f"plc_project/config.st: {n} 'TASK Cyclic(INTERVAL := ...)' declarations, expected one")
    return text


def prepare(pvl, source_name: str | None = None, *, text: str | None = None,
            task_interval_ns: int = TASK_INTERVAL_NS) -> Project:
    """Write (if needed) the entry file commissioning `pvl`, or the dataset file `text` (datasets.py: per-node
    datasets), with the PLC task's interval. Raises DatasetError when it does not fit."""
    tree = resources.library_tree()
    plc_project = tree / "plc_project"
    if not (plc_project / "commission.st").exists():
        raise FileNotFoundError(f"{plc_project}/commission.st not found: reinstall linmot-st")
    if text is None:
        text = to_st(pvl, source_name=source_name)
    committed = plc_project / "dataset.st"
    own_task = task_interval_ns != TASK_INTERVAL_NS
    if committed.exists() and committed.read_text() == text and not own_task:
        return Project(plc_project / "plc.st", text, True)
    config = configuration_text((plc_project / "config.st").read_text(), task_interval_ns) if own_task else None
    key = text if config is None else text + config
    folder = resources.work_dir("commission") / hashlib.sha256(key.encode()).hexdigest()[:16]
    folder.mkdir(parents=True, exist_ok=True)
    _write_if_changed(folder / "dataset.st", text)
    if config is not None:
        _write_if_changed(folder / "config.st", f"(* GENERATED by linmot-st commission: plc_project/config.st with a "
                                                f"task interval of {task_interval_ns / 1000:g} us *)\n" + config)
    _write_if_changed(folder / "plc.st", "\n".join([
        "(* GENERATED by linmot-st commission: plc_project with the dataset of "
        f"{(source_name or 'a PVL file').replace('*)', '* )')} *)",
        '{#include "st_lib/linmot.st"}',
        '{#include "dataset.st"}',
        '{#include "plc_project/motion.st"}',
        '{#include "plc_project/commission.st"}',
        '{#include "config.st"}' if config is not None else '{#include "plc_project/config.st"}',
        "",
    ]))
    return Project(folder / "plc.st", text, False, root=folder, task_interval_ns=task_interval_ns)


def _write_if_changed(path: Path, text: str) -> None:
    if not path.exists() or path.read_text() != text:
        path.write_text(text)


def build_project(project: Project, backend: str = "auto"):
    """The toolchain's BuildResult (cached by content)."""
    return toolchain.build(str(project.entry), backend=backend, root=project.root)   # toolchain.build: tests replace it
