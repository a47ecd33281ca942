"""The overloads of the standard functions: which names call which family with which types.

The families (table.py) are called by their name (ADD), by a typed variant that fixes the family's type
variable (ADD_INT, MUX_DINT_INT), or, for the conversions, by one of MatIEC's `X_TO_Y` names, derived from
rules that reproduce MatIEC's set (tests/toolchain/builtin/test_builtin_stdlib.py compares the two where MatIEC is installed);
the durations' and dates' arithmetic has its own names (ADD_TOD_TIME...). `lookup` resolves a name, and the
checker records what it resolved a call to as a `StdCall` for the code generator.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

from .. import types as T
from .table import CONV, ELEM_FOR_SEL, FAMILIES, Family

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

# the typed variants (ADD_INT, MAX_STRING, ...): the types each family's suffix may name (its row's `suffixes`)
SUFFIXED = {f.name: f.suffixes for f in FAMILIES.values() if f.suffixes}
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
    names = {f"MUX_{k.name}_{t.name}" for k in T.INTS for t in ELEM_FOR_SEL}
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
        if k in T.INTS and t in ELEM_FOR_SEL:
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
    The checker refuses it (table.shiftable), case reject_shift_bool."""
    shift = name in FAMILIES and FAMILIES[name].rule == "shift"
    return shift and bool(params) and params[0] == "BOOL"
