"""The ST assertion library (st_lib/stunit/stunit.st) and how a failed assertion reads in Python.

One table here is the single source of both: which elementary types have an AssertEqual_<T> and an
AssertWithin_<T>, and in which fields of T_StUnit each keeps the expected and the actual value of a
failure. `python -m linmot_st.plctest.stunit_lib --write` writes the ST file; a test checks it is in sync.

The library stays inside MatIEC's subset: MatIEC has no generic parameters in user POUs (ANY), so there is
one FUNCTION per type; a FUNCTION cannot reach a global, so each takes the test's record T (VAR_IN_OUT)
first (a local of the test: MatIEC generates C that does not compile for a VAR_EXTERNAL passed on as a
FUNCTION's VAR_IN_OUT inside an FB); and a FUNCTION call cannot stand as a statement, so a test writes `Ok := AssertTrue(StUnit, ...)`
or `IF NOT AssertEqual_DINT(StUnit, ...) THEN RETURN; END_IF;`. No FOR loop (MatIEC HEAD's FOR defect).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass

from linmot_st import resources

ST_PATH = "st_lib/stunit/stunit.st"     # relative to the library tree
BYTES_MAX = 64                           # T_StBytes : ARRAY[1..64] OF BYTE


@dataclass(frozen=True)
class Family:
    """Where T_StUnit keeps the values of a failed assertion of the types of this family."""
    field: str            # ExpInt/ActInt...
    st_type: str          # the field's type
    to_field: str         # conversion from the asserted type: '{}_TO_LINT' or '' (the same type)


FAMILIES = {
    "bool": Family("Bool", "BOOL", ""),
    "int": Family("Int", "LINT", "{}_TO_LINT"),
    "uns": Family("Uns", "ULINT", "{}_TO_ULINT"),
    "bits": Family("Uns", "ULINT", "{}_TO_ULINT"),       # shown in hex
    "real": Family("Real", "LREAL", "{}_TO_LREAL"),
    "time": Family("Time", "TIME", ""),
    "text": Family("Text", "STRING", ""),
}
TYPES = {
    "BOOL": "bool", "SINT": "int", "INT": "int", "DINT": "int", "LINT": "int",
    "USINT": "uns", "UINT": "uns", "UDINT": "uns", "ULINT": "uns",
    "BYTE": "bits", "WORD": "bits", "DWORD": "bits", "LWORD": "bits",
    "REAL": "real", "LREAL": "real", "TIME": "time", "STRING": "text",
}
WITHIN = ["SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "ULINT", "REAL", "LREAL", "TIME"]


def _conv(type_name: str, expr: str) -> str:
    fam = FAMILIES[TYPES[type_name]]
    return fam.to_field.format(type_name) + f"({expr})" if fam.to_field and type_name != fam.st_type else expr


HEADER = f"""(* stunit: assertions for tests written in ST, run by the linmot-st pytest plugin (docs/testing.md).
   GENERATED from harness/linmot_st/plctest/stunit_lib.py by `python -m linmot_st.plctest.stunit_lib --write`:
   edit the Python, not this file. Needs nothing else; the plugin includes it before a test file.
   Every assertion is a FUNCTION returning TRUE when it holds. Its first argument is the test's record, a
   local variable `StUnit : T_StUnit` of the test FB or PROGRAM (the plugin reads it; a helper FB takes it
   VAR_IN_OUT); its last, the message that names the assertion in a failure: give each assertion its own,
   the plugin finds the failed assertion's line by it. MatIEC allows a FUNCTION call only inside an
   expression:
     Ok := AssertEqual_DINT(StUnit, 100, Position, 'position after the move');
     IF NOT AssertTrue(StUnit, Axis.Ready, 'axis ready') THEN RETURN; END_IF;
   A failed assertion fails the test at the end of the scan; the first failure is the one reported. *)
TYPE
  T_StBytes : ARRAY[1..{BYTES_MAX}] OF BYTE;
END_TYPE

