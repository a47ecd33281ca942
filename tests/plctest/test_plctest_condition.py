"""The condition grammar of the rig (linmot_st.plctest.condition): random expressions, written with the fewest
parentheses IEC 61131-3's precedence table allows, evaluated by the parser and by a Python reference over the
same tree; errors with their column; the real PLC's variables in tests/plctest/test_plctest_rig.py."""

from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from linmot_st.plctest.condition import ConditionError, condition

# IEC 61131-3 ed. 3, table 71: the strongest binding has the highest number; all binary operators associate
# left to right. Written here from the standard, not from the parser's grammar.
LEVEL = {"OR": 1, "XOR": 2, "AND": 3, "=": 4, "<>": 4, "<": 5, ">": 5, "<=": 5, ">=": 5,
         "+": 6, "-": 6, "*": 7, "/": 7, "MOD": 7, "unary": 8, "**": 9, "atom": 10}


class FakeVar:
    def __init__(self, type_: str, value):
        self.type, self._value = type_, value

    @property
    def value(self):
        return self._value


class FakePlc:
    """What condition() needs of a Plc: var(path) with .type and .value (and an enum's _names)."""

    def __init__(self, values: dict):
        self.vars = {k: FakeVar("BOOL" if isinstance(v, bool) else "INT", v) for k, v in values.items()}
        self.vars["MAIN.STATE"] = FakeVar("E_STATE", "ST_READY")
        self.vars["MAIN.STATE"]._names = ("ST_BOOT", "ST_READY", "ST_ERROR")

    def var(self, path: str):
        try:
            return self.vars[path.upper()]
        except KeyError:
            raise KeyError(f"no variable {path}") from None


BOOLS = [f"MAIN.B{i}" for i in range(3)]
INTS = [f"MAIN.N{i}" for i in range(3)]


def trunc_div(a, b):
    q = abs(a) // abs(b)
    return q if (a < 0) == (b < 0) else -q


def reference(node, env):
    """IEC semantics on Python values: integer / and MOD truncate toward zero; AND/OR/XOR bit-wise on integers."""
    op = node[0]
    if op == "lit":
        return node[1]
    if op == "var":
        return env[node[1]]
    if op == "NOT":
        return not reference(node[1], env)
    if op == "neg":
        return -reference(node[1], env)
    a, b = reference(node[1], env), reference(node[2], env)
    if op in ("AND", "OR", "XOR"):
        r = {"AND": a & b, "OR": a | b, "XOR": a ^ b}[op]
        return bool(r) if isinstance(a, bool) else r
    if op == "/":
        return trunc_div(a, b)
    if op == "MOD":
        return a - b * trunc_div(a, b)
    if op == "**":
        return a ** b
    return {"+": a + b, "-": a - b, "*": a * b, "=": a == b, "<>": a != b, "<": a < b,
            ">": a > b, "<=": a <= b, ">=": a >= b}[op]


def level(node) -> int:
    op = node[0]
    return LEVEL["atom"] if op in ("lit", "var") else LEVEL["unary"] if op in ("NOT", "neg") else LEVEL[op]


def render(node, draw_case) -> str:
    """The fewest parentheses: a left operand needs them when it binds weaker, a right one also at equal level."""
    op = node[0]
    if op == "lit":
        v = node[1]
        return ("TRUE" if v else "FALSE") if isinstance(v, bool) else (f"16#{v:X}" if v > 9 and v % 2 else str(v))
    if op == "var":
        return node[1]
    if op in ("NOT", "neg"):
        inner = render(node[1], draw_case)
        inner = f"({inner})" if level(node[1]) < LEVEL["unary"] else inner
        return f"{draw_case('NOT')} {inner}" if op == "NOT" else f"- {inner}"
    left, right = render(node[1], draw_case), render(node[2], draw_case)
    if level(node[1]) < LEVEL[op]:
        left = f"({left})"
    if level(node[2]) <= LEVEL[op]:
        right = f"({right})"
    word = draw_case(op) if op.isalpha() else op
    return f"{left} {word} {right}"


def ints(depth: int):
    leaf = st.one_of(st.integers(0, 40).map(lambda v: ("lit", v)), st.sampled_from(INTS).map(lambda p: ("var", p)))
    if depth == 0:
        return leaf
    sub = ints(depth - 1)
    return st.one_of(
        leaf,
        st.tuples(st.just("neg"), sub),
        st.tuples(st.sampled_from(["+", "-", "*", "/", "MOD", "AND", "OR", "XOR"]), sub, sub),
        st.tuples(st.just("**"), leaf, st.integers(0, 3).map(lambda v: ("lit", v))))


