"""`linmot-st build` and `linmot-st run`."""

from __future__ import annotations

import argparse
import sys


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
    r.add_argument("--cycles", type=int, required=True, metavar="N", help="scans to run")
    r.add_argument("--watch", nargs="+", default=[], metavar="VAR",
                   help="IEC paths to print (a unique suffix is enough, e.g. INST0.X)")
    r.add_argument("--set", action="append", default=[], metavar="VAR=VALUE",
                   help="write a variable before the first scan (repeatable); VALUE is a Python literal")
    r.add_argument("--every", type=int, default=0, metavar="K",
                   help="also print the watched variables every K scans")
    r.set_defaults(func=cmd_run)


def _common(p: argparse.ArgumentParser) -> None:
    p.add_argument("path", metavar="PATH", help="a .st file or a project folder (entry file plc.st)")
    p.add_argument("--root", metavar="DIR", default=None,
                   help="the folder include paths resolve against (default: the nearest ancestor holding "
                        "st_lib/linmot.st, else the current folder)")
    p.add_argument("--backend", choices=["auto", "matiec", "builtin"], default="auto",
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

    from . import TRACEBACK_ENV, CompileError, InternalCompilerError, SourcePathError, build, choose_backend
    chosen = choose_backend(args.backend)
    if args.backend == "auto":
        why = "iec2c found" if chosen == "matiec" else "iec2c not found"
        print(f"backend: {chosen} (auto: {why})", file=sys.stderr)
    try:
        res = build(args.path, backend=args.backend, out=out, use_cache=use_cache, root=args.root)
    except OSError as exc:      # the cache or output folder cannot be written, a source cannot be read...
        print(f"error: {exc}", file=sys.stderr)
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
    try:
        res = _build(args, out=args.out, use_cache=not args.no_cache)
    except _Failed as failed:
        return failed.code
    how = "cached" if res.cached else "compiled"
    print(f"{res.entry}: {how} with {res.backend} in {res.seconds:.3f} s")
    print(f"  library:  {res.library}")
    print(f"  manifest: {res.manifest}")
    return 0


def _parse_value(text: str):
    import ast
    try:
        return ast.literal_eval(text)
    except (ValueError, SyntaxError):
        return text   # a bare word: an enum value or a string


def cmd_run(args) -> int:
    from ..plc import PathError, Plc, PlcFault
    if args.cycles < 0:
        print("error: --cycles must be >= 0", file=sys.stderr)
        return 2
    try:
        res = _build(args)
    except _Failed as failed:
        return failed.code
    plc = Plc(res)
    try:
        watched = [plc.var(w) for w in args.watch]
        for item in args.set:
            name, sep, value = item.partition("=")
            if not sep:
                print(f"error: --set {item!r}: expected VAR=VALUE", file=sys.stderr)
                return 2
            plc[name.strip()] = _parse_value(value.strip())
    except (PathError, TypeError, ValueError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2

    def show() -> None:
        print(f"scan {plc.scan_count}  t = {plc.time_ns / 1e6:g} ms")
        for v in watched:
            print(f"  {v.path} = {v.value!r}")

    try:
        done = 0
        step = args.every if args.every > 0 else args.cycles
        while done < args.cycles:
            n = min(step, args.cycles - done)
            plc.step(n)
            done += n
            if args.every > 0 and done < args.cycles:
                show()
    except PlcFault as fault:
        print(str(fault), file=sys.stderr)
        show()
        return 3
    show()
    return 0
