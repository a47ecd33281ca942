"""Deep and long expressions: the builtin compiler never crashes on them, long left-associative chains
compile (MatIEC compiles a sum of 5000 terms), and nesting is bounded exactly where MatIEC's parser
stack overflows (builtin/nesting.py), so what the builtin accepts also parses with iec2c.

The MatIEC limits below were measured with iec2c (HEAD of 2024-10, -f -l -p) by bisection; where iec2c is
installed, test_matiec_limits measures them again.
"""

from __future__ import annotations

import subprocess

import pytest

from linmot_st.plc import Plc
from linmot_st.toolchain.builtin import BuiltinCompileError, check_text, compile_text
from linmot_st.toolchain.testing import BACKEND_PARAMS, build_text, requires_matiec

HEAD = """TYPE tn_arr : ARRAY[0..3] OF INT; END_TYPE
FUNCTION tn_f : INT
  VAR_INPUT a : INT; END_VAR
  tn_f := a;
END_FUNCTION
"""
VARS = "i, j : INT; b : BOOL; arr : tn_arr; t : TON;"


def program(body: str, extra_vars: str = "") -> str:
    return HEAD + f"PROGRAM tn_main\n  VAR {VARS} {extra_vars} END_VAR\n{body}\nEND_PROGRAM\n"


def fors(n: int, by: str = "") -> str:
    return "".join(f"FOR k{i} := 0 TO 1 {by}DO " for i in range(n)) + "j := j;" + " END_FOR;" * n


# shape: (body of n levels, extra variables, MatIEC's largest n, the builtin's largest n)
SHAPES = {
    "parentheses": (lambda n: "i := " + "(" * n + "i" + ")" * n + ";", None, 189, 189),
    "standard calls": (lambda n: "i := " + "ABS(" * n + "i" + ")" * n + ";", None, 94, 94),
    "formal calls": (lambda n: "i := " + "tn_f(a := " * n + "i" + ")" * n + ";", None, 47, 47),
    "right operands": (lambda n: "i := " + "i + (" * n + "i" + ")" * n + ";", None, 63, 63),
    "indices": (lambda n: "i := " + "arr[" * n + "0" + "]" * n + ";", None, 94, 94),
    "NOT": (lambda n: "b := " + "NOT (" * n + "b" + ")" * n + ";", None, 94, 94),
    "IF": (lambda n: "IF b THEN " * n + "i := i;" + " END_IF;" * n, None, 63, 63),
    "ELSE": (lambda n: "IF b THEN i := i; ELSE " * n + "i := i;" + " END_IF;" * n, None, 31, 31),
    "ELSIF": (lambda n: "IF b THEN i := i; ELSIF b THEN " * n + "i := i;" + " END_IF;" * n, None, 23, 23),
    "WHILE": (lambda n: "WHILE b DO " * n + "i := i;" + " END_WHILE;" * n, None, 63, 63),
    "REPEAT": (lambda n: "REPEAT " * n + "i := i;" + " UNTIL b END_REPEAT;" * n, None, 189, 189),
    "FOR": (fors, lambda n: "".join(f"k{i} : INT; " for i in range(n)), 27, 27),
    "FOR BY": (lambda n: fors(n, "BY 1 "), lambda n: "".join(f"k{i} : INT; " for i in range(n)), 21, 21),
    # the model takes 5 symbols for each CASE level, MatIEC manages one level more
    "CASE": (lambda n: "CASE i OF 1: " * n + "j := j;" + " END_CASE;" * n, None, 38, 37),
    # a duration literal is several tokens to MatIEC (6 for T#1s; the model takes the longest form, 8)
    "duration leaf": (lambda n: "t.PT := " + "(" * n + "T#1s" + ")" * n + ";", None, 184, 182),
}


def text(shape: str, n: int) -> str:
    body, extra, _, _ = SHAPES[shape]
    return program("  " + body(n), extra(n) if extra else "")


def accepted(src: str) -> bool:
    try:
        check_text(src)
    except BuiltinCompileError as exc:
        assert all("nested too deeply" in d.message for d in exc.diagnostics), exc.diagnostics
        return False
    return True


