"""`linmot-st export st OUT.st` and `linmot-st export plcopen OUT.xml`: the library for other PLC tools.

OUT `-` writes to standard output (the summary then goes to standard error). A file is written whole or
not at all: the text goes to a temporary file beside OUT, which then replaces OUT.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path


def _add_common(p: argparse.ArgumentParser) -> None:
    p.add_argument("--entry", metavar="FILE", default=None,
                   help="the ST entry file to export (default: st_lib/linmot.st of the current checkout)")


def _add_st(p: argparse.ArgumentParser) -> None:
    p.add_argument("out", metavar="OUT.st", help="file to write, or - for standard output")
    _add_common(p)


def _add_plcopen(p: argparse.ArgumentParser) -> None:
    p.add_argument("out", metavar="OUT.xml", help="file to write, or - for standard output")
    _add_common(p)
    from ..cliargs import existing_file
    p.add_argument("--schema", metavar="XSD", default=None, type=existing_file("schema"),
                   help="validate the result against this XSD (e.g. PLCopen's tc6_xml_v201.xsd) before writing")
    p.add_argument("--no-plaintext-interface", dest="plaintext", action="store_false",
                   help="leave out the declarations as written (CODESYS's interfaceasplaintext addData)")


class _WriteError(Exception):
    pass


def write_output(out: str, data: bytes) -> str:
    """Write data to `out` (or stdout for `-`) atomically; returns the name written."""
    if out == "-":
        sys.stdout.buffer.write(data)
        sys.stdout.flush()
        return "<stdout>"
    from ..cliargs import UsageError, check_output_file
    path = Path(out).expanduser()
    try:
        check_output_file(out, out)
    except UsageError as exc:
        raise _WriteError(str(exc)) from None
    folder = path.parent if str(path.parent) else Path(".")
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", dir=folder)
    except OSError as exc:
        raise _WriteError(f"{out}: cannot write in {folder}: {exc.strerror or exc}") from None
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
        if path.exists():
            os.chmod(tmp, path.stat().st_mode & 0o777)
        else:
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except OSError as exc:
        Path(tmp).unlink(missing_ok=True)
        raise _WriteError(f"{out}: cannot write: {exc.strerror or exc}") from None
    return str(path)


def _summary(lib, name: str, data: bytes) -> str:
    c = lib.counts
    words = [("types", "data type"), ("functions", "function"), ("function_blocks", "function block"),
             ("programs", "program"), ("configurations", "configuration")]
    parts = [f"{c[key]} {word}{'' if c[key] == 1 else 's'}" for key, word in words
             if c[key] or key in ("types", "functions", "function_blocks")]
    lines = data.count(b"\n")
    return (f"wrote {name}: {', '.join(parts)} from {len(lib.files)} source files; "
            f"{len(data):,} bytes, {lines:,} lines")


def _report(out: str, message: str) -> None:
    print(message, file=sys.stderr if out == "-" else sys.stdout)


def _check_out(args: argparse.Namespace) -> None:
    """The output checked before any work (a UsageError: exit 2)."""
    from ..cliargs import check_output_file
    if args.out != "-":
        check_output_file(args.out, args.out)


def _run_st(args: argparse.Namespace) -> int:
    from ..cliargs import error
    from .library import ExportError
    from .st import export_st

    _check_out(args)
    try:
        result = export_st(args.entry)
        data = result.text.encode("utf-8")
        name = write_output(args.out, data)
    except (ExportError, _WriteError) as exc:
        error(args, str(exc))
        return 1
    _report(args.out, _summary(result.library, name, data))
    return 0


def _run_plcopen(args: argparse.Namespace) -> int:
    from ..cliargs import error
    from .library import ExportError
    from .plcopen import export_plcopen, validate

    _check_out(args)
    try:
        data, lib = export_plcopen(args.entry, plaintext_interfaces=args.plaintext)
        if args.schema:
            errors = validate(data, args.schema)
            if errors:
                raise ExportError(f"the XML does not validate against {args.schema} (nothing written):\n"
                                  + "\n".join(errors[:20]))
        name = write_output(args.out, data)
    except (ExportError, _WriteError) as exc:
        error(args, str(exc))
        return 1
    message = _summary(lib, name, data)
    if args.schema:
        message += f"; valid against {args.schema}"
    _report(args.out, message)
    return 0


COMMANDS = [
    ("st", "the whole library as one ST file (Beremiz, OpenPLC)", _add_st, _run_st),
    ("plcopen", "the library as PLCopen XML, TC6 2.01 (CODESYS, TwinCAT, Beremiz)", _add_plcopen, _run_plcopen),
]


def register(subparsers) -> None:
    parser = subparsers.add_parser("export", help="the ST library for other PLC tools: st, plcopen",
                                   description="Export the ST library for import into PLC programming tools "
                                               "(docs/import.md).")
    sub = parser.add_subparsers(dest="export_command", metavar="FORMAT")
    for name, help_text, add_arguments, run in COMMANDS:
        p = sub.add_parser(name, help=help_text, description=help_text)
        add_arguments(p)
        p.set_defaults(func=run)
    parser.set_defaults(func=lambda args: (parser.print_help(), 2)[1])
