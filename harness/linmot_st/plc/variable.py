"""Bound accessors: a path resolved once, read and written through a ctypes object at a fixed address.

`Plc.var(path)` returns one of these; the elementary kinds read and write with no lookup at all, which is
what keeps one step plus a few I/O accesses within microseconds.
"""

from __future__ import annotations

import ctypes
from typing import Any

from .access import FORCE_FLAG, Target, check_integer, enum_name, read_value, write_value
from .layout import INTEGER_RANGES, TypeInfo


class Var:
    """A variable of a loaded PLC. `value` reads and writes it; `force`/`unforce` pin it."""

    __slots__ = ("path", "type", "_addr", "_info", "_flags", "_owner", "_view")

    def __init__(self, target: Target, owner: Any = None):
        self.path = target.path
        self.type = target.info.name or target.info.kind
        self._addr = target.addr
        self._info = target.info
        self._owner = owner   # keeps the library (and so the memory) alive
        self._flags = None
        self._view: memoryview | None = None
        if target.wrapper_addr is not None:
            offset = target.wrapper_info.ctype.flags.offset
            self._flags = ctypes.c_uint8.from_address(target.wrapper_addr + offset)

    @property
    def value(self) -> Any:
        return read_value(self._addr, self._info)

    @value.setter
    def value(self, v: Any) -> None:
        write_value(self._addr, self._info, v, self.path)

    @property
    def forced(self) -> bool:
        return bool(self._flags is not None and self._flags.value & FORCE_FLAG)

    def force(self, value: Any) -> None:
        """Write `value` and set the force flag: the PLC's own writes to it are skipped until unforce()."""
        if self._flags is None:
            raise TypeError(f"{self.path} cannot be forced: only a whole variable (a POU variable or a "
                            f"global, not an element or member inside one) carries a force flag")
        self.value = value
        self._flags.value |= FORCE_FLAG

    def unforce(self) -> None:
        if self._flags is not None:
            self._flags.value &= ~FORCE_FLAG & 0xFF

    @property
    def address(self) -> int:
        """Where the value lives in the PLC's memory (for bulk ctypes access, e.g. ctypes.memmove)."""
        return self._addr

    @property
    def nbytes(self) -> int:
        return self._info.size

    @property
    def info(self) -> TypeInfo:
        """The value's resolved type (its C layout: the offsets of its members, its elements' size)."""
        return self._info

    def view(self) -> memoryview:
        """The value's bytes in the PLC's memory as a writable memoryview (made once): struct.pack_into and
        unpack_from work on it in one call, where a ctypes memmove or string_at costs a foreign call each."""
        if self._view is None:
            self._view = memoryview((ctypes.c_char * self._info.size).from_address(self._addr)).cast("B")
        return self._view

    def read_bytes(self) -> bytes:
        """The value's raw C bytes (an ARRAY OF BYTE is its bytes, in index order)."""
        return (self._view or self.view()).tobytes()

    def write_bytes(self, data: bytes) -> None:
        """Overwrite the value's leading bytes with `data` (at most its size)."""
        if len(data) > self._info.size:
            raise ValueError(f"{self.path}: {len(data)} bytes do not fit its {self._info.size}")
        (self._view or self.view())[:len(data)] = data

    def __repr__(self) -> str:
        return f"<Var {self.path}: {self.type} = {self.value!r}>"


class IntVar(Var):
    __slots__ = ("_c", "_lo", "_hi")

    def __init__(self, target: Target, owner: Any = None):
        super().__init__(target, owner)
        self._c = target.info.ctype.from_address(target.addr)
        self._lo, self._hi = INTEGER_RANGES[target.info.name]

    @property
    def value(self) -> int:
        return self._c.value

    @value.setter
    def value(self, v: int) -> None:
        if type(v) is not int or not self._lo <= v <= self._hi:
            check_integer(self._info.name, v, self.path)   # raises the clear error
        self._c.value = v


class BoolVar(Var):
    __slots__ = ("_c",)

    def __init__(self, target: Target, owner: Any = None):
        super().__init__(target, owner)
        self._c = ctypes.c_uint8.from_address(target.addr)

    @property
    def value(self) -> bool:
        return self._c.value != 0

    @value.setter
    def value(self, v: bool) -> None:
        if v is True or v is False or v in (0, 1):
            self._c.value = 1 if v else 0
        else:
            raise TypeError(f"{self.path} is BOOL: assign True or False, not {v!r}")


class RealVar(Var):
    __slots__ = ("_c",)

    def __init__(self, target: Target, owner: Any = None):
        super().__init__(target, owner)
        self._c = target.info.ctype.from_address(target.addr)

    @property
    def value(self) -> float:
        return self._c.value

    @value.setter
    def value(self, v: float) -> None:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise TypeError(f"{self.path} is {self._info.name}: assign a number, not {v!r}")
        self._c.value = v


class EnumVar(Var):
    """An enumerated variable: reads its value's name (the number itself when out of range), writes either."""

    __slots__ = ("_c", "_names")

    def __init__(self, target: Target, owner: Any = None):
        super().__init__(target, owner)
        self._c = ctypes.c_int.from_address(target.addr)
        self._names = tuple(target.info.values)

    @property
    def value(self) -> Any:
        return enum_name(self._names, self._c.value)

    @value.setter
    def value(self, v: Any) -> None:
        write_value(self._addr, self._info, v, self.path)


def make_var(target: Target, owner: Any = None) -> Var:
    info = target.info
    if info.kind == "enum":
        return EnumVar(target, owner)
    if info.kind == "elementary":
        if info.name == "BOOL":
            return BoolVar(target, owner)
        if info.name in INTEGER_RANGES:
            return IntVar(target, owner)
        if info.name in ("REAL", "LREAL"):
            return RealVar(target, owner)
    return Var(target, owner)
