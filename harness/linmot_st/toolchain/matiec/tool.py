"""MatIEC's iec2c: finding it, its flags and identity, running it, and its diagnostics as
`file:line:col: error: message` lines. What its C declares becomes the manifest in layout.py.
"""

from __future__ import annotations

import functools
import hashlib
import os
import re
import shutil
import signal as _signal
import subprocess
from dataclasses import dataclass
from pathlib import Path

from linmot_st.resources import TREES

from ..sources import Sources

WANTED_FLAGS = ("-f", "-l", "-p")   # as Beremiz: those of them that `iec2c -h` lists


class MatiecError(Exception):
    """iec2c rejected the sources (diagnostics: file:line:col: error: message lines) or its output is
    not understood."""

    def __init__(self, message: str, diagnostics: list[str] | None = None):
        super().__init__(message)
        self.diagnostics = diagnostics or [message]


@dataclass(frozen=True)
class Matiec:
    iec2c: Path
    lib: Path        # holds ieclib.txt; its C/ folder holds the headers

    @property
    def include(self) -> Path:
        return self.lib / "C"


def find() -> Matiec | None:
    """iec2c from $IEC2C, $MATIEC_HOME/iec2c or PATH; its lib folder from $MATIEC_HOME/lib or beside it."""
    candidates = []
    if os.environ.get("IEC2C"):
        candidates.append(Path(os.environ["IEC2C"]))
    home = os.environ.get("MATIEC_HOME")
    if home:
        candidates.append(Path(home) / "iec2c")
    on_path = shutil.which("iec2c")
    if on_path:
        candidates.append(Path(on_path))
    for c in candidates:
        if c.is_file() and os.access(c, os.X_OK):
            exe = c.resolve()
            libs = ([Path(home) / "lib"] if home else []) + [c.parent / "lib", exe.parent / "lib"]
            for lib in libs:
                if (lib / "ieclib.txt").is_file():
                    return Matiec(exe, lib.resolve())
    return None


@functools.cache
def flags(iec2c: Path) -> tuple[str, ...]:
    """Beremiz's choice: whichever of -f -l -p the help lists; plus, when listed, `-O l` (#line
    directives into the ST files, so gcc errors and the debug line table point at ST lines) and `-O p`."""
    try:
        proc = subprocess.run([str(iec2c), "-h"], capture_output=True, text=True, check=False, timeout=30)
        help_text = proc.stdout + proc.stderr
    except subprocess.TimeoutExpired:
        help_text = ""
    chosen = [f for f in WANTED_FLAGS if re.search(rf"^\s*{f}\b", help_text, re.M)]
    if re.search(r"^\s*-O\b", help_text, re.M):
        # p: one .c per POU, so the POUs compile in parallel units (generate() groups them)
        out = [o for o in ("l", "p") if re.search(rf"^\s*{o}\s*:", help_text, re.M)]
        if out:
            chosen += ["-O", ",".join(out)]
    return tuple(chosen)


def version(m: Matiec) -> str:
    """Identity of the compiler for the cache key: its binary and library, by content."""
    h = hashlib.sha256()
    for p in [m.iec2c, *sorted(m.lib.glob("*.txt")), *sorted(m.include.glob("*.h"))]:
        st = p.stat()
        h.update(f"{p}:{st.st_size}:{st.st_mtime_ns};".encode())
    return f"iec2c {m.iec2c} {h.hexdigest()[:16]}"


_ERROR = re.compile(r"^(?P<file>.*?):(?P<line>\d+)-(?P<col>\d+)(?:\.\.\d+-\d+)?: (?P<sev>error|warning): (?P<msg>.*)$")


_INCLUDED_FROM = re.compile(r"^in file included from file (?P<file>.*?):(?P<line>\d+)")


def diagnostics_from(stderr: str, entry: str, rc: int) -> list[str]:
    """iec2c's `file:l-c..l-c: error: msg` as `file:l:c: error: msg`; anything else it says is attached to
    the entry file, since it names no position."""
    out: list[str] = []
    for raw in stderr.splitlines():
        line = raw.strip()
        if not line or re.match(r"^\d+ error\(s\) found", line):
            continue
        inc = _INCLUDED_FROM.match(line)
        if inc:
            out.append(f"{inc['file']}:{inc['line']}:1: note: included from here")
            continue
        m = _ERROR.match(line)
        if m:
            if m["sev"] == "error":
                out.append(f"{m['file']}:{m['line']}:{m['col']}: error: {m['msg']}")
        else:
            out.append(f"{entry}:1:1: error: iec2c: {line}")
    if rc < 0 or rc >= 128:
        sig = -rc if rc < 0 else rc - 128
        out.append(f"{entry}:1:1: error: {signal_message(sig)}")
    if not out:
        out.append(f"{entry}:1:1: error: iec2c failed with exit code {rc}")
    return out


