"""Constant expressions that overflow their type: the builtin refuses exactly those MatIEC's constant folding
refuses (builtin/constfold.py). Each row's verdict was measured with iec2c (MatIEC HEAD); where iec2c is
installed, it is asked again."""

from __future__ import annotations

import subprocess

import pytest

from linmot_st.toolchain.builtin import BuiltinCompileError, check_text
from linmot_st.toolchain.testing import requires_matiec

SOURCE = """PROGRAM cf_main
  VAR {decls} END_VAR
  {stmt}
END_PROGRAM
CONFIGURATION cf_cfg
  RESOURCE cf_res ON PLC
    TASK cf_task(INTERVAL := T#10ms, PRIORITY := 0);
    PROGRAM cf_inst WITH cf_task : cf_main;
  END_RESOURCE
END_CONFIGURATION
"""

# (declarations, statement, MatIEC refuses it)
ROWS = [
    ("i : INT;", "i := 32767 + 1;", True),
    ("i : INT;", "i := 32767 + 1 - 1;", True),             # the intermediate overflows, the end is in range
    ("i : INT;", "i := INT#200 * INT#200;", True),
    ("i : INT;", "i := INT#200 * 200;", True),
    ("i : DINT;", "i := DINT#2147483647 + 1 - 1;", True),
    ("i : SINT;", "i := SINT#100 + SINT#100 - SINT#100;", True),
    ("i : SINT;", "i := 100 + 100 - 100;", True),
    ("i : DINT;", "i := 32767 + 1;", False),               # an untyped constant takes the target's type
    ("i : INT;", "i := i + 32767 + 1;", False),            # (i + 32767) + 1 is not constant
    ("i : INT;", "i := i + (32767 + 1);", True),
    ("i : INT;", "i := -32767 - 1;", False),
    ("i : INT;", "i := -(32767 + 1);", True),
    ("i : INT;", "i := -INT#-32768;", False),              # negation folds without a range check...
    ("i : INT;", "i := -INT#-32768 + 0;", True),           # ...but the value it gives is checked by the next '+'
    ("i : INT;", "i := -(-32767 - 1) - 1;", False),
    ("i : INT;", "i := -32768 - 1 + 1;", True),
    ("i : UINT;", "i := 1 - 2 + 1;", True),
    ("i : UINT;", "i := UINT#0 - 1;", True),
    ("i : ULINT;", "i := 9223372036854775807 + 1;", False),
    ("i : ULINT;", "i := 18446744073709551615 + 1;", True),
    ("i : LINT;", "i := 65536 * 65536 / 65536;", False),
    ("i : DINT;", "i := 65536 * 65536 / 65536;", True),
    ("i : INT;", "i := INT#-32768 / INT#-1;", True),
    ("i : INT;", "i := INT#7 MOD 0;", False),
    ("i : INT; c : INT;", "i := c + 32767 + 1;", False),
    ("b : BOOL;", "b := 32767 + 1 > 0;", False),
    ("b : BOOL;", "b := INT#32767 + 1 > 0;", True),
    ("i : INT;", "i := ABS(INT#32767 + 1);", True),
    ("i : INT;", "i := (INT#32767 + 1) * 0;", True),
    ("a : ARRAY[0..1] OF INT; i : INT;", "i := a[INT#32767 + 1];", True),
    ("r : REAL;", "r := 1.0E38 * 10.0;", True),
    ("r : REAL;", "r := 1.0E38 * 10.0 / 10.0;", True),
    ("r : LREAL;", "r := 1.0E38 * 10.0;", False),
    ("r : LREAL;", "r := LREAL#1.0E38 * 10.0 * 10.0;", False),
    ("r : LREAL;", "r := " + " * ".join(["1.0E30"] * 11) + ";", True),   # infinite (literals stop at 3.4E38)
]
IDS = [stmt for _, stmt, _ in ROWS]


@pytest.mark.parametrize("decls, stmt, refused", ROWS, ids=IDS)
def test_builtin_refuses_what_matiec_folding_refuses(decls, stmt, refused):
    text = SOURCE.format(decls=decls, stmt=stmt)
    if not refused:
        check_text(text)
        return
    with pytest.raises(BuiltinCompileError) as info:
        check_text(text)
    first = info.value.diagnostics[0]
    assert "constant folding refuses it" in first.message, first
    assert first.line == 3


@pytest.mark.parametrize("stmt", ["b := 2147483647 + 1 > 0;", "b := 2147483647 * 2 > 0;",
                                  "b := -(2147483647 + 1) < 0;"])
def test_untyped_comparisons_that_overflow_c_int_are_refused(stmt):
    # iec2c builds these, but its C computes them as C int literals: `2147483647 + 1 > 2147483647` is FALSE
    with pytest.raises(BuiltinCompileError) as info:
        check_text(SOURCE.format(decls="b : BOOL;", stmt=stmt))
    assert "overflows C's int" in info.value.diagnostics[0].message


@pytest.mark.parametrize("stmt", ["b := 3000000000 > 0;", "b := 4294967295 + 1 > 4294967295;",
                                  "b := 18446744073709551615 > 0;"])
def test_untyped_comparisons_beyond_dint_take_a_wider_type(stmt):
    check_text(SOURCE.format(decls="b : BOOL;", stmt=stmt))


def test_the_first_overflowing_operation_is_named():
    with pytest.raises(BuiltinCompileError) as info:
        check_text(SOURCE.format(decls="i : INT;", stmt="i := 1 + 32767 * 2 - 32767 - 32767;"))
    assert "'*' gives 65534" in info.value.diagnostics[0].message


def test_a_long_constant_sum_is_folded_without_recursion():
    terms = " + ".join(["2"] * 20000)
    with pytest.raises(BuiltinCompileError) as info:
        check_text(SOURCE.format(decls="i : INT;", stmt=f"i := {terms};"))
    assert "'+' gives 32768" in info.value.diagnostics[0].message
    check_text(SOURCE.format(decls="i : DINT;", stmt=f"i := {terms};"))


@requires_matiec
@pytest.mark.matiec
@pytest.mark.parametrize("decls, stmt, refused", ROWS, ids=IDS)
def test_iec2c_verdict_is_the_measured_one(decls, stmt, refused, tmp_path):
    from linmot_st.toolchain import matiec
    tool = matiec.find()
    (tmp_path / "cf.st").write_text(SOURCE.format(decls=decls, stmt=stmt))
    (tmp_path / "out").mkdir()
    argv = [str(tool.iec2c), *matiec.flags(tool.iec2c), "-I", str(tool.lib), "-T", "out", "cf.st"]
    rc = subprocess.run(argv, cwd=tmp_path, capture_output=True, timeout=60).returncode
    assert (rc != 0) == refused
