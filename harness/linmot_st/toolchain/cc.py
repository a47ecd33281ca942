"""The C compiler: generated C + glue -> one shared library.

Each translation unit is compiled in its own gcc process, all in parallel (the ~6k lines of headers each
MatIEC unit includes dominate the time; the builtin backend cuts its C into units of equal size for
this), then linked. The glue depends on nothing generated, so its gcc may start before the ST is
translated (`start`). gcc's diagnostics become a CompileError: with iec2c's `#line` directives they
already point into the ST files.
"""

from __future__ import annotations

import functools
import os
import shlex
import shutil
import subprocess
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

GLUE_DIR = Path(__file__).parent / "glue"
GLUE_SOURCES = [GLUE_DIR / "plc_glue.c"]
COVERAGE_GLUE = GLUE_DIR / "plc_coverage.c"      # coverage builds: flushes libgcov's counters on request

# Coverage builds (docs/coverage.md): gcc's own arc counters (gcov). -O0: at -O1 gcc moves and merges the
# code of neighbouring statements, and gcov's counts per (ST) line stop matching what the ST ran.
COVERAGE_FLAGS = ["--coverage", "-O0"]
COVERAGE_LINK_FLAGS = ["--coverage"]

# -g: the line table lets a fault's address be mapped back to its POU and ST line
BASE_FLAGS = ["-O1", "-g1", "-fPIC", "-Wno-unused-function", "-fno-strict-aliasing"]
# Optimisation level by size (docs/toolchain.md). gcc's -O1 grows faster than linearly with the length of
# one function (its memory-SSA walks over a body that stores through one pointer again and again): one
# function of 10k ST statements took ~55 s and 400 MB at -O1, ~4 s at -O0; and even cut into short
# functions, straight-line ST costs -O1 about 1 ms per C line. A unit with a function longer than
# LONG_FUNCTION_LINES, or longer than LARGE_UNIT_LINES in all, is compiled at -O0. plc_project's units stay
# far below both (about 10k lines, the longest function a few hundred).
LONG_FUNCTION_LINES = 4000
LARGE_UNIT_LINES = 40_000
# ... and gcc collects its garbage more often there: a 48k-line unit peaked at 262 MB instead of 380 MB for
# 14 % more CPU (a 100k-statement program: 1.2 GB before)
LARGE_UNIT_MEMORY_FLAGS = ("--param", "ggc-min-expand=30", "--param", "ggc-min-heapsize=32768")
# Flags of the builtin backend's units. gcc's dead store elimination and dominator optimisation cost its
# C about a quarter of gcc's time (plc_project: 2.7 s -> 2.0 s of CPU), for no measurable cost per scan
# (docs/toolchain.md, "Build speed"). Both are old gcc options; a compiler that does not know them (clang)
# warns and goes on.
BUILTIN_FLAGS = ["-fno-tree-dse", "-fno-tree-dominator-opts"]
# -z defs: a symbol the generated C uses but never defines fails the link, not the later dlopen
LINK_FLAGS = ["-shared", "-Wl,-z,defs", "-lm", "-ldl", "-lpthread", "-lrt"]   # -lrt: timer_create (glibc < 2.34)


class CCompileError(Exception):
    """gcc failed; `diagnostics` holds its error lines."""

    def __init__(self, message: str, diagnostics: list[str]):
        super().__init__(message)
        self.diagnostics = diagnostics


@dataclass(frozen=True)
class Compiler:
    path: str
    version: str


@functools.cache
def find_compiler() -> Compiler:
    name = os.environ.get("CC", "gcc")
    argv = shlex.split(name)
    path = shutil.which(argv[0])
    if not path:
        raise CCompileError(f"no C compiler: {argv[0]!r} is not on PATH (install gcc, or set CC)", [])
    out = subprocess.run([path, *argv[1:], "--version"], capture_output=True, text=True, check=False)
    return Compiler(" ".join([path, *argv[1:]]), out.stdout.splitlines()[0] if out.stdout else "unknown")


@functools.cache
def supports(flags: tuple[str, ...]) -> bool:
    """Whether the compiler accepts these flags (probed once on an empty unit)."""
    cc = find_compiler()
    proc = subprocess.run([*shlex.split(cc.path), *flags, "-x", "c", "-c", "-o", os.devnull, "-"],
                          input="int x;\n", capture_output=True, text=True, check=False)
    return proc.returncode == 0


# the checks of iec2c's C for behaviour C leaves undefined and a PLC must not meet silently: an index out
# of range, a shift count out of range, a float -> integer conversion out of range (inf, NaN included)
CHECKS = "shift-exponent,float-cast-overflow"


def check_flags() -> list[str]:
    """Flags that stop iec2c's C at an out-of-range index, shift count or float -> integer conversion,
    checked one by one for support.

    First choice: UBSan's checks calling its `_abort` entry points, which the glue defines (plc_glue.c),
    so each check is a PLC fault of its own kind. Else a trapping bounds check alone (SIGILL, kind 2).
    `bounds-strict` also checks the trailing array member of a struct, which is exactly MatIEC's
    `struct {T table[n];}` reached through a pointer; plain `bounds` leaves those unchecked.
    """
    return list(_check_flags())


@functools.cache
def _check_flags() -> tuple[str, ...]:
    for flags in ((f"-fsanitize=bounds-strict,{CHECKS}", "-fno-sanitize-recover=all"),
                  (f"-fsanitize=bounds,{CHECKS}", "-fno-sanitize-recover=all"),
                  ("-fsanitize=bounds-strict", "-fsanitize-undefined-trap-on-error"),
                  ("-fsanitize=bounds", "-fsanitize-trap=bounds"),
                  ("-fsanitize=bounds", "-fsanitize-undefined-trap-on-error")):
        if supports(flags):
            return flags
    return ()


