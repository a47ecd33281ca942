"""The table of the standard function families: one row per family, read by the checker and the code generator.

A row gives the family's formal parameters, the typing rule the checker applies to a call
(checker/std_calls.py, by `rule`), what its type variable may be (`accepts`), the types its typed
variants may name (ADD_INT: `suffixes`), the argument layout of a string function, a fixed result type,
its ST operator (durations, arithmetic, comparisons) and its C (`c`: a template or an emitter of c.py).
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass

from .. import types as T
from . import c as C


def selectable(t: T.Type) -> bool:
    tb = t.base()
    return isinstance(tb, T.Elem)


def shiftable(t: T.Type) -> bool:
    # no BOOL: iec2c accepts SHL(b, 1) but calls SHL__BOOL__BOOL__SINT, which its headers do not define
    return T.is_bit(t) and not T.same(t, T.BOOL)


NUMBER = (T.is_num, "a number")
INTEGER = (T.is_int, "an integer")
BITS = (T.is_bit, "a bit string")
REAL = (T.is_real, "a REAL or LREAL")
ELEMENTARY = (selectable, "an elementary value")
SHIFTABLE = (shiftable, "a bit string other than BOOL (BYTE, WORD, DWORD or LWORD: iec2c accepts a BOOL, but "
                        "MatIEC's C defines no shift or rotate of a BOOL and does not compile)")
# the types a typed variant of a selection or comparison may name (MAX_STRING, MUX_INT_TOD, ...)
ELEM_FOR_SEL = T.NUMS + T.BITS + (T.TIME, T.STRING) + T.DATES


@dataclass(frozen=True)
class Family:
    name: str                   # ADD, SHL, CONV, ...
    params: tuple[str, ...]     # formal names; the last one repeats for an extensible family
    extensible: bool = False    # ADD(IN1, IN2, IN3, ...)
    min_args: int = 0
    rule: str = "tvar"          # the checker's typing rule (checker/std_calls.py)
    accepts: tuple[Callable[[T.Type], bool], str] | None = None   # the type variable: predicate, as a message says it
    suffixes: tuple[T.Elem, ...] = ()     # the types a typed variant (ADD_INT) may name
    layout: str = ""            # a string function's arguments: S a STRING, I an integer
    result: Callable[[], T.Type] | None = None    # the result type when it is not the type variable
    op: str = ""                # the ST operator (durations, arithmetic, comparisons)
    # the C: a template ({0}, {1}... the arguments' C, {t} the result's C type, {site} the fault site) or an
    # emitter of c.py, (gen, e, sc, cs, t, fam) -> str
    c: str | Callable | None = None


FAMILIES: dict[str, Family] = {}


def _row(name, params, extensible=False, min_args=None, **facts):
    FAMILIES[name] = Family(name, tuple(params), extensible, len(params) if min_args is None else min_args, **facts)


_PAIR, _IN = ("IN1", "IN2"), ("IN",)
# arithmetic: of numbers, or of durations and dates (ADD(t, T#1s), as the operators)
_row("ADD", _PAIR, True, rule="arith", accepts=NUMBER, suffixes=T.NUMS, op="+", c=C.fold_arith)
_row("MUL", _PAIR, True, rule="arith", accepts=NUMBER, suffixes=T.NUMS, op="*", c=C.fold_arith)
_row("SUB", _PAIR, rule="arith", accepts=NUMBER, suffixes=T.NUMS, op="-", c=C.fold_arith)
# DIV(x, 0) is defined (0, as MatIEC's DIV function returns); only the operator faults
_row("DIV", _PAIR, rule="arith", accepts=NUMBER, suffixes=T.NUMS, op="/", c=C.div)
_row("MOD", _PAIR, accepts=INTEGER, suffixes=T.INTS, c="__mod_{t}({0}, {1})")
_row("EXPT", _PAIR, rule="expt", c=C.expt)
_row("ABS", _IN, accepts=NUMBER, suffixes=T.NUMS, c=C.abs_)
for _name, _cfn in (("SQRT", "sqrt"), ("LN", "log"), ("LOG", "log10"), ("EXP", "exp"), ("SIN", "sin"), ("COS", "cos"),
                    ("TAN", "tan"), ("ASIN", "asin"), ("ACOS", "acos"), ("ATAN", "atan")):
    _row(_name, _IN, rule="math", accepts=REAL, suffixes=T.REALS, c=f"(({{t}})__builtin_{_cfn}((double)({{0}})))")
_row("MOVE", _IN, accepts=ELEMENTARY, suffixes=ELEM_FOR_SEL, c="{0}")
_row("TRUNC", _IN, rule="trunc", result=lambda: T.poly(T.INTS, T.DINT), c=C.trunc)
# bit strings
_row("AND", _PAIR, True, accepts=BITS, suffixes=T.BITS, c=C.fold_bits("&&", "&"))
_row("OR", _PAIR, True, accepts=BITS, suffixes=T.BITS, c=C.fold_bits("||", "|"))
_row("XOR", _PAIR, True, accepts=BITS, suffixes=T.BITS, c=C.fold_bits("^", "^"))
_row("NOT", _IN, accepts=BITS, suffixes=T.BITS, c=C.not_)
for _name in ("SHL", "SHR", "ROL", "ROR"):
    _row(_name, ("IN", "N"), rule="shift", accepts=SHIFTABLE,
         c=f"__{_name.lower()}_{{t}}({{0}}, (long long)({{1}}), {{site}})")
# selection
_row("SEL", ("G", "IN0", "IN1"), rule="sel", accepts=ELEMENTARY, suffixes=ELEM_FOR_SEL, c="({0} ? {2} : {1})")
_row("MAX", _PAIR, True, accepts=ELEMENTARY, suffixes=ELEM_FOR_SEL, op="<", c=C.extreme)
_row("MIN", _PAIR, True, accepts=ELEMENTARY, suffixes=ELEM_FOR_SEL, op=">", c=C.extreme)
_row("LIMIT", ("MN", "IN", "MX"), accepts=ELEMENTARY, suffixes=ELEM_FOR_SEL, c=C.limit)
_row("MUX", ("K", "IN0", "IN1"), True, min_args=2, rule="mux", accepts=ELEMENTARY, c=C.mux)
# comparison
for _name, _op in (("GT", ">"), ("GE", ">="), ("EQ", "="), ("LE", "<="), ("LT", "<")):
    _row(_name, _PAIR, True, rule="compare", accepts=ELEMENTARY, suffixes=ELEM_FOR_SEL, op=_op, c=C.compare)
_row("NE", _PAIR, rule="compare", accepts=ELEMENTARY, suffixes=ELEM_FOR_SEL, op="<>", c=C.compare)
# character strings
_STR_LEN = lambda: T.poly(T.INTS, T.INT)     # noqa: E731 (a fresh literal type per call, as any result)
_row("LEN", _IN, rule="string", layout="S", result=_STR_LEN, c="(({t})({0}).len)")
_row("FIND", _PAIR, rule="string", layout="SS", result=_STR_LEN, c="(({t})__str_find({0}, {1}))")
_row("LEFT", ("IN", "L"), rule="string", layout="SI", c="__str_left({0}, (long long)({1}))")
_row("RIGHT", ("IN", "L"), rule="string", layout="SI", c="__str_right({0}, (long long)({1}))")
_row("MID", ("IN", "L", "P"), rule="string", layout="SII", c="__str_mid({0}, (long long)({1}), (long long)({2}))")
_row("CONCAT", _PAIR, True, min_args=1, rule="string", layout="S*", c=C.concat)
_row("INSERT", ("IN1", "IN2", "P"), rule="string", layout="SSI", c="__str_insert({0}, {1}, (long long)({2}))")
_row("DELETE", ("IN", "L", "P"), rule="string", layout="SII",
     c="__str_delete({0}, (long long)({1}), (long long)({2}))")
_row("REPLACE", ("IN1", "IN2", "L", "P"), rule="string", layout="SSII",
     c="__str_replace({0}, {1}, (long long)({2}), (long long)({3}))")
# time and date (their C is the operators': c.py's time path)
_row("MULTIME", _PAIR, rule="multime", suffixes=T.NUMS, op="*")
_row("DIVTIME", _PAIR, rule="multime", suffixes=T.NUMS, op="/")
_row("CONCAT_DATE_TOD", _PAIR, rule="concat_date_tod", c="({0} + {1})")

# the conversions (X_TO_Y, BCD): their overloads are overloads.py's
CONV = Family("CONV", ("IN",), False, 1, rule="conv", c=C.conversion)

# the standard functions a user FUNCTION may be named after: iec2c builds such a FUNCTION, but wherever the
# name is called it calls its own standard function (measured: docs/builtin-compiler.md). The others are
# operators to iec2c ("Function overloading not allowed") or clash with its C (CONCAT, CONCAT_DATE_TOD).
USER_NAMEABLE = frozenset(FAMILIES) - {"AND", "OR", "XOR", "NOT", "MOD", "CONCAT", "CONCAT_DATE_TOD"}

# functions outside the subset that people reach for: a clear message instead of "unknown function"
UNSUPPORTED_FUNCTIONS = {
    "SIZEOF": "SIZEOF", "ADR": "ADR", "REF": "REF()", "LOWER_BOUND": "LOWER_BOUND", "UPPER_BOUND": "UPPER_BOUND",
    "MEMCPY": "MEMCPY", "ASC": "ASC", "CHR": "CHR", "LEN_WSTRING": "WSTRING functions", "NEW": "__NEW",
}


def param_names(fam: Family, n_args: int) -> list[str]:
    """Formal names of the first n arguments (IN1, IN2, IN3... for an extensible family)."""
    names = list(fam.params)
    if fam.extensible:
        last = names[-1]
        m = re.fullmatch(r"([A-Z]+)(\d+)", last)
        if m:
            stem, k = m.group(1), int(m.group(2))
            while len(names) < n_args:
                k += 1
                names.append(f"{stem}{k}")
    return names


def string_layout(fam: Family, n_args: int) -> str:
    """S or I per argument of a string function (CONCAT: any number of STRINGs)."""
    return fam.layout[0] * n_args if fam.layout.endswith("*") else fam.layout