TYPE
  T_StUnit : STRUCT
    Asserts : UDINT;              (* assertions evaluated *)
    Failures : UDINT;             (* of them failed *)
    Check : STRING;               (* the first failure: the assertion's name, *)
    Msg : STRING;                 (* its message, *)
    ExpBool : BOOL;               (* and the values it compared, in the fields of their type's family *)
    ActBool : BOOL;
    ExpInt : LINT;
    ActInt : LINT;
    ExpUns : ULINT;
    ActUns : ULINT;
    ExpReal : LREAL;
    ActReal : LREAL;
    TolReal : LREAL;
    ExpTime : TIME;
    ActTime : TIME;
    TolTime : TIME;
    TolInt : LINT;
    TolUns : ULINT;
    ExpText : STRING;
    ActText : STRING;
    ExpBytes : T_StBytes;
    ActBytes : T_StBytes;
    Count : INT;                  (* bytes compared *)
    Index : INT;                  (* the first that differs *)
  END_STRUCT;
END_TYPE

FUNCTION StUnit_Fail : BOOL
  (* counts an assertion; TRUE when it failed and is the test's first failure (the caller then records
     the values it compared) *)
  VAR_IN_OUT
    T : T_StUnit;
  END_VAR
  VAR_INPUT
    Ok : BOOL;
    Check : STRING;
    Msg : STRING;
  END_VAR
  T.Asserts := T.Asserts + 1;
  StUnit_Fail := FALSE;
  IF NOT Ok THEN
    T.Failures := T.Failures + 1;
    IF T.Failures = 1 THEN
      T.Check := Check;
      T.Msg := Msg;
      StUnit_Fail := TRUE;
    END_IF;
  END_IF;
END_FUNCTION
"""


def _function(name: str, doc: str, inputs: list[tuple[str, str]], locals_: list[tuple[str, str]],
              body: list[str], record: list[str], in_outs: list[tuple[str, str]] = ()) -> str:
    lines = [f"FUNCTION {name} : BOOL", f"  (* {doc} *)", "  VAR_IN_OUT", "    T : T_StUnit;",
             *[f"    {n} : {t};" for n, t in in_outs], "  END_VAR",
             "  VAR_INPUT", *[f"    {n} : {t};" for n, t in inputs], "    Msg : STRING;", "  END_VAR",
             "  VAR", "    Ok : BOOL;", *[f"    {n} : {t};" for n, t in locals_], "  END_VAR",
             *[f"  {b}" for b in body], f"  IF StUnit_Fail(T, Ok, '{name}', Msg) THEN",
             *[f"    {r}" for r in record], "  END_IF;", f"  {name} := Ok;", "END_FUNCTION", ""]
    return "\n".join(lines)


def _record(type_name: str) -> list[str]:
    f = FAMILIES[TYPES[type_name]].field
    return [f"T.Exp{f} := {_conv(type_name, 'Expected')};", f"T.Act{f} := {_conv(type_name, 'Actual')};"]


def render_st() -> str:
    out = [HEADER]
    out.append(_function("AssertTrue", "TRUE when Condition is TRUE", [("Condition", "BOOL")], [],
                         ["Ok := Condition;"], ["T.ExpBool := TRUE;", "T.ActBool := Condition;"]))
    out.append(_function("AssertFalse", "TRUE when Condition is FALSE", [("Condition", "BOOL")], [],
                         ["Ok := NOT Condition;"], ["T.ExpBool := FALSE;", "T.ActBool := Condition;"]))
    for t in TYPES:
        out.append(_function(f"AssertEqual_{t}", "TRUE when Actual = Expected",
                             [("Expected", t), ("Actual", t)], [], ["Ok := Actual = Expected;"], _record(t)))
    for t in WITHIN:
        fam = FAMILIES[TYPES[t]]
        # |Actual - Expected| <= Tolerance, computed without leaving the type (an unsigned type cannot go
        # below zero, so the larger minus the smaller)
        body = ["IF Actual > Expected THEN", "  Diff := Actual - Expected;", "ELSE", "  Diff := Expected - Actual;",
                "END_IF;", "Ok := Diff <= Tolerance;"]
        tol = f"T.Tol{fam.field} := {_conv(t, 'Tolerance')};"
        out.append(_function(f"AssertWithin_{t}", "TRUE when Actual is within Tolerance of Expected",
                             [("Expected", t), ("Actual", t), ("Tolerance", t)], [("Diff", t)], body,
                             _record(t) + [tol]))
    out.append(_function(
        "AssertEqual_Bytes", f"TRUE when the first Count (0..{BYTES_MAX}) bytes of Actual equal those of Expected "
        "(arrays are VAR_IN_OUT: MatIEC cannot pass an ARRAY as a FUNCTION's VAR_INPUT)",
        [("Count", "INT")], [("I", "INT")],
        [f"Ok := Count >= 0 AND Count <= {BYTES_MAX};", "I := 1;", "WHILE Ok AND I <= Count DO",
         "  IF Expected[I] <> Actual[I] THEN", "    Ok := FALSE;", "  ELSE", "    I := I + 1;", "  END_IF;",
         "END_WHILE;"],
        ["T.ExpBytes := Expected;", "T.ActBytes := Actual;", "T.Count := Count;", "T.Index := I;"],
        in_outs=[("Expected", "T_StBytes"), ("Actual", "T_StBytes")]))
    return "\n".join(out)


# ---- reading a failure -----------------------------------------------------------------------------------

def describe_failure(rec: dict) -> str:
    """'AssertEqual_DINT: expected 100, actual 97' from the T_StUnit record as the loader reads it."""
    check = rec.get("CHECK", "")
    kind, _, type_name = check.partition("_")
    if check in ("AssertTrue", "AssertFalse"):
        return f"{check}: the condition is {'TRUE' if rec['ACTBOOL'] else 'FALSE'}"
    if type_name == "Bytes":
        n, i = rec["COUNT"], rec["INDEX"]
        if not 0 <= n <= BYTES_MAX:
            return f"{check}: Count {n} is outside 0..{BYTES_MAX}"
        exp, act = bytes(rec["EXPBYTES"][:n]), bytes(rec["ACTBYTES"][:n])
        return (f"{check}: byte {i} of {n} differs: expected {exp.hex(' ').upper()}, "
                f"actual {act.hex(' ').upper()}")
    family = TYPES.get(type_name.upper())
    if family is None:
        return check or "assertion failed"
    f = FAMILIES[family].field.upper()
    exp, act = _show(family, rec[f"EXP{f}"]), _show(family, rec[f"ACT{f}"])
    text = f"{check}: expected {exp}, actual {act}"
    if kind == "AssertWithin":
        text += f", tolerance {_show(family, rec[f'TOL{f}'])}"
    return text


def _show(family: str, v) -> str:
    if family == "bits":
        return f"16#{v:X}"
    if family == "time":
        return _time_literal(v)
    if family == "bool":
        return "TRUE" if v else "FALSE"
    return repr(v) if family == "text" else str(v)


def _time_literal(ns: int) -> str:
    sign, ns = ("-", -ns) if ns < 0 else ("", ns)
    if ns % 1_000_000 == 0:
        return f"{sign}T#{ns // 1_000_000}ms"
    return f"{sign}T#{ns / 1e6:g}ms"


# ---- the generated file --------------------------------------------------------------------------------

def st_file():
    return resources.library_tree() / ST_PATH


def check() -> list[str]:
    path = st_file()
    if not path.is_file() or path.read_text() != render_st():
        return [f"{path} differs from {__name__}: run python -m {__name__} --write"]
    return []


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog=f"python -m {__name__}", description=__doc__.splitlines()[0])
    g = p.add_mutually_exclusive_group(required=True)
    g.add_argument("--write", action="store_true", help=f"rewrite {ST_PATH}")
    g.add_argument("--check", action="store_true", help="exit 1 if the file differs")
    args = p.parse_args(argv)
    if args.write:
        st_file().parent.mkdir(parents=True, exist_ok=True)
        st_file().write_text(render_st())
        return 0
    problems = check()
    for line in problems:
        print(line, file=sys.stderr)
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
