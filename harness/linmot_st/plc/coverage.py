"""The coverage builds loaded in this process, and their counters written into a session folder.

A coverage build (toolchain.build(coverage=True)) links libgcov, whose counters live in the library:
each private copy a Plc loads (plc/runtime.py) has its own. `dump(folder)` makes each library loaded
since the last dump write its counters out, once (what it runs afterwards is not counted); libgcov adds
them to the .gcda file already there, so the instances of one build and several processes (pytest-xdist
workers) sum up. The .gcda of a build goes to
`folder/<entry name>/`, beside a copy of the build's .gcno files, which is what gcov reads.
"""

from __future__ import annotations

import json
import os
import shutil
import threading
from pathlib import Path

COVERAGE_RECORD = "coverage.json"       # toolchain/__init__.py writes it into a coverage build's entry
DUMP_SYMBOL = "plc_coverage_dump"       # toolchain/glue/plc_coverage.c

_loaded: list[tuple[object, Path]] = []   # (the library's ctypes handle, its build entry)
_lock = threading.Lock()
lost: list[Path] = []                     # builds whose counters could not be written (their folder went)


def is_coverage_build(entry: Path) -> bool:
    return (Path(entry) / COVERAGE_RECORD).is_file()


def register(lib, library: Path) -> None:
    """A Plc loaded `library` (the build's libplc.so) as `lib`: if it is a coverage build, remember it for
    dump(). The handle is kept: the library is never unloaded anyway (plc/runtime.py)."""
    entry = Path(library).parent
    if hasattr(lib, DUMP_SYMBOL) and is_coverage_build(entry):
        with _lock:
            _loaded.append((lib, entry))


def loaded_entries() -> list[Path]:
    with _lock:
        return sorted({entry for _, entry in _loaded})


def dump(folder: Path) -> list[Path]:
    """Write the counters of every coverage build loaded since the last dump into `folder` (added to what
    is there). Returns the build folders under `folder` that received data."""
    folder = Path(folder)
    out: set[Path] = set()
    with _lock:
        todo = list(_loaded)
        _loaded.clear()
        for lib, entry in todo:
            try:
                record = json.loads((entry / COVERAGE_RECORD).read_text())
                target = folder / entry.name
                _place_notes(entry, target)
            except (OSError, ValueError):
                # the build's folder is gone (a test's temporary cache): without its .gcno the counts
                # cannot be read, so they are not written
                lost.append(entry)
                continue
            objdir = Path(record["objdir"])
            # libgcov writes <objdir>/<unit>.gcda; GCOV_PREFIX_STRIP drops the objdir's components and
            # GCOV_PREFIX puts the file under target (read at each dump, so set per build)
            saved = {k: os.environ.get(k) for k in ("GCOV_PREFIX", "GCOV_PREFIX_STRIP")}
            os.environ["GCOV_PREFIX"] = str(target)
            os.environ["GCOV_PREFIX_STRIP"] = str(len(objdir.parts) - 1)
            try:
                getattr(lib, DUMP_SYMBOL)()
            finally:
                for k, v in saved.items():
                    if v is None:
                        os.environ.pop(k, None)
                    else:
                        os.environ[k] = v
            out.add(target)
    return sorted(out)


def _place_notes(entry: Path, target: Path) -> None:
    """The build's .gcno files (gcc's description of the counters) and its record beside the .gcda."""
    target.mkdir(parents=True, exist_ok=True)
    for note in [*entry.glob("*.gcno"), entry / COVERAGE_RECORD]:
        dest = target / note.name
        if not dest.exists():
            tmp = target / f".{note.name}.{os.getpid()}"
            shutil.copyfile(note, tmp)
            os.replace(tmp, dest)      # atomic: another worker may place the same file
