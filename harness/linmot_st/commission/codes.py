"""ErrorIDs of the commissioning FB that the library's table (linmot_st.errors) does not have, and the
decoding of every ErrorID the FB reports.

Group 16#06xx (the library uses 01xx..05xx). This table generates `st_lib/commission/errors.st`
(the struct `T_LmComErrorIds`, the library's pattern for ErrorID constants):

    python -m linmot_st.commission.codes --write      # rewrite st_lib/commission/errors.st
    python -m linmot_st.commission.codes --check      # exit 1 if it differs

`tests/test_commission_st.py` fails if they diverge.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from linmot_st import errors as lib_errors
from linmot_st.errors import ErrorDef

COMMISSION_ERRORS: tuple[ErrorDef, ...] = (
    ErrorDef("DatasetInvalid", 0x0601,
             "commissioning dataset malformed: magic word, format version, counts or record order wrong "
             "(FailStep = the word index)"),
    ErrorDef("ResetNeedsFlash", 0x0602,
             "reset requested without the flash save while the dataset holds curves or command-table entries "
             "(the reset would lose them)"),
    ErrorDef("VerifyMismatch", 0x0603,
             "read-back differs from the dataset (FailItem, FailStep, FailExpected, FailActual say where)"),
)

BY_VALUE = {e.value: e for e in COMMISSION_ERRORS}
BY_NAME = {e.name: e for e in COMMISSION_ERRORS}

REPO = Path(__file__).resolve().parents[3]
ST_FILE = REPO / "st_lib" / "commission" / "errors.st"


def describe(error_id: int, abort_code: int = 0) -> str:
    """Text for any ErrorID the commissioning FB reports (the library's and this group)."""
    e = BY_VALUE.get(error_id)
    if e is not None:
        return f"16#{error_id:04X} {e.text}"
    return lib_errors.describe(error_id, abort_code)


def name_of(error_id: int) -> str:
    e = BY_VALUE.get(error_id)
    return e.name if e is not None else lib_errors.name_of(error_id)


def render_st() -> str:
    width = max(len(e.name) for e in COMMISSION_ERRORS)
    lines = [
        "(* ErrorIDs of FB_LmCommission beyond the library's T_LmErrorIds (group 16#06xx). GENERATED from",
        "   harness/linmot_st/commission/codes.py by `python -m linmot_st.commission.codes --write`. *)",
        "TYPE",
        "  T_LmComErrorIds : STRUCT",
    ]
    for e in COMMISSION_ERRORS:
        lines.append(f"    {e.name.ljust(width)} : WORD := 16#{e.value:04X};  (* {e.text} *)")
    lines += ["  END_STRUCT;", "END_TYPE", ""]
    return "\n".join(lines)


def check() -> list[str]:
    clash = [e.name for e in COMMISSION_ERRORS if e.value in lib_errors.BY_VALUE or e.name in lib_errors.BY_NAME]
    problems = [f"{n}: value or name already in linmot_st.errors" for n in clash]
    if not ST_FILE.exists() or ST_FILE.read_text() != render_st():
        problems.append(f"{ST_FILE} differs from the table in {__name__}")
    return problems


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m linmot_st.commission.codes", description=__doc__.splitlines()[0])
    g = p.add_mutually_exclusive_group(required=True)
    g.add_argument("--write", action="store_true")
    g.add_argument("--check", action="store_true")
    args = p.parse_args(argv)
    if args.write:
        ST_FILE.parent.mkdir(parents=True, exist_ok=True)
        ST_FILE.write_text(render_st())
        return 0
    problems = check()
    for line in problems:
        print(line, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
