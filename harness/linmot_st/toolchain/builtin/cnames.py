"""The C types of IEC types, as the generated C declares and computes them (codegen.py, stdfuncs/c.py)."""

from __future__ import annotations

from . import types as T


def cname_of(t: T.Type) -> str:
    """C storage type of an IEC type."""
    t = t.base() if isinstance(t, (T.Alias, T.Subrange)) else t
    if isinstance(t, T.Pseudo):
        t = t.default
    return t.cname


def is_time(t: T.Type) -> bool:
    return T.is_time_like(t)


def vtype(t: T.Type) -> str:
    """C type of a value of t in an expression."""
    return "__ns_t" if is_time(t) else cname_of(t)
