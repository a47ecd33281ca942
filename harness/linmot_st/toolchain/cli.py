"""`linmot-st build` and `linmot-st run`."""

from __future__ import annotations

import argparse
import sys
import time

from ..cliargs import int_range, non_negative_seconds
from .backends import CHOICES

RUN_CHUNK_S = 0.05      # `run` steps in C for about this long between two checks for Ctrl-C


def register(subparsers) -> None:
    p = subparsers.add_parser("build", help="compile ST (a .st file or a project folder) into a PLC library",
                              description="Compile a .st file, or a project folder whose entry file is plc.st, "
                                          "into a shared library and its manifest (cached by content).")
    _common(p)
    p.add_argument("--out", metavar="DIR", help="also copy the library, manifest.json and the generated C here")
    p.add_argument("--no-cache", action="store_true", help="rebuild even if an identical build is cached")
    p.set_defaults(func=cmd_build)

    r = subparsers.add_parser("run", help="build, then run a PLC for N scans in virtual time",
                              description="Build (cached), load and run the PLC scan by scan in virtual time, "
                                          "then print the watched variables.")
    _common(r)
    r.add_argument("--cycles", type=int_range(0), required=True, metavar="N", help="scans to run")
    r.add_argument("--watch", nargs="+", action="extend", default=[], metavar="VAR",
                   help="IEC paths to print (a unique suffix is enough, e.g. INST0.X); repeatable")
    r.add_argument("--set", action="append", default=[], metavar="VAR=VALUE",
                   help="write a variable before the first scan (repeatable); VALUE is a Python literal")
    r.add_argument("--every", type=int_range(0), default=0, metavar="K",
                   help="also print the watched variables every K scans")
    r.add_argument("--watchdog", type=non_negative_seconds, default=1.0, metavar="S",
                   help="a scan that takes more than S seconds of CPU time ends the run as a PLC fault naming "
                        "its POU (default 1; 0 = off)")
    r.set_defaults(func=cmd_run)


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("path", metavar="PATH", help="a .st file or a project folder (entry file plc.st)")
    p.add_argument("--root", metavar="DIR", default=None,
                   help="the folder include paths resolve against (default: the nearest ancestor holding "
                        "st_lib/linmot.st, else the current folder)")
    p.add_argument("--backend", choices=CHOICES, default="auto",
                   help="auto: matiec when iec2c is found, else builtin (default)")
    p.add_argument("--verbose", action="store_true",
                   help="on an internal compiler error, also print its traceback (or set LINMOT_ST_TRACEBACK=1)")


class _Failed(Exception):
    """The build failed; `code` is the exit status (1 compile error, 2 bad path)."""

    def __init__(self, code: int):
        self.code = code


def _build(args, out=None, use_cache=True):
    """The build result; raises _Failed after printing the diagnostics."""
    import os

    from . import TRACEBACK_ENV, CompileError, InternalCompilerError, SourcePathError, build
    from .backends import AUTO, auto_note, choose
    if args.backend == AUTO:
        chosen = choose(args.backend)
        print(f"backend: {chosen.name} (auto: {auto_note(chosen)})", file=sys.stderr)
    try:
        res = build(args.path, backend=args.backend, out=out, use_cache=use_cache, root=args.root)
    except OSError as exc:      # the cache or output folder cannot be written, a source cannot be read...
        from ..cliargs import error
        error(args, str(exc))
        raise _Failed(1) from None
    except CompileError as exc:
        for line in exc.diagnostics:
            print(line, file=sys.stderr)
        if isinstance(exc, InternalCompilerError) and exc.__cause__ is not None and (
                getattr(args, "verbose", False) or os.environ.get(TRACEBACK_ENV, "") not in ("", "0")):
            import traceback
            traceback.print_exception(type(exc.__cause__), exc.__cause__, exc.__cause__.__traceback__,
                                      file=sys.stderr)
        raise _Failed(2 if isinstance(exc, SourcePathError) else 1) from None
    for w in res.warnings:
        print(f"warning: {w}", file=sys.stderr)
    return res


def cmd_build(args) -> int:
    if args.out:
        from ..cliargs import check_output_folder
        check_output_folder(args.out, f"--out {args.out}")
    try:
        res = _build(args, out=args.out, use_cache=not args.no_cache)
    except _Failed as failed:
        return failed.code
    how = "cached" if res.cached else "compiled"
    print(f"{res.entry}: {how} with {res.backend} in {res.seconds:.3f} s")
    print(f"  library:  {res.library}")
    print(f"  manifest: {res.manifest}")
    for report in AFTER_BUILD.get(res.backend, ()):
        report(args)
    return 0


def _report_for_semantics(args) -> None:
    """Which FOR semantics this iec2c has, and the program's FOR loops that it changes (spec/matiec.md
    7.1): users' iec2c differ there."""
    from . import cache as _cache
    from . import sources as _sources
    from .matiec import for_loops, for_semantics
    src = _sources.collect(args.path, root=args.root)
    try:
        sem = for_semantics.probe(_cache.default_dir(src.root, src.writable_tree))
    except Exception as exc:        # the probe is advice: a build that worked is not failed by it
        print(f"warning: the FOR semantics of this iec2c could not be measured: {exc}", file=sys.stderr)
        return
    print(f"  {sem.describe()}")
    for line in for_loops.warnings(src.files, src.root, src.search, sem):
        print(line, file=sys.stderr)


# what `build` adds to its report, by backend: users' iec2c differ in FOR
AFTER_BUILD = {"matiec": [_report_for_semantics]}


def _parse_value(text: str):
    import ast
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return text   # a bare word: an enum value or a string


def cmd_run(args) -> int:
    from ..cliargs import UsageError, error
    from ..plc import PathError, Plc, PlcFault
    for item in args.set:
        if "=" not in item:
            raise UsageError(f"--set {item!r}: expected VAR=VALUE")
    try:
        res = _build(args)
    except _Failed as failed:
        return failed.code
    plc = Plc(res)
    plc.watchdog_ns = int(args.watchdog * 1e9)
    try:
        watched = [plc.var(w) for w in args.watch]
        for item in args.set:
            name, _, value = item.partition("=")
            plc[name.strip()] = _parse_value(value.strip())
    except (PathError, TypeError, ValueError) as exc:
        raise UsageError(str(exc)) from None

    def show() -> None:
        print(f"scan {plc.scan_count}  t = {plc.time_ns / 1e6:g} ms")
        for v in watched:
            print(f"  {v.path} = {v.value!r}")

    # scans go in chunks of about RUN_CHUNK_S, so that Ctrl-C (KeyboardInterrupt, raised between two calls
    # into C) stops the run promptly; a scan that never ends is the watchdog's
    done, chunk, next_show = 0, 100, args.every or None
    try:
        while done < args.cycles:
            n = min(chunk, args.cycles - done, (next_show - done) if next_show else args.cycles)
            t0 = time.perf_counter()
            plc.step(n)
            done += n
            spent = time.perf_counter() - t0
            chunk = max(1, min(1_000_000, int(chunk * RUN_CHUNK_S / spent) if spent > 0 else chunk * 2))
            if next_show and done == next_show:
                if done < args.cycles:
                    show()
                next_show += args.every
    except PlcFault as fault:
        error(args, str(fault))
        show()
        return 3
    except KeyboardInterrupt:
        error(args, f"interrupted after {plc.scan_count} of {args.cycles} scans")
        show()
        return 130
    show()
    return 0