def signal_message(sig: int) -> str:
    """What it means when iec2c ends on a signal."""
    try:
        name = _signal.Signals(sig).name
    except ValueError:
        name = f"signal {sig}"
    if sig == _signal.SIGSEGV:
        return ("iec2c crashed (SIGSEGV); MatIEC does this after some syntax errors, e.g. a reserved word "
                "(a standard function or type name) used as an identifier")
    if sig == _signal.SIGABRT:
        return "iec2c aborted (SIGABRT): an internal check of MatIEC failed on this input"
    if sig == _signal.SIGKILL:
        return "iec2c was killed (SIGKILL): out of memory, or killed from outside"
    if sig in (_signal.SIGTERM, _signal.SIGINT, _signal.SIGHUP):
        return f"iec2c was stopped from outside ({name})"
    return f"iec2c ended on {name}"


TIMEOUT_ENV = "LINMOT_ST_IEC2C_TIMEOUT"
DEFAULT_TIMEOUT_S = 120.0     # st_lib takes about 2 s; MatIEC needs minutes for arrays of 10^8 elements


def timeout_s() -> float | None:
    """iec2c's time limit in seconds: $LINMOT_ST_IEC2C_TIMEOUT (0: none), else 120."""
    text = os.environ.get(TIMEOUT_ENV, "").strip()
    if not text:
        return DEFAULT_TIMEOUT_S
    try:
        value = float(text)
    except ValueError:
        raise MatiecError(f"{TIMEOUT_ENV}={text!r}: expected a number of seconds") from None
    return value if value > 0 else None


def include_folder(m: Matiec, search: list[Path], folder: Path) -> Path:
    """iec2c searches one folder before its working directory: the -I folder, which must hold MatIEC's own
    library (ieclib.txt and the files it includes). For a build with the library tree on its search path
    (sources.library_search), `folder` gets links to MatIEC's library files and to the tree's st_lib/ and
    plc_project/, and serves as that -I folder."""
    folder.mkdir(parents=True, exist_ok=True)
    links = {p.name: p for p in m.lib.iterdir()}
    for tree in search:
        links.update({name: tree / name for name in TREES if (tree / name).is_dir()})
    for name, target in links.items():
        link = folder / name
        if not link.exists():
            link.symlink_to(target.resolve())
    return folder


def run_iec2c(m: Matiec, sources: Sources, out_dir: Path) -> list[Path]:
    """Compile the entry file into out_dir; returns the generated files iec2c lists."""
    out_dir.mkdir(parents=True, exist_ok=True)
    lib = include_folder(m, sources.search, out_dir.parent / "iec2c-include") if sources.search else m.lib
    argv = [str(m.iec2c), *flags(m.iec2c), "-I", str(lib), "-T", str(out_dir), sources.entry_rel]
    limit = timeout_s()
    try:
        proc = subprocess.run(argv, cwd=sources.root, capture_output=True, text=True, check=False, timeout=limit)
    except subprocess.TimeoutExpired:
        msg = (f"{sources.entry_rel}:1:1: error: iec2c did not finish within {limit:g} s and was stopped "
               f"(set {TIMEOUT_ENV} to a longer time in seconds, or 0 for none; MatIEC takes minutes on "
               f"very large arrays)")
        raise MatiecError(msg, [msg]) from None
    finally:
        if lib != m.lib:
            shutil.rmtree(lib, ignore_errors=True)
    if proc.returncode != 0:
        diags = diagnostics_from(proc.stderr + ("\n" + proc.stdout if proc.returncode != 1 else ""),
                                 sources.entry_rel, proc.returncode)
        raise MatiecError("\n".join(diags), diags)
    files = [out_dir / line.strip() for line in proc.stdout.splitlines() if line.strip()]
    missing = [f.name for f in files if not f.is_file()]
    if missing or not files:
        raise MatiecError(f"{sources.entry_rel}:1:1: error: iec2c reported success but wrote no "
                          f"{', '.join(missing) or 'files'}")
    return files
