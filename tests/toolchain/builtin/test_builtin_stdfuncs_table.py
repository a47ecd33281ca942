"""The standard functions' table (toolchain/builtin/stdfuncs/table.py) is whole: every row names a typing rule
the checker applies and has C (or reaches C through the durations' path), and its C templates take as many
arguments as the family has formal parameters. The behaviour of each family is tested by
test_builtin_stdlib.py (every MatIEC overload) and the conformance cases std_*, conv_*."""

from __future__ import annotations

import string

import pytest

from linmot_st.toolchain.builtin import BuiltinCompileError, check_text, stdfuncs
from linmot_st.toolchain.builtin.checker import Checker
from linmot_st.toolchain.builtin.checker.std_calls import RULES
from linmot_st.toolchain.builtin.codegen import CodeGen

ROWS = sorted(stdfuncs.FAMILIES.values(), key=lambda f: f.name) + [stdfuncs.CONV]


@pytest.mark.parametrize("fam", ROWS, ids=lambda f: f.name)
def test_row_names_a_rule_the_checker_applies(fam):
    assert fam.rule in RULES
    assert callable(getattr(Checker, RULES[fam.rule]))
    if fam.rule in ("tvar", "arith", "math", "shift", "sel", "mux", "compare"):
        pred, what = fam.accepts
        assert callable(pred) and what


@pytest.mark.parametrize("fam", ROWS, ids=lambda f: f.name)
def test_row_has_c(fam):
    if fam.rule == "multime":      # MULTIME, DIVTIME: always durations, their C is the operators'
        assert fam.op in ("*", "/") and fam.c is None
        return
    assert fam.c is not None
    if isinstance(fam.c, str):
        fields = {f for _, f, _, _ in string.Formatter().parse(fam.c) if f is not None}
        positions = {int(f) for f in fields if f.isdigit()}
        assert positions == set(range(len(fam.params))), fam.c
        assert fields - {str(p) for p in positions} <= {"t", "site"}


def test_every_rule_is_used():
    assert {f.rule for f in ROWS} == set(RULES)


def test_string_layout_covers_each_argument():
    for fam in ROWS:
        if fam.rule == "string":
            assert len(stdfuncs.string_layout(fam, len(fam.params))) == len(fam.params), fam.name


def test_a_row_drives_the_checker_and_the_c():
    """One fact, two readers: SHL's row refuses a BOOL in the checker and names its C function."""
    with pytest.raises(BuiltinCompileError, match="defines no shift or rotate of a BOOL"):
        check_text("PROGRAM prg VAR b : BOOL; END_VAR b := SHL(b, 1); END_PROGRAM")
    prog = check_text("PROGRAM prg VAR w : WORD; END_VAR w := SHL(w, 1); END_PROGRAM")
    _, units, _ = CodeGen(prog, "test").generate_units()
    assert "__shl_WORD(" in "".join(units)
