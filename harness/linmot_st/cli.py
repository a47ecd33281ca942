"""The `linmot-st` command. Each subcommand lives in the module of its concern and registers itself.

A module listed here provides `register(subparsers)`, which adds its parser and sets
`func=callable(args) -> int` as the default. Modules are imported only when the command line is parsed,
and each keeps its heavy imports inside its functions so that `linmot-st --help` stays fast.
"""

from __future__ import annotations

import argparse
import importlib
import sys

# subcommand module paths, in the order `--help` lists them
SUBCOMMAND_MODULES = [
    "linmot_st.toolchain.cli",     # build, run
    "linmot_st.emulator.cli",      # emulate
    "linmot_st.pvl.cli",           # pvl show, pvl to-st
    "linmot_st.jobs.commission.cli",    # commission
    "linmot_st.jobs.motion.cli",        # motion
    "linmot_st.export.cli",        # export st, export plcopen
    "linmot_st.userproject.cli",   # init
    "linmot_st_bench.runner",      # bench (a checkout only: the benches are not in the wheel)
]


class Parser(argparse.ArgumentParser):
    """argparse with the commands' one error style: a single line `linmot-st CMD: error: ...`, exit 2
    (the subcommands' parsers are of this class too: add_subparsers takes the parent's class)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {message} (see {self.prog} --help)\n")


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(prog="linmot-st", description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name in SUBCOMMAND_MODULES:
        try:
            module = importlib.import_module(name)
        except ModuleNotFoundError as exc:
            if not name.startswith(exc.name or "\0"):  # a missing dependency inside the module is an error
                raise
            continue
        module.register(sub)
    return parser


def _leaf_parsers(parser: argparse.ArgumentParser):
    """Every parser that runs a command (the subcommands, and theirs)."""
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                yield sub
                yield from _leaf_parsers(sub)


def main(argv: list[str] | None = None) -> int:
    try:
        return _main(argv)
    except KeyboardInterrupt:     # Ctrl-C before a command's own handling (while starting): no traceback
        print("linmot-st: interrupted", file=sys.stderr)
        return 130


def _main(argv: list[str] | None) -> int:
    from .cliargs import UsageError, error

    parser = build_parser()
    for sub in _leaf_parsers(parser):
        sub.set_defaults(_prog=sub.prog)          # `linmot-st CMD`, for the common error style
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except UsageError as exc:                     # a bad argument found by a command's own checks
        error(args, str(exc))
        return 2


if __name__ == "__main__":
    sys.exit(main())
