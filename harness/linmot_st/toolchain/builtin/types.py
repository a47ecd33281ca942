"""The IEC 61131-3 type system of the builtin compiler (strict, as MatIEC: no implicit conversions).

Elementary types have MatIEC's C layout. Derived types: enumerations, arrays (compared by identity,
i.e. by name: two ARRAY declarations are two types even when they look alike, as in MatIEC without
-l), structures, subranges and aliases of elementary types (both compatible with their base type,
as in MatIEC), function block and program types.

Untyped literals get a *pseudo* type (LIT_INT, LIT_REAL) until their context fixes the type; a few
standard functions overloaded on their result type (LEN, FIND, TRUNC, *_TO_BCD) get a pseudo type too.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


class Type:
    # subclasses define `name` and `cname`

    def base(self) -> Type:
        """The type used for compatibility: subranges and aliases resolve to their base."""
        return self

    def __repr__(self) -> str:
        return self.name


@dataclass(eq=False, repr=False)
class Elem(Type):
    name: str
    cname: str
    kind: str           # bool sint uint bit real time date tod dt string
    bits: int = 0

    @property
    def lo(self) -> int:
        if self.kind == "sint":
            return -(1 << (self.bits - 1))
        return 0

    @property
    def hi(self) -> int:
        if self.kind == "sint":
            return (1 << (self.bits - 1)) - 1
        if self.kind == "bool":
            return 1
        return (1 << self.bits) - 1


def _e(name, kind, bits=0, cname=None):
    return Elem(name, cname or name, kind, bits)


BOOL = _e("BOOL", "bool", 8)
SINT, INT, DINT, LINT = _e("SINT", "sint", 8), _e("INT", "sint", 16), _e("DINT", "sint", 32), _e("LINT", "sint", 64)
USINT, UINT, UDINT, ULINT = _e("USINT", "uint", 8), _e("UINT", "uint", 16), _e("UDINT", "uint", 32), _e("ULINT", "uint", 64)
BYTE, WORD, DWORD, LWORD = _e("BYTE", "bit", 8), _e("WORD", "bit", 16), _e("DWORD", "bit", 32), _e("LWORD", "bit", 64)
REAL, LREAL = _e("REAL", "real", 32), _e("LREAL", "real", 64)
TIME, DATE, TOD, DT = _e("TIME", "time", 64), _e("DATE", "date", 64), _e("TOD", "tod", 64), _e("DT", "dt", 64)
STRING = _e("STRING", "string", 0)

ELEMENTARY: dict[str, Elem] = {t.name: t for t in (
    BOOL, SINT, INT, DINT, LINT, USINT, UINT, UDINT, ULINT, BYTE, WORD, DWORD, LWORD, REAL, LREAL,
    TIME, DATE, TOD, DT, STRING)}
# long spellings of the date and time types
ELEMENTARY_ALIASES = {"TIME_OF_DAY": TOD, "DATE_AND_TIME": DT}

SIGNED_INTS = (SINT, INT, DINT, LINT)
UNSIGNED_INTS = (USINT, UINT, UDINT, ULINT)
INTS = SIGNED_INTS + UNSIGNED_INTS
NBITS = (BYTE, WORD, DWORD, LWORD)
BITS = (BOOL,) + NBITS
REALS = (REAL, LREAL)
NUMS = REALS + INTS
DATES = (DATE, TOD, DT)

# elementary types not in this subset (MatIEC has no WSTRING/CHAR)
UNSUPPORTED_ELEMENTARY = {"WSTRING", "CHAR", "WCHAR", "LTIME", "LDATE", "LTOD", "LDT", "LTIME_OF_DAY",
                          "LDATE_AND_TIME", "ANY", "ANY_INT", "ANY_NUM", "ANY_REAL", "ANY_BIT", "ANY_STRING",
                          "ANY_DATE", "ANY_ELEMENTARY", "ANY_MAGNITUDE", "ANY_DERIVED"}

STR_MAX_LEN = 126


def is_int(t: Type) -> bool:
    t = t.base()
    return isinstance(t, Elem) and t.kind in ("sint", "uint")


def is_signed(t: Type) -> bool:
    t = t.base()
    return isinstance(t, Elem) and t.kind in ("sint", "real")


def is_bit(t: Type) -> bool:
    """ANY_BIT: BOOL, BYTE, WORD, DWORD, LWORD."""
    t = t.base()
    return isinstance(t, Elem) and t.kind in ("bool", "bit")


def is_real(t: Type) -> bool:
    t = t.base()
    return isinstance(t, Elem) and t.kind == "real"


def is_num(t: Type) -> bool:
    return is_int(t) or is_real(t)


def is_time_like(t: Type) -> bool:
    t = t.base()
    return isinstance(t, Elem) and t.kind in ("time", "date", "tod", "dt")


def is_elementary(t: Type) -> bool:
    return isinstance(t.base(), Elem)


@dataclass(eq=False, repr=False)
class Enum(Type):
    name: str
    values: list[str]          # upper case, in order (0, 1, ...)
    spelled: list[str]         # as declared
    cname: str = ""

    def __post_init__(self):
        self.cname = self.name


@dataclass(eq=False, repr=False)
class Array(Type):
    name: str                  # the declared name, or a generated one for an anonymous array
    elem: Type
    dims: list[tuple[int, int]]
    cname: str = ""
    anonymous: bool = False

    @property
    def count(self) -> int:
        n = 1
        for lo, hi in self.dims:
            n *= hi - lo + 1
        return n


@dataclass(eq=False)
class Field:
    name: str                  # as declared
    key: str
    ty: Type
    init: Any                  # AST init value or None
    pos: Any = None


@dataclass(eq=False, repr=False)
class Struct(Type):
    name: str
    fields: list[Field] = field(default_factory=list)
    cname: str = ""

    def field(self, key: str) -> Field | None:
        for f in self.fields:
            if f.key == key:
                return f
        return None


@dataclass(eq=False, repr=False)
class Subrange(Type):
    """INT(0..100), named or not. Compatible with its base (MatIEC); its default value is `lo`."""
    name: str
    of: Elem
    lo: int
    hi: int

    @property
    def cname(self) -> str:       # type: ignore[override]
        return self.of.cname

    def base(self) -> Type:
        return self.of


@dataclass(eq=False, repr=False)
class Alias(Type):
    """TYPE MyInt : INT := 7; END_TYPE: compatible with INT, with its own default value."""
    name: str
    of: Type
    init: Any = None

    @property
    def cname(self) -> str:       # type: ignore[override]
        return self.of.cname

    def base(self) -> Type:
        return self.of.base()


@dataclass(eq=False, repr=False)
class PouType(Type):
    """The type of a FUNCTION_BLOCK instance, or of a PROGRAM (its instance struct)."""
    name: str
    pou: Any                   # checker.PouSym
    cname: str = ""

    def __post_init__(self):
        self.cname = self.name


@dataclass(eq=False, repr=False)
class Pseudo(Type):
    """The type of an untyped literal, or of a call overloaded on its result, until its context fixes it."""
    name: str
    accepts: tuple[Type, ...]
    default: Elem
    literal: bool              # a constant whose value must fit the type it settles to

    @property
    def cname(self) -> str:       # type: ignore[override]
        return self.default.cname


class ErrorType(Type):
    """The type of a name whose declaration was rejected: its uses are not checked (nor reported)."""
    name = cname = "<error>"


ERROR = ErrorType()

LIT_INT = Pseudo("integer literal", INTS + BITS, DINT, True)
LIT_REAL = Pseudo("real literal", REALS, LREAL, True)


def poly(accepts: tuple[Type, ...], default: Elem) -> Pseudo:
    return Pseudo("/".join(t.name for t in accepts) if len(accepts) < 4 else "ANY_INT", accepts, default, False)


def same(a: Type, b: Type) -> bool:
    """Assignment compatibility: the same type (subranges and aliases count as their base)."""
    return a.base() is b.base()


def describe(t: Type) -> str:
    if isinstance(t, Array) and t.anonymous:
        dims = ", ".join(f"{lo}..{hi}" for lo, hi in t.dims)
        return f"ARRAY[{dims}] OF {describe(t.elem)}"
    if isinstance(t, Subrange):
        return t.name
    return t.name


def fits(value: int, t: Type) -> bool:
    t = t.base()
    if isinstance(t, Elem) and t.kind in ("sint", "uint", "bit", "bool"):
        return t.lo <= value <= t.hi
    return False
