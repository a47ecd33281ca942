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
    "linmot_st.commission.cli",    # commission
    "linmot_st.motion.cli",        # motion
    "linmot_st.export.cli",        # export st, export plcopen
    "linmot_st.userproject.cli",   # init
    "linmot_st.bench",             # bench
]


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="linmot-st", description=__doc__.splitlines()[0])
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


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    return int(args.func(args) or 0)


if __name__ == "__main__":
    sys.exit(main())
