"""The standard functions of IEC 61131-3 as MatIEC provides them: names, formal parameters, typing rules.

Each name maps to a `Family`; the checker applies the family's typing rule to a call and records a
`StdCall` on it, which the code generator turns into C. Typed variants (`ADD_INT`, `MUX_DINT_INT`,
`ADD_TOD_TIME`...) fix the family's type variable. Conversions are derived from rules that reproduce
MatIEC's set of `X_TO_Y` functions (tests/test_builtin_stdlib.py compares the two where MatIEC is
installed).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

from . import types as T

# ------------------------------------------------------------------ families


@dataclass(frozen=True)
class Family:
    name: str                   # ADD, SHL, CONV, ...
    params: tuple[str, ...]     # formal names; the last one repeats for an extensible family
    extensible: bool = False    # ADD(IN1, IN2, IN3, ...)
    min_args: int = 0


ARITH_EXT = {"ADD", "MUL"}
ARITH_2 = {"SUB", "DIV", "MOD"}
MATH_1 = {"SQRT", "LN", "LOG", "EXP", "SIN", "COS", "TAN", "ASIN", "ACOS", "ATAN"}
BIT_EXT = {"AND", "OR", "XOR"}
SHIFTS = {"SHL", "SHR", "ROL", "ROR"}
CMP_EXT = {"GT", "GE", "EQ", "LE", "LT"}
STRING_FUNCS = {"LEN", "LEFT", "RIGHT", "MID", "CONCAT", "INSERT", "DELETE", "REPLACE", "FIND"}

FAMILIES: dict[str, Family] = {}


def _fam(name, params, extensible=False, min_args=None):
    FAMILIES[name] = Family(name, tuple(params), extensible, len(params) if min_args is None else min_args)


for _n in ARITH_EXT:
    _fam(_n, ("IN1", "IN2"), extensible=True)
for _n in ARITH_2:
    _fam(_n, ("IN1", "IN2"))
_fam("EXPT", ("IN1", "IN2"))
_fam("ABS", ("IN",))
for _n in MATH_1:
    _fam(_n, ("IN",))
_fam("MOVE", ("IN",))
_fam("TRUNC", ("IN",))
for _n in BIT_EXT:
    _fam(_n, ("IN1", "IN2"), extensible=True)
_fam("NOT", ("IN",))
for _n in SHIFTS:
    _fam(_n, ("IN", "N"))
_fam("SEL", ("G", "IN0", "IN1"))
_fam("MAX", ("IN1", "IN2"), extensible=True)
_fam("MIN", ("IN1", "IN2"), extensible=True)
_fam("LIMIT", ("MN", "IN", "MX"))
_fam("MUX", ("K", "IN0", "IN1"), extensible=True, min_args=2)
for _n in CMP_EXT:
    _fam(_n, ("IN1", "IN2"), extensible=True)
_fam("NE", ("IN1", "IN2"))
_fam("LEN", ("IN",))
_fam("LEFT", ("IN", "L"))
_fam("RIGHT", ("IN", "L"))
_fam("MID", ("IN", "L", "P"))
_fam("CONCAT", ("IN1", "IN2"), extensible=True, min_args=1)
_fam("INSERT", ("IN1", "IN2", "P"))
_fam("DELETE", ("IN", "L", "P"))
_fam("REPLACE", ("IN1", "IN2", "L", "P"))
_fam("FIND", ("IN1", "IN2"))
_fam("MULTIME", ("IN1", "IN2"))
_fam("DIVTIME", ("IN1", "IN2"))
_fam("CONCAT_DATE_TOD", ("IN1", "IN2"))
CONV = Family("CONV", ("IN",), False, 1)

# the standard functions a user FUNCTION may be named after: iec2c builds such a FUNCTION, but wherever the
# name is called it calls its own standard function (measured: docs/builtin-compiler.md). The others are
# operators to iec2c ("Function overloading not allowed") or clash with its C (CONCAT, CONCAT_DATE_TOD).
USER_NAMEABLE = frozenset(FAMILIES) - {"AND", "OR", "XOR", "NOT", "MOD", "CONCAT", "CONCAT_DATE_TOD"}


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


# ------------------------------------------------------------------ conversions (MatIEC's set)

_NUMBIT = T.NUMS + T.BITS          # ANY_NUM + ANY_BIT (with BOOL)
_TIMEDATE = (T.TIME,) + T.DATES


def _conversion_table() -> dict[str, tuple[T.Elem, T.Elem]]:
    table: dict[str, tuple[T.Elem, T.Elem]] = {}

    def add(src, dst, name=None):
        table[name or f"{src.name}_TO_{dst.name}"] = (src, dst)

    for a in _NUMBIT:
        for b in _NUMBIT:
            add(a, b)
        for b in _TIMEDATE:
            add(a, b)
        add(a, T.STRING)
        add(T.STRING, a)
    for a in _TIMEDATE:
        for b in _NUMBIT:
            add(a, b)
        add(a, T.STRING)
        add(T.STRING, a)
    add(T.DT, T.DATE)
    add(T.DT, T.DT)
    add(T.DT, T.TOD)
    add(T.DATE, T.DATE)
    add(T.TOD, T.TOD)
    add(T.TIME, T.TIME)
    add(T.DT, T.DATE, "DATE_AND_TIME_TO_DATE")
    add(T.DT, T.TOD, "DATE_AND_TIME_TO_TIME_OF_DAY")
    return table


CONVERSIONS = _conversion_table()
# BCD: X_BCD_TO_U (X in BYTE..LWORD, U in USINT..ULINT); U_TO_BCD_X; overloaded BCD_TO_U / U_TO_BCD
BCD_DECODE = {f"{b.name}_BCD_TO_{u.name}": (b, u) for b in T.NBITS for u in T.UNSIGNED_INTS}
BCD_ENCODE = {f"{u.name}_TO_BCD_{b.name}": (u, b) for b in T.NBITS for u in T.UNSIGNED_INTS}
BCD_DECODE_GENERIC = {f"BCD_TO_{u.name}": u for u in T.UNSIGNED_INTS}
BCD_ENCODE_GENERIC = {f"{u.name}_TO_BCD": u for u in T.UNSIGNED_INTS}

# families that accept a type suffix (ADD_INT, MAX_STRING, ...), and which types they allow
_ELEM_FOR_SEL = T.NUMS + T.BITS + (T.TIME, T.STRING) + T.DATES
SUFFIXED = {
    "ADD": T.NUMS, "MUL": T.NUMS, "SUB": T.NUMS, "DIV": T.NUMS, "MOD": T.INTS, "ABS": T.NUMS,
    "SQRT": T.REALS, "LN": T.REALS, "LOG": T.REALS, "EXP": T.REALS, "SIN": T.REALS, "COS": T.REALS,
    "TAN": T.REALS, "ASIN": T.REALS, "ACOS": T.REALS, "ATAN": T.REALS,
    "AND": T.BITS, "OR": T.BITS, "XOR": T.BITS, "NOT": T.BITS,
    "MOVE": _ELEM_FOR_SEL, "SEL": _ELEM_FOR_SEL, "MAX": _ELEM_FOR_SEL, "MIN": _ELEM_FOR_SEL,
    "LIMIT": _ELEM_FOR_SEL, "GT": _ELEM_FOR_SEL, "GE": _ELEM_FOR_SEL, "EQ": _ELEM_FOR_SEL,
    "LE": _ELEM_FOR_SEL, "LT": _ELEM_FOR_SEL, "NE": _ELEM_FOR_SEL,
    "MULTIME": T.NUMS, "DIVTIME": T.NUMS,
}
# ADD_TIME, ADD_TOD_TIME, SUB_DATE_DATE... : (family, (arg types), result)
TIME_ARITH = {
    "ADD_TIME": ("ADD", (T.TIME, T.TIME), T.TIME),
    "ADD_TOD_TIME": ("ADD", (T.TOD, T.TIME), T.TOD),
    "ADD_DT_TIME": ("ADD", (T.DT, T.TIME), T.DT),
    "SUB_TIME": ("SUB", (T.TIME, T.TIME), T.TIME),
    "SUB_DATE_DATE": ("SUB", (T.DATE, T.DATE), T.TIME),
    "SUB_TOD_TIME": ("SUB", (T.TOD, T.TIME), T.TOD),
    "SUB_TOD_TOD": ("SUB", (T.TOD, T.TOD), T.TIME),
    "SUB_DT_TIME": ("SUB", (T.DT, T.TIME), T.DT),
    "SUB_DT_DT": ("SUB", (T.DT, T.DT), T.TIME),
}


def _missing_in_matiec_c() -> set[str]:
    """Names MatIEC's standard_functions.txt declares but its C headers never define (its C then does not
    compile): the explicitly typed MUX_<K>_<T>, and the BOOL variants of the comparisons, LIMIT and MIN."""
    names = {f"MUX_{k.name}_{t.name}" for k in T.INTS for t in _ELEM_FOR_SEL}
    names |= {f"{f}_BOOL" for f in ("EQ", "GE", "GT", "LE", "LT", "LIMIT", "MIN")}
    return names


@dataclass
class Lookup:
    family: Family
    fixed: T.Elem | None = None               # the type variable, fixed by a suffix
    conv: tuple[T.Elem, T.Elem] | None = None
    kind: str = ""                            # "", "conv", "bcd_decode", "bcd_encode", "time_arith", "mux_k"
    extra: Any = None


def lookup(name: str) -> Lookup | None:
    """The standard function called `name` (upper case), or None (also for MISSING_IN_MATIEC_C)."""
    if name in MISSING_IN_MATIEC_C:
        return None
    if name in FAMILIES:
        return Lookup(FAMILIES[name])
    if name in CONVERSIONS:
        return Lookup(CONV, conv=CONVERSIONS[name], kind="conv")
    if name in BCD_DECODE:
        return Lookup(CONV, conv=BCD_DECODE[name], kind="bcd_decode")
    if name in BCD_ENCODE:
        return Lookup(CONV, conv=BCD_ENCODE[name], kind="bcd_encode")
    if name in BCD_DECODE_GENERIC:
        return Lookup(CONV, kind="bcd_decode", extra=BCD_DECODE_GENERIC[name])
    if name in BCD_ENCODE_GENERIC:
        return Lookup(CONV, kind="bcd_encode", extra=BCD_ENCODE_GENERIC[name])
    if name in TIME_ARITH:
        fam, args, res = TIME_ARITH[name]
        return Lookup(FAMILIES[fam], kind="time_arith", extra=(args, res))
    m = re.fullmatch(r"MUX_([A-Z]+)_([A-Z]+)", name)
    if m and m.group(1) in T.ELEMENTARY and m.group(2) in T.ELEMENTARY:
        k, t = T.ELEMENTARY[m.group(1)], T.ELEMENTARY[m.group(2)]
        if k in T.INTS and t in _ELEM_FOR_SEL:
            return Lookup(FAMILIES["MUX"], fixed=t, kind="mux_k", extra=k)
    base, _, suffix = name.rpartition("_")
    if base in SUFFIXED and suffix in T.ELEMENTARY and T.ELEMENTARY[suffix] in SUFFIXED[base]:
        return Lookup(FAMILIES[base], fixed=T.ELEMENTARY[suffix])
    return None


def is_std_function(name: str) -> bool:
    return lookup(name.upper()) is not None


@dataclass
class StdCall:
    """What the checker resolved a standard function call to, for the code generator."""
    name: str                   # the family (ADD, CONV, ...)
    args: list                  # argument expressions in formal order
    ty: T.Type | None = None    # the family's type variable after resolution
    conv: tuple | None = None   # (src, dst) of a conversion
    kind: str = ""
    extra: Any = None
    en: Any = None              # EN := expression, or None
    eno: Any = None             # ENO => variable, or None
    tvar_args: list = field(default_factory=list)   # the arguments that share the type variable
    pred: Any = None            # (predicate on the type variable, description)


MISSING_IN_MATIEC_C = _missing_in_matiec_c()


def missing_overload_in_matiec_c(name: str, params: list[str] | tuple[str, ...]) -> bool:
    """An overload MatIEC's library declares whose C iec2c calls by a name its headers do not define: a
    shift or rotate of a BOOL (iec2c calls SHL__BOOL__BOOL__SINT; iec_std_functions.h defines SHL__BOOL__SINT).
    The checker refuses it (`_shiftable`), case reject_shift_bool."""
    return name in SHIFTS and bool(params) and params[0] == "BOOL"
