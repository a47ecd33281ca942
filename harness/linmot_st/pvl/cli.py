"""`linmot-st pvl ...`: commands on PVL files.

    linmot-st pvl show FILE [-v]            a readable summary (errors as file:line messages)
    linmot-st pvl to-st FILE -o OUT.st      the commissioning dataset as ST data for the PLC (to_st.py)

Each command is one entry of `COMMANDS`: (name, function that adds its arguments, function that runs it).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path


def load_or_report(path: str, stream=None):
    """The PVL file for a command, or None after printing why not (its file:line errors and their count,
    or why it could not be read): the one way every command that takes a PVL file reports a bad one."""
    from .errors import PvlError
    from .parser import load_pvl

    stream = stream or sys.stderr
    try:
        return load_pvl(path)
    except PvlError as err:
        print(err, file=stream)
        print(f"{path}: {len(err.diagnostics)} error(s)", file=stream)
    except OSError as err:
        print(f"{path}: {err.strerror or err}", file=stream)
    return None


def _add_show(p: argparse.ArgumentParser) -> None:
    p.add_argument("file", metavar="FILE", help="a .pvl file")
    p.add_argument("-v", "--verbose", action="store_true",
                   help="list every parameter row (stringlets too), curve unit IDs and wizard data, CT parameters")


def _run_show(args: argparse.Namespace) -> int:
    from .show import summary

    pvl = load_or_report(args.file)
    if pvl is None:
        return 1
    sys.stdout.write(summary(pvl, verbose=args.verbose))
    return 0


def _add_to_st(p: argparse.ArgumentParser) -> None:
    from .to_st import DEFAULT_TYPE
    p.add_argument("file", metavar="FILE", help="a .pvl file")
    p.add_argument("-o", "--output", metavar="OUT.st", required=True, help="the ST file to write ('-' = stdout)")
    p.add_argument("--type", dest="type_name", default=DEFAULT_TYPE, metavar="NAME",
                   help=f"name of the generated ARRAY type (default {DEFAULT_TYPE})")


def _run_to_st(args: argparse.Namespace) -> int:
    from ..cliargs import check_output_file, error
    from .dataset import DatasetError
    from .to_st import read_st, to_st

    if args.output != "-":
        check_output_file(args.output, f"-o {args.output}")       # before any work; no folder is created
    pvl = load_or_report(args.file)
    if pvl is None:
        return 1
    try:
        text = to_st(pvl, args.type_name)
    except (DatasetError, ValueError) as err:
        error(args, str(err))
        return 1
    if args.output == "-":
        sys.stdout.write(text)
    else:
        out = Path(args.output)
        try:
            out.write_text(text)
        except OSError as exc:
            error(args, f"-o {args.output}: {exc.strerror or exc}")
            return 1
        print(f"{out}: {args.type_name}, {len(read_st(text)[1])} words", file=sys.stderr)
    return 0


COMMANDS = [
    ("show", "print a readable summary of a PVL file (errors as file:line messages)", _add_show, _run_show),
    ("to-st", "generate the commissioning dataset (ST data for the PLC) from a PVL file", _add_to_st, _run_to_st),
]


def register(subparsers) -> None:
    parser = subparsers.add_parser("pvl", help="LinMot PVL files: show a summary, generate the PLC's dataset (to-st)",
                                   description="Commands on LinMot PVL (Parameter Value List) files.")
    sub = parser.add_subparsers(dest="pvl_command", metavar="PVL_COMMAND")
    for name, help_text, add_arguments, run in COMMANDS:
        p = sub.add_parser(name, help=help_text, description=help_text)
        add_arguments(p)
        p.set_defaults(func=run)
    parser.set_defaults(func=lambda args: (parser.print_help(), 2)[1])
