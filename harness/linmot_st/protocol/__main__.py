"""python -m linmot_st.protocol --write | --check: regenerate, or verify, every file generated from the
catalogue (protocol/generate.py lists them)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .errors import describe
from .generate import REPO, check, write


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m linmot_st.protocol", description=__doc__.splitlines()[0])
    g = p.add_mutually_exclusive_group(required=True)
    g.add_argument("--write", action="store_true", help="rewrite every generated ST and docs file")
    g.add_argument("--check", action="store_true", help="exit 1, naming each generated file that differs")
    g.add_argument("--describe", type=lambda s: int(s, 0), metavar="ERRORID", help="print the text of an ErrorID")
    p.add_argument("--root", type=Path, default=REPO, help="the repository (default: this checkout)")
    args = p.parse_args(argv)
    if args.write:
        for path in write(args.root):
            print(f"wrote {path}")
        return 0
    if args.check:
        problems = check(args.root)
        for line in problems:
            print(line, file=sys.stderr)
        return 1 if problems else 0
    print(describe(args.describe))
    return 0


if __name__ == "__main__":
    sys.exit(main())
