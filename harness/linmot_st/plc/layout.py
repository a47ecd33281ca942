"""ctypes types for the data layout a build's manifest describes (docs/architecture.md 1.1).

A type reference is an elementary IEC name, a name in the manifest's `types`, `var:T` (MatIEC's
`{T value; BYTE flags}`), `ptr:T` (`{T *value; BYTE flags}`) or `ref:T` (a bare `T *`, MatIEC's
VAR_EXTERNAL of a function block type). The layout of the elementary types is MatIEC's, for both backends.
"""

from __future__ import annotations

import ctypes
import json
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any


class LayoutError(Exception):
    """The manifest is malformed, or does not match the compiled library."""


STRING_CAPACITY = 126   # MatIEC's STR_MAX_LEN


class IecTime(ctypes.Structure):
    _fields_ = [("tv_sec", ctypes.c_long), ("tv_nsec", ctypes.c_long)]


class IecString(ctypes.Structure):
    _fields_ = [("len", ctypes.c_uint8), ("body", ctypes.c_uint8 * STRING_CAPACITY)]


INTEGER_CTYPES: dict[str, Any] = {
    "SINT": ctypes.c_int8, "INT": ctypes.c_int16, "DINT": ctypes.c_int32, "LINT": ctypes.c_int64,
    "USINT": ctypes.c_uint8, "UINT": ctypes.c_uint16, "UDINT": ctypes.c_uint32, "ULINT": ctypes.c_uint64,
    "BYTE": ctypes.c_uint8, "WORD": ctypes.c_uint16, "DWORD": ctypes.c_uint32, "LWORD": ctypes.c_uint64,
}
ELEMENTARY_CTYPES: dict[str, Any] = {
    **INTEGER_CTYPES,
    "BOOL": ctypes.c_uint8,
    "REAL": ctypes.c_float, "LREAL": ctypes.c_double,
    "TIME": IecTime, "DATE": IecTime, "TOD": IecTime, "DT": IecTime,
    "STRING": IecString,
}
INTEGER_RANGES = {
    name: ((-(1 << (8 * ctypes.sizeof(ct) - 1)), (1 << (8 * ctypes.sizeof(ct) - 1)) - 1)
           if name in ("SINT", "INT", "DINT", "LINT") else (0, (1 << (8 * ctypes.sizeof(ct))) - 1))
    for name, ct in INTEGER_CTYPES.items()
}
TIME_TYPES = ("TIME", "DATE", "TOD", "DT")


@dataclass
class TypeInfo:
    """One resolved type: its ctypes class and what path access needs to know about it."""

    ref: str                      # the type reference as written in the manifest
    kind: str                     # elementary | enum | array | struct | fb | program | var | ptr | ref
    ctype: Any
    name: str = ""                # elementary name, or the manifest type name
    inner: TypeInfo | None = None  # var/ptr/ref: the wrapped type; array: the element type
    dims: list[tuple[int, int]] = field(default_factory=list)   # array: [(lower, upper)] per dimension
    fields: dict[str, tuple[int, TypeInfo]] = field(default_factory=dict)  # struct/fb/program: NAME -> (offset, type)
    field_order: list[str] = field(default_factory=list)
    values: list[str] = field(default_factory=list)   # enum

    @property
    def size(self) -> int:
        return ctypes.sizeof(self.ctype)


# The resolved types of the manifests loaded last, by their type declarations: a second Plc of the same build (each
# test, each run of a job) finds its ctypes classes made (plc_project's: ~45 ms to build). TypeInfo is not changed
# once built, so Layouts of equal declarations share it; the oldest entry goes beyond SHARED_LAYOUTS.
SHARED_LAYOUTS = 16
_shared: OrderedDict[str, dict[str, TypeInfo]] = OrderedDict()


class Layout:
    """Every type of a manifest as ctypes, built on demand and memoised by reference."""

    def __init__(self, manifest: dict):
        if manifest.get("schema") != 1:
            raise LayoutError(f"manifest schema {manifest.get('schema')!r} is not supported (expected 1)")
        self.types: dict[str, dict] = {k.upper(): v for k, v in manifest.get("types", {}).items()}
        key = json.dumps(self.types, sort_keys=True)
        resolved = _shared.pop(key, None)
        self._resolved: dict[str, TypeInfo] = {} if resolved is None else resolved
        _shared[key] = self._resolved             # the newest last
        while len(_shared) > SHARED_LAYOUTS:
            _shared.popitem(last=False)
        self._building: set[str] = set()

    def resolve(self, ref: str) -> TypeInfo:
        key = ref.upper()
        info = self._resolved.get(key)
        if info is None:
            if key in self._building:
                raise LayoutError(f"type {ref} contains itself")
            self._building.add(key)
            try:
                info = self._build(key)
            finally:
                self._building.discard(key)
            self._resolved[key] = info
        return info

    def _build(self, ref: str) -> TypeInfo:
        prefix, _, rest = ref.partition(":")
        if rest:
            inner = self.resolve(rest)
            if prefix == "VAR":
                ct = type(f"var_{_ident(rest)}", (ctypes.Structure,),
                          {"_fields_": [("value", inner.ctype), ("flags", ctypes.c_uint8)]})
                return TypeInfo(ref, "var", ct, inner=inner)
            if prefix == "PTR":
                ct = type(f"ptr_{_ident(rest)}", (ctypes.Structure,),
                          {"_fields_": [("value", ctypes.c_void_p), ("flags", ctypes.c_uint8)]})
                return TypeInfo(ref, "ptr", ct, inner=inner)
            if prefix == "REF":
                return TypeInfo(ref, "ref", ctypes.c_void_p, inner=inner)
            raise LayoutError(f"unknown type reference prefix in {ref!r}")
        if ref in ELEMENTARY_CTYPES:
            return TypeInfo(ref, "elementary", ELEMENTARY_CTYPES[ref], name=ref)
        decl = self.types.get(ref)
        if decl is None:
            raise LayoutError(f"type {ref} is neither elementary nor declared in the manifest")
        kind = decl.get("kind")
        if kind == "enum":
            values = [str(v).upper() for v in decl.get("values", [])]
            return TypeInfo(ref, "enum", ctypes.c_int, name=ref, values=values)
        if kind == "array":
            elem = self.resolve(decl["elem"])
            dims = [(int(lo), int(hi)) for lo, hi in decl["dims"]]
            if not dims or any(hi < lo for lo, hi in dims):
                raise LayoutError(f"array type {ref} has bad bounds {decl['dims']}")
            table = elem.ctype
            for lo, hi in reversed(dims):
                table = table * (hi - lo + 1)
            ct = type(_ident(ref), (ctypes.Structure,), {"_fields_": [("table", table)]})
            return TypeInfo(ref, "array", ct, name=ref, inner=elem, dims=dims)
        if kind in ("struct", "fb", "program"):
            members = [(str(f["name"]).upper(), self.resolve(f["type"])) for f in decl.get("fields", [])]
            ct = type(_ident(ref), (ctypes.Structure,),
                      {"_fields_": [(f"f{i}_{n}", t.ctype) for i, (n, t) in enumerate(members)]})
            info = TypeInfo(ref, kind, ct, name=ref)
            for i, (n, t) in enumerate(members):
                info.fields[n] = (getattr(ct, f"f{i}_{n}").offset, t)
                info.field_order.append(n)
            return info
        raise LayoutError(f"type {ref} has unknown kind {kind!r}")


def _ident(ref: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in ref)