def bools(depth: int):
    leaf = st.one_of(st.booleans().map(lambda v: ("lit", v)), st.sampled_from(BOOLS).map(lambda p: ("var", p)))
    if depth == 0:
        return leaf
    sub = bools(depth - 1)
    return st.one_of(
        leaf,
        st.tuples(st.just("NOT"), sub),
        st.tuples(st.sampled_from(["AND", "OR", "XOR", "=", "<>"]), sub, sub),
        st.tuples(st.sampled_from(["=", "<>", "<", ">", "<=", ">="]), ints(depth - 1), ints(depth - 1)))


ENV = st.fixed_dictionaries({**{p: st.booleans() for p in BOOLS}, **{p: st.integers(-50, 50) for p in INTS}})
CASE = st.sampled_from([str.upper, str.lower, str.title])


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(tree=bools(4), env=ENV, case=CASE)
def test_random_conditions_agree_with_the_reference(tree, env, case):
    text = render(tree, case)
    try:
        expected = reference(tree, env)
    except ZeroDivisionError:
        with pytest.raises(ZeroDivisionError):
            condition(FakePlc(env), text).test()
        return
    assert condition(FakePlc(env), text).test() is bool(expected), text


@settings(max_examples=200, deadline=None)
@given(tree=bools(3), env=ENV, cut=st.integers(0, 200))
def test_a_cut_condition_fails_with_a_column_inside_it(tree, env, cut):
    text = render(tree, str.upper)
    text = text[:cut % (len(text) + 1)]
    try:
        condition(FakePlc(env), text)
    except ConditionError as exc:
        assert 1 <= exc.column <= len(text) + 1 and f"column {exc.column}" in str(exc)


@pytest.mark.parametrize("text,value", [
    ("MAIN.B0 OR MAIN.B1 AND MAIN.B2", True),        # AND before OR
    ("(MAIN.B0 OR MAIN.B1) AND MAIN.B2", False),
    ("MAIN.B0 XOR MAIN.B1 OR MAIN.B0", True),         # XOR before OR
    ("NOT MAIN.B1 AND MAIN.B0", True),                # NOT before AND
    ("MAIN.N0 + MAIN.N1 * 2 = 7", True),              # * before +, arithmetic on both sides
    ("MAIN.N0 * 2 - 1 > MAIN.N1 + MAIN.N2", False),   # two variables compared
    ("-2 ** 2 = -4", True),                           # ** before unary minus
    ("-7 / 2 = -3 AND -7 MOD 2 = -1", True),          # integer / and MOD truncate toward zero
    ("MAIN.STATE = ST_READY AND MAIN.STATE <> E_STATE#ST_BOOT", True),
    ("MAIN.STATE = 'ST_READY' & MAIN.B0", True),
    ("(MAIN.N2 AND 16#4) <> 0", True),                # bit-wise on integers: N2 = 4
    ("MAIN.N0 >= 2#1 AND T#1s = 1_000_000_000 AND T#1m30s = TIME#90s", True),
    ("INT#-5 + DINT#16#10 = 11 AND LREAL#2.5 * 2 = 5", True),
])
def test_precedence_and_literals(text, value):
    plc = FakePlc({"MAIN.B0": True, "MAIN.B1": False, "MAIN.B2": False, "MAIN.N0": 1, "MAIN.N1": 3,
                   "MAIN.N2": 4})
    assert condition(plc, text).test() is value


@pytest.mark.parametrize("text,column,message", [
    ("MAIN.B0 OR", 11, "ends too early"),
    ("MAIN.B0 AND (MAIN.B1", 21, "ends too early"),
    ("MAIN.B0 ? MAIN.B1", 9, "unexpected character '?'"),
    ("MAIN.B0 MAIN.B1", 9, "unexpected 'MAIN.B1'"),
    ("MAIN.B0 OR MAIN.NOSUCH", 12, "no variable MAIN.NOSUCH"),
    ("NOT MAIN.STATE = ST_READY", 1, "NOT takes a BOOL, not ENUM"),
    ("MAIN.STATE = ST_GONE", 14, "ST_GONE is neither a variable nor a value of the enum (ST_BOOT, ST_READY"),
    ("MAIN.STATE < ST_READY", 12, "enum values compare with = and <> only"),
    ("MAIN.N0", 1, "the condition is INT, not BOOL"),
    ("MAIN.N0 < MAIN.N1 < 3", 19, "< compares BOOL with INT"),
    ("MAIN.B0 + 1 = 2", 9, "+ takes numbers, not BOOL and INT"),
    ("T#3x > 0", 1, "not a duration"),
    ("INT#x5 > 0", 1, "INT#x5: not a INT literal"),
])
def test_errors_say_where(text, column, message):
    plc = FakePlc({"MAIN.B0": True, "MAIN.B1": False, "MAIN.N0": 1, "MAIN.N1": 3})
    with pytest.raises(ConditionError) as info:
        condition(plc, text)
    assert info.value.column == column and message in str(info.value), str(info.value)