@pytest.mark.parametrize("shape", SHAPES)
def test_nesting_limit_is_matiecs(shape):
    """The builtin accepts exactly up to its limit, which is MatIEC's or (where the model is coarser) a
    level or two below it, never above; the rejection is a diagnostic, not a crash."""
    _, _, matiec_limit, builtin_limit = SHAPES[shape]
    assert builtin_limit <= matiec_limit
    assert accepted(text(shape, builtin_limit))
    assert not accepted(text(shape, builtin_limit + 1))
    with pytest.raises(BuiltinCompileError) as info:
        check_text(text(shape, builtin_limit + 1))
    assert "nested too deeply: MatIEC's parser keeps at most 200 symbols pending" in str(info.value)


@pytest.mark.parametrize("shape", SHAPES)
def test_deepest_accepted_nesting_generates_c(shape, tmp_path):
    """At the limit, the checker and the code generator stay within Python's recursion limit."""
    compile_text(text(shape, SHAPES[shape][3]), tmp_path)


def test_deeper_nesting_is_one_diagnostic_not_a_traceback():
    src = program("  i := " + "ABS(" * 400 + "i" + ")" * 400 + ";\n  i := " + "(" * 3000 + "i" + ")" * 3000 + ";")
    with pytest.raises(BuiltinCompileError) as info:
        check_text(src, "deep.st")
    diags = [str(d) for d in info.value.diagnostics]
    assert len(diags) == 2 and all(d.startswith("deep.st:") and "expression nested too deeply" in d for d in diags)


@requires_matiec
@pytest.mark.matiec
@pytest.mark.parametrize("shape", SHAPES)
def test_matiec_limits(shape, tmp_path):
    """iec2c accepts each shape at the builtin's limit and at its own, and rejects it one level deeper."""
    from linmot_st.toolchain import matiec
    tool = matiec.find()
    _, _, matiec_limit, builtin_limit = SHAPES[shape]

    def iec2c_accepts(n: int) -> bool:
        src = tmp_path / f"n{n}.st"
        src.write_text(text(shape, n))
        out = tmp_path / f"out{n}"
        out.mkdir(exist_ok=True)
        argv = [str(tool.iec2c), *matiec.flags(tool.iec2c), "-I", str(tool.lib), "-T", str(out), src.name]
        return subprocess.run(argv, cwd=tmp_path, capture_output=True, timeout=60).returncode == 0

    assert iec2c_accepts(builtin_limit)
    assert iec2c_accepts(matiec_limit)
    assert not iec2c_accepts(matiec_limit + 1)


LONG = """
PROGRAM Main
  VAR
    d : DINT := 3;
    s, n : DINT;
    w : INT := 1;
    u : INT := 1;
    x : INT;
    b : BOOL := TRUE;
    all_true, any_false : BOOL;
    r : LREAL := 0.5;
    y : LREAL;
  END_VAR
  s := {dsum};
  n := {lits};
  x := {wrapping};
  all_true := {conj};
  any_false := {disj};
  y := {reals};
END_PROGRAM

CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK T1(INTERVAL := T#10ms, PRIORITY := 0);
    PROGRAM Inst0 WITH T1 : Main;
  END_RESOURCE
END_CONFIGURATION
"""


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_sums_of_thousands_of_terms(backend, tmp_path):
    """Left-associative chains of any length: a 5000-term sum of variables, of literals (typed by their
    context), INT arithmetic that leaves the type's range on the way, a 1000-factor product, 2000-term
    AND/OR chains, a 3000-term LREAL sum."""
    src = LONG.format(
        dsum=" + ".join(["d"] * 5000),
        lits=" + ".join(["1"] * 5000),
        wrapping=" + ".join(["w"] * 2000) + " - " + " - ".join(["w"] * 2000) + " + " + " * ".join(["u"] * 1000),
        conj=" AND ".join(["b"] * 2000),
        disj=" OR ".join(["NOT b"] * 2000),
        reals=" + ".join(["r"] * 3000),
    )
    plc = Plc(build_text(src, tmp_path, backend))
    plc["INST0.W"] = 300          # 2000 * 300 leaves INT's range on the way; the result does not
    plc.step(1)
    assert plc["INST0.S"] == 15000
    assert plc["INST0.N"] == 5000
    assert plc["INST0.X"] == 1
    assert plc["INST0.ALL_TRUE"] is True and plc["INST0.ANY_FALSE"] is False
    assert plc["INST0.Y"] == 1500.0