def checks_undefined_values() -> bool:
    """Whether iec2c's C is stopped at shift counts and conversions that C leaves undefined."""
    return any(CHECKS in f for f in _check_flags())


def longest_function_lines(text: str) -> int:
    """Lines of the longest top-level brace block of a C text: from a line at column 0 that opens one
    ('{' alone, or a declaration ending in '{') to the next line that starts with '}'. Both backends
    write function bodies so."""
    longest, start = 0, None
    for i, line in enumerate(text.split("\n")):
        if start is None:
            if line[:1] not in ("", " ", "\t", "#", "/", "*", "}") and line.rstrip().endswith("{") or line == "{":
                start = i
        elif line[:1] == "}":
            longest = max(longest, i - start)
            start = None
    return longest


def size_flags(unit: Path, lines: int | None = None) -> list[str]:
    """Flags by the unit's size: -O0 for a unit longer than LARGE_UNIT_LINES or with a function longer
    than LONG_FUNCTION_LINES. `lines`: count these lines instead of the unit's own (the whole program's,
    for a unit cut from one program: cutting it does not change its optimisation level)."""
    try:
        text = Path(unit).read_text(errors="replace")
    except OSError:
        return []
    if lines is None:
        lines = text.count("\n")
    big = lines > LARGE_UNIT_LINES or longest_function_lines(text) > LONG_FUNCTION_LINES
    if not big:
        return []
    return ["-O0", *(LARGE_UNIT_MEMORY_FLAGS if supports(LARGE_UNIT_MEMORY_FLAGS) else ())]


def program_lines(units: list[Path]) -> int:
    """The lines of units cut from one program, together (size_flags' `lines`)."""
    total = 0
    for unit in units:
        try:
            total += Path(unit).read_bytes().count(b"\n")
        except OSError:
            pass
    return total


class Started:
    """One unit's gcc, started ahead of compile_shared (the glue's, while the ST is being translated)."""

    def __init__(self, unit: Path, obj: Path, argv: list[str], cwd: Path | None):
        self.unit, self.obj, self.argv = unit, obj, argv
        self.proc = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=cwd)

        self._result: subprocess.CompletedProcess | None = None

    def result(self) -> subprocess.CompletedProcess:
        if self._result is None:
            out, err = self.proc.communicate()
            self._result = subprocess.CompletedProcess(self.argv, self.proc.returncode, out, err)
        return self._result

    def cancel(self) -> None:
        """Stop it if it still runs (the build failed before linking)."""
        if self._result is None and self.proc.poll() is None:
            self.proc.kill()
        self.result()


def start(units: list[Path], objdir: Path, *, cwd: Path | None = None, extra_flags: list[str] = ()) -> list[Started]:
    """Start compiling units that include nothing generated (no -I) into objdir; compile_shared(started=)
    links them. Flags as compile_shared gives them."""
    cc = shlex.split(find_compiler().path)
    out = []
    for unit in units:
        obj = objdir / (Path(unit).stem + ".o")
        out.append(Started(unit, obj, [*cc, *BASE_FLAGS, *extra_flags, *size_flags(unit), "-c", str(unit),
                                       "-o", str(obj)], cwd))
    return out


def compile_shared(units: list[Path], output: Path, *, include_dirs: list[Path] = (),
                   unit_flags: dict[Path, list[str]] | None = None, cwd: Path | None = None,
                   extra_flags: list[str] = (), one_program: list[Path] = (),
                   started: list[Started] = (), link_flags: list[str] = ()) -> None:
    """Compile each unit (with its own extra flags) and link them into `output`, with the objects of the
    `started` compiles. `one_program`: units cut from one program, sized together (size_flags)."""
    cc = shlex.split(find_compiler().path)
    objdir = output.parent
    incs = [f"-I{d}" for d in include_dirs]
    together = program_lines(one_program) if len(one_program) > 1 else None
    jobs = []
    for unit in units:
        obj = objdir / (unit.stem + ".o")
        flags = (unit_flags or {}).get(unit, []) + size_flags(unit, together if unit in one_program else None)
        jobs.append((unit, obj, [*cc, *BASE_FLAGS, *extra_flags, *flags, *incs, "-c", str(unit), "-o", str(obj)]))

    def run(job):
        return job, subprocess.run(job[2], capture_output=True, text=True, cwd=cwd, check=False)

    with ThreadPoolExecutor(max_workers=max(1, min(len(jobs), os.cpu_count() or 1))) as pool:
        results = list(pool.map(run, jobs))
    results += [((s.unit, s.obj, s.argv), s.result()) for s in started]
    failed = [(job, proc) for job, proc in results if proc.returncode != 0]
    if failed:
        raise _error(failed)
    link = [*cc, *BASE_FLAGS, *extra_flags, *[str(obj) for (_, obj, _), _ in results], "-o", str(output),
            *link_flags, *LINK_FLAGS]
    proc = subprocess.run(link, capture_output=True, text=True, cwd=cwd, check=False)
    if proc.returncode != 0:
        raise _error([((None, None, link), proc)])


def _error(failed) -> CCompileError:
    diagnostics: list[str] = []
    text: list[str] = []
    for (_unit, _, argv), proc in failed:
        text.append(f"$ {shlex.join(argv)}\n{proc.stderr.strip()}")
        diagnostics += [line for line in proc.stderr.splitlines() if ": error:" in line or ": fatal error:" in line]
    return CCompileError("C compilation failed:\n" + "\n".join(text), diagnostics)
