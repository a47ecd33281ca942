"""The parameter store: every UPID with its type, ROM, RAM, default, min, max, live flag and access rights.

Rules (seeds 2.3..2.5): the drive works with RAM values; ROM is copied to RAM when the firmware starts. Over the
bus the RAM value of a non-live parameter cannot be written; ROM can be written while the firmware runs, except
read-only parameters. Every value goes through the bus as 32 bits and is masked to the parameter's width.
"""

from __future__ import annotations

from bisect import bisect_left
from collections.abc import Callable
from dataclasses import dataclass

from .paramtypes import stringlets_of, text_of
from .profile import ParamDef


class ParameterError(Exception):
    """Base of the store's refusals; the SDO layer turns each into an abort code."""


class UnknownUpid(ParameterError):
    pass


class NoValueAccess(ParameterError):
    """A string header has no 32-bit value: its stringlets carry the text."""


class NotWritable(ParameterError):
    pass


class OutOfRange(ParameterError):
    pass


@dataclass
class Parameter:
    d: ParamDef
    rom: int
    ram: int

    # read-only views of the definition, for inspection
    upid = property(lambda self: self.d.upid)
    name = property(lambda self: self.d.name)
    kind = property(lambda self: self.d.kind)
    type = property(lambda self: self.d.type)
    default = property(lambda self: self.d.default)
    min = property(lambda self: self.d.min)
    max = property(lambda self: self.d.max)
    live = property(lambda self: self.d.live)
    access = property(lambda self: self.d.access)
    layer = property(lambda self: self.d.layer)
    address_usage = property(lambda self: self.d.address_usage)

    @property
    def modified(self) -> bool:
        """ROM differs from default (what the modified-UPID list reports)."""
        return self.d.kind == "par" and self.rom != self.d.default


class ParameterStore:
    stringlet_offset = 1                        # stringlet k at string UPID + k - 1 + offset (B1100: 0)

    def __init__(self, definitions: list[ParamDef]):
        self._p: dict[int, Parameter] = {d.upid: Parameter(d, d.default, d.default) for d in definitions}
        self.by_upid = self._p                  # read-only view for the MC's per-cycle parameter reads
        self._order = sorted(self._p)
        self._strings = {d.upid: d for d in definitions if d.kind == "string"}
        self.live: Callable[[int], int | None] | None = None   # the drive's variables now (the MC's provider)
        self.rom_writes = 0                     # ROM writes over the bus (02h, 06h), kept across boots

    # ---- lookup ----
    def __getitem__(self, upid: int) -> Parameter:
        try:
            return self._p[upid]
        except KeyError:
            raise UnknownUpid(f"no parameter with UPID {upid:04X}h") from None

    def __contains__(self, upid: int) -> bool:
        return upid in self._p

    def __iter__(self):
        return (self._p[u] for u in self._order)

    def __len__(self) -> int:
        return len(self._order)

    def upids(self) -> list[int]:
        return list(self._order)

    def next_entry(self, start: int, modified_only: bool = False) -> Parameter | None:
        """The first UPID >= start (of the modified ones, with modified_only), or None at the end."""
        i = bisect_left(self._order, start)
        while i < len(self._order):
            p = self._p[self._order[i]]
            if not modified_only or p.modified:
                return p
            i += 1
        return None

    # ---- firmware start ----
    def load_ram_from_rom(self, layers: set[int] | None = None) -> None:
        for p in self._p.values():
            if p.d.kind == "par" and (layers is None or p.d.layer in layers):
                p.ram = p.rom

    def set_layer_default(self, layer: int) -> int:
        """Set the ROM value of every writable parameter of `layer` to its default; returns how many changed."""
        n = 0
        for p in self._p.values():
            if p.d.layer == layer and p.d.kind == "par" and p.d.access == "rw" and p.rom != p.d.default:
                p.rom = p.d.default
                n += 1
        return n

    # ---- 32-bit access as over the bus ----
    def _value_param(self, upid: int) -> Parameter:
        p = self[upid]
        if p.d.kind == "string":
            raise NoValueAccess(f"UPID {upid:04X}h is a string: access its stringlets {upid + 1:04X}h..")
        return p

    def read(self, upid: int, what: str) -> int:
        """The raw 32-bit value of 'ram', 'rom', 'min', 'max' or 'default'."""
        p = self._value_param(upid)
        if what == "rom" and p.d.kind == "var":
            raise NoValueAccess(f"UPID {upid:04X}h is a variable: it has no ROM value")
        if what == "ram" and p.d.kind == "var" and self.live is not None:
            v = self.live(upid)
            if v is not None:
                return p.d.type.to_raw(v)
        value = {"ram": p.ram, "rom": p.rom, "min": p.d.min, "max": p.d.max, "default": p.d.default}[what]
        return p.d.type.to_raw(value)

    def _checked(self, p: Parameter, raw32: int) -> int:
        value = p.d.type.from_raw(raw32)
        if not p.d.min <= value <= p.d.max:
            raise OutOfRange(f"UPID {p.d.upid:04X}h: {value} outside {p.d.min} .. {p.d.max}")
        return value

    def write(self, upid: int, raw32: int, ram: bool, rom: bool) -> None:
        """Write RAM and/or ROM as the bus does: masked to the width, range checked, all or nothing."""
        p = self._value_param(upid)
        if p.d.kind == "var" or p.d.access != "rw":
            raise NotWritable(f"UPID {upid:04X}h is read only")
        if ram and not p.d.live:
            raise NotWritable(f"UPID {upid:04X}h is not live: its RAM value cannot be written over the bus")
        value = self._checked(p, raw32)
        if ram:
            p.ram = value
        if rom:
            p.rom = value
            self.rom_writes += 1            # the parameter store is non-volatile too: writes are counted

    def set_variable(self, upid: int, value: int) -> None:
        """The drive's own update of a variable (status word, state var...)."""
        p = self._p.get(upid)
        if p is not None:
            p.ram = p.d.type.from_raw(value)

    # ---- strings (inspection and test setup) ----
    def use_strings(self, headers: list[ParamDef], stringlet_offset: int) -> None:
        """A drive whose string UPID is its first stringlet (B1100) has no header rows: give them here."""
        self._strings = {d.upid: d for d in headers}
        self.stringlet_offset = stringlet_offset

    def string(self, upid: int, which: str = "rom") -> str:
        d = self._strings[upid]
        o = self.stringlet_offset - 1
        return text_of([getattr(self._p[upid + k + o], which) for k in range(1, d.stringlets + 1)])

    def set_string(self, upid: int, text: str, which: str = "both") -> None:
        d = self._strings[upid]
        for k, v in enumerate(stringlets_of(text, d.stringlets), start=1):
            p = self._p[upid + k - 1 + self.stringlet_offset]
            if which in ("rom", "both"):
                p.rom = v
            if which in ("ram", "both"):
                p.ram = v
