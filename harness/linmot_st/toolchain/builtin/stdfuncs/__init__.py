"""The standard functions of IEC 61131-3 as MatIEC provides them, in one place: table.py (one row per family:
formal parameters, typing rule, accepted types, typed variants, result, C), overloads.py (the names that call a
family: typed variants, conversions, BCD, the durations' arithmetic; `lookup`) and c.py (the C emitters the
rows name). The checker (checker/std_calls.py) applies a row's typing rule to a call and records a `StdCall`
on it; the code generator turns that into C with `c_call`.
"""

from __future__ import annotations

from . import c as _c
from .overloads import MISSING_IN_MATIEC_C, Lookup, StdCall, is_std_function, lookup, missing_overload_in_matiec_c
from .table import CONV, FAMILIES, UNSUPPORTED_FUNCTIONS, USER_NAMEABLE, Family, param_names, string_layout

__all__ = [
    "CONV", "FAMILIES", "MISSING_IN_MATIEC_C", "UNSUPPORTED_FUNCTIONS", "USER_NAMEABLE", "Family", "Lookup", "StdCall",
    "c_call", "family_of", "is_std_function", "lookup", "missing_overload_in_matiec_c", "param_names", "string_layout",
]


def family_of(sc: StdCall) -> Family:
    """The row of the family a checked call resolved to."""
    return CONV if sc.name == "CONV" else FAMILIES[sc.name]


def c_call(gen, e, sc: StdCall) -> str:
    """The C of a checked standard function call (gen: the code generator)."""
    return _c.call(gen, e, sc, family_of(sc))
