"""The builtin compiler's standard functions against MatIEC's library: every overload MatIEC declares in
lib/standard_functions.txt must type-check, and compile, with the builtin compiler (MatIEC installed only).
The values are compared by the conformance suite (tests/conformance/cases/std_*, conv_*)."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from linmot_st.toolchain.builtin import BuiltinCompileError, check_text, stdfuncs
from linmot_st.toolchain.testing import requires_matiec

ELEMENTARY = ["BOOL", "SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "ULINT", "BYTE", "WORD", "DWORD",
              "LWORD", "REAL", "LREAL", "TIME", "DATE", "TOD", "DT", "STRING"]
SIGNATURE = re.compile(r"^FUNCTION (\w+) : (\w+) VAR_INPUT (.*?) END_VAR", re.M)


def matiec_signatures() -> list[tuple[str, str, list[str]]]:
    from linmot_st.toolchain import matiec
    tool = matiec.find()
    text = (tool.lib / "standard_functions.txt").read_text()
    out = []
    for name, ret, params in SIGNATURE.findall(text):
        types = []
        for decl in params.split(";"):
            decl = decl.strip()
            if not decl:
                continue
            names, typ = decl.rsplit(":", 1)
            extensible = ".." in names
            types += [typ.strip()] * (2 if extensible else 1)
        out.append((name, ret, types))
    return out


def call_statement(name: str, ret: str, params: list[str]) -> str:
    args = ", ".join(f"v_{t}" for t in params)
    return f"  v_{ret} := {name}({args});"


def program(statements: list[str]) -> str:
    decls = " ".join(f"v_{t} : {t};" for t in ELEMENTARY)
    return f"PROGRAM p_std\n  VAR {decls} END_VAR\n" + "\n".join(statements) + "\nEND_PROGRAM\n"


@requires_matiec
def test_every_matiec_standard_function_type_checks():
    sigs = matiec_signatures()
    assert len(sigs) > 1500
    # declared by MatIEC's library but absent from its C headers: refused by the builtin compiler too
    assert stdfuncs.MISSING_IN_MATIEC_C <= {name for name, _, _ in sigs}
    sigs = [s for s in sigs if s[0] not in stdfuncs.MISSING_IN_MATIEC_C]
    # overloads whose C iec2c names wrongly (a shift of a BOOL): refused, as MatIEC's C cannot build them
    absent = [s for s in sigs if stdfuncs.missing_overload_in_matiec_c(s[0], s[2])]
    assert len(absent) == 4 * 8
    for name, ret, params in absent:
        with pytest.raises(BuiltinCompileError, match="defines no shift or rotate of a BOOL"):
            check_text(program([call_statement(name, ret, params)]), "std.st")
    sigs = [s for s in sigs if s not in absent]
    missing = sorted({name for name, _, _ in sigs if stdfuncs.lookup(name) is None})
    assert not missing, f"standard functions MatIEC has and the builtin compiler lacks: {missing}"
    rejected = []
    for name, ret, params in sigs:
        try:
            check_text(program([call_statement(name, ret, params)]), "std.st")
        except BuiltinCompileError as exc:
            rejected.append(f"{name}({', '.join(params)}) : {ret}: {exc.diagnostics[0].message}")
    assert not rejected, "overloads the builtin compiler rejects:\n" + "\n".join(rejected[:40])


@requires_matiec
def test_every_matiec_standard_function_compiles(tmp_path: Path):
    """All overloads in one program, through gcc: the code generator has C for each of them."""
    from linmot_st.toolchain.testing import build_text
    statements = [call_statement(n, r, p) for n, r, p in matiec_signatures()
                  if n not in stdfuncs.MISSING_IN_MATIEC_C and not stdfuncs.missing_overload_in_matiec_c(n, p)]
    src = program(statements) + ("CONFIGURATION c\n  RESOURCE r ON PLC\n    TASK t(INTERVAL := T#10ms, PRIORITY := 0);\n"
                                 "    PROGRAM i WITH t : p_std;\n  END_RESOURCE\nEND_CONFIGURATION\n")
    res = build_text(src, tmp_path, "builtin")
    from linmot_st.plc import Plc
    Plc(res)        # loads; not run: with all inputs 0, DIVTIME(t, 0) faults


def test_conversions_are_matiecs_set():
    """Conversions the rules derive (without MatIEC at hand): a few that exist and a few that do not."""
    for name in ("INT_TO_REAL", "TIME_TO_DINT", "STRING_TO_TIME", "DT_TO_TOD", "DATE_AND_TIME_TO_DATE",
                 "BOOL_TO_TIME", "BYTE_BCD_TO_USINT", "USINT_TO_BCD_WORD", "BCD_TO_UINT", "UDINT_TO_BCD"):
        assert stdfuncs.lookup(name) is not None, name
    for name in ("DATE_TO_TOD", "TIME_TO_DATE", "STRING_TO_STRING", "TOD_TO_TIME", "INT_TO_BCD", "REAL_TO_BCD"):
        assert stdfuncs.lookup(name) is None, name
