"""Variables of a loaded PLC by IEC path: resolution (once) into bound accessors, and value conversion.

Paths are case-insensitive, `.` separates members, `[i]` / `[i, j]` / `[i][j]` index arrays with their
declared bounds. A path may start with any unique suffix of a root path (`INST0.X` for
`CONFIG0.RES0.INST0.X`); a located root such as `%IX0.0` is named in full. `var:`/`ptr:`/`ref:` wrappers are
transparent. Values: BOOL -> bool, integers -> int, REAL/LREAL -> float, TIME/DATE/TOD/DT -> int ns,
STRING -> str (latin-1), enums -> str, arrays -> lists (nested per dimension), structs/FBs -> dicts.
"""

from __future__ import annotations

import ctypes
import re
from dataclasses import dataclass
from typing import Any

from .layout import INTEGER_RANGES, STRING_CAPACITY, TIME_TYPES, IecString, IecTime, Layout, TypeInfo

FORCE_FLAG = 0x02   # MatIEC's __IEC_FORCE_FLAG: every __SET_VAR skips a forced variable


class PathError(KeyError):
    """A path that names no variable, or names one ambiguously."""

    def __str__(self) -> str:
        return str(self.args[0]) if self.args else ""


@dataclass
class Target:
    """A resolved path: the address of its value, its type, and the wrapper that carries its flags."""

    path: str
    addr: int
    info: TypeInfo
    wrapper_addr: int | None = None       # the var:/ptr: wrapper holding the force flag, if the path ends at one
    wrapper_info: TypeInfo | None = None


_TOKEN = re.compile(r"\s*(?:(?P<name>[A-Za-z_][A-Za-z0-9_]*)|(?P<dot>\.)|\[(?P<idx>[^\]]*)\])")


def parse_components(path: str) -> list[tuple[str, list[int]]]:
    """`A.B[1,2][3].C` -> [("A", []), ("B", [1, 2, 3]), ("C", [])]."""
    comps: list[tuple[str, list[int]]] = []
    pos, expect_name = 0, True
    text = path.strip()
    while pos < len(text):
        m = _TOKEN.match(text, pos)
        if not m or m.end() == pos:
            raise PathError(f"bad path {path!r} at column {pos + 1}")
        pos = m.end()
        if m.group("name"):
            if not expect_name:
                raise PathError(f"bad path {path!r}: missing '.' before {m.group('name')}")
            comps.append((m.group("name").upper(), []))
            expect_name = False
        elif m.group("dot"):
            if expect_name:
                raise PathError(f"bad path {path!r}: empty member name")
            expect_name = True
        else:
            if expect_name or not comps:
                raise PathError(f"bad path {path!r}: index without a variable")
            try:
                comps[-1][1].extend(int(i, 0) for i in m.group("idx").split(","))
            except ValueError:
                raise PathError(f"bad path {path!r}: index [{m.group('idx')}] is not a list of integers") from None
    if expect_name:
        raise PathError(f"bad path {path!r}")
    return comps


class Resolver:
    """Resolves paths against a manifest's roots, given their addresses."""

    def __init__(self, layout: Layout, roots: list[tuple[str, str, int]]):
        self.layout = layout
        # (path as written, components, type, address)
        self.roots = [(p, p.upper().split(".") if not p.startswith("%") else [p.upper()], layout.resolve(t), a)
                      for p, t, a in roots]

    def resolve(self, path: str) -> Target:
        text = path.strip()
        if text.startswith("%"):
            return self._resolve_located(text)
        comps = parse_components(text)
        found: list[Target] = []
        errors: list[str] = []
        for root_path, rcomps, info, addr in self.roots:
            if rcomps[0].startswith("%"):
                continue
            for k in range(min(len(rcomps), len(comps)), 0, -1):
                head = comps[:k]
                if [n for n, _ in head] != rcomps[-k:] or any(idx for _, idx in head[:-1]):
                    continue
                rest = ([(None, head[-1][1])] if head[-1][1] else []) + comps[k:]
                try:
                    found.append(self._walk(text, root_path, addr, info, rest))
                except PathError as exc:
                    errors.append(str(exc))
                break
        if len(found) == 1:
            return found[0]
        if len(found) > 1:
            raise PathError(f"path {path!r} is ambiguous: it matches "
                            + ", ".join(sorted(t.path for t in found)) + "; give more of the path")
        if errors:
            raise PathError(errors[0])
        raise PathError(f"no variable {path!r}: no root path ends with {comps[0][0]!r} "
                        f"(roots: {', '.join(r[0] for r in self.roots)})")

    def _resolve_located(self, text: str) -> Target:
        up = text.upper()
        located = sorted((r for r in self.roots if r[1][0].startswith("%")), key=lambda r: -len(r[1][0]))
        for root_path, rcomps, info, addr in located:
            r = rcomps[0]
            if up == r or (up.startswith(r) and up[len(r)] in ".["):
                rest: list = []
                if len(up) > len(r):
                    (_, idx), *more = parse_components("X" + text[len(r):])
                    rest = ([(None, idx)] if idx else []) + more
                return self._walk(text, root_path, addr, info, rest)
        raise PathError(f"no located variable {text!r}")

    def _walk(self, path: str, root: str, addr: int, info: TypeInfo, rest: list) -> Target:
        where = root
        wrapper = (None, None)
        for name, indices in rest:
            addr, info = _unwrap(addr, info, where)
            if name is not None:
                if info.kind not in ("struct", "fb", "program"):
                    raise PathError(f"{where} is a {_describe(info)}: it has no member {name}")
                member = info.fields.get(name)
                if member is None:
                    raise PathError(f"{where} ({info.name}) has no member {name}; members: "
                                    + ", ".join(info.field_order))
                offset, info = member
                addr += offset
                where = f"{where}.{name}"
            if indices:
                addr, info = _unwrap(addr, info, where)
                if info.kind != "array":
                    raise PathError(f"{where} is a {_describe(info)}, not an array")
                if len(indices) != len(info.dims):
                    raise PathError(f"{where} has {len(info.dims)} dimension(s), got {len(indices)} index(es)")
                flat = 0
                for i, (lo, hi) in zip(indices, info.dims):
                    if not lo <= i <= hi:
                        raise PathError(f"index {i} of {where} is out of its bounds {lo}..{hi}")
                    flat = flat * (hi - lo + 1) + (i - lo)
                info = info.inner
                addr += flat * info.size
                where = f"{where}[{', '.join(map(str, indices))}]"
        if info.kind in ("var", "ptr"):
            wrapper = (addr, info)
        addr, info = _unwrap(addr, info, where)
        return Target(where, addr, info, wrapper[0], wrapper[1])


def _unwrap(addr: int, info: TypeInfo, where: str) -> tuple[int, TypeInfo]:
    while info.kind in ("var", "ptr", "ref"):
        if info.kind == "var":
            info = info.inner   # value is the first member
        else:
            target = ctypes.c_void_p.from_address(addr).value
            if not target:
                raise PathError(f"{where} points nowhere (is the PLC initialised?)")
            addr, info = target, info.inner
    return addr, info


def _describe(info: TypeInfo) -> str:
    return info.name if info.kind == "elementary" else f"{info.kind} {info.name}"


# ---- values -------------------------------------------------------------------------------------------

def enum_name(values, i: int) -> Any:
    """An enumerated value's name; the number itself when it names none."""
    return values[i] if 0 <= i < len(values) else i


def read_value(addr: int, info: TypeInfo) -> Any:
    kind = info.kind
    if kind == "elementary":
        name = info.name
        if name == "BOOL":
            return bool(ctypes.c_uint8.from_address(addr).value)
        if name in TIME_TYPES:
            t = IecTime.from_address(addr)
            return t.tv_sec * 1_000_000_000 + t.tv_nsec
        if name == "STRING":
            s = IecString.from_address(addr)
            return bytes(s.body[: min(s.len, STRING_CAPACITY)]).decode("latin-1")
        return info.ctype.from_address(addr).value
    if kind == "enum":
        return enum_name(info.values, ctypes.c_int.from_address(addr).value)
    if kind in ("var", "ptr", "ref"):
        try:
            addr, info = _unwrap(addr, info, "")
        except PathError:
            return None
        return read_value(addr, info)
    if kind == "array":
        return _read_array(addr, info, 0)
    return {name: read_value(addr + off, t) for name, (off, t) in info.fields.items()}


def _read_array(addr: int, info: TypeInfo, dim: int) -> list:
    lo, hi = info.dims[dim]
    n = hi - lo + 1
    elem = info.inner
    if dim + 1 == len(info.dims):
        if elem.kind == "elementary" and elem.name not in TIME_TYPES and elem.name != "STRING":
            values = list((elem.ctype * n).from_address(addr))
            return [bool(v) for v in values] if elem.name == "BOOL" else values
        return [read_value(addr + i * elem.size, elem) for i in range(n)]
    stride = elem.size
    for a, b in info.dims[dim + 1:]:
        stride *= b - a + 1
    return [_read_array(addr + i * stride, info, dim + 1) for i in range(n)]


def write_value(addr: int, info: TypeInfo, value: Any, where: str) -> None:
    kind = info.kind
    if kind == "elementary":
        _write_elementary(addr, info.name, info.ctype, value, where)
    elif kind == "enum":
        ctypes.c_int.from_address(addr).value = _enum_index(info, value, where)
    elif kind in ("var", "ptr", "ref"):
        a, i = _unwrap(addr, info, where)
        write_value(a, i, value, where)
    elif kind == "array":
        _write_array(addr, info, 0, value, where)
    else:
        if not isinstance(value, dict):
            raise TypeError(f"{where} is a {info.kind} {info.name}: assign a dict of members, not {value!r}")
        for name, v in value.items():
            member = info.fields.get(str(name).upper())
            if member is None:
                raise PathError(f"{where} ({info.name}) has no member {name}")
            write_value(addr + member[0], member[1], v, f"{where}.{str(name).upper()}")


def _write_array(addr: int, info: TypeInfo, dim: int, value: Any, where: str) -> None:
    lo, hi = info.dims[dim]
    n = hi - lo + 1
    if not isinstance(value, (list, tuple)) or len(value) != n:
        raise TypeError(f"{where} (dimension {dim + 1}, {lo}..{hi}) takes a list of {n} values")
    stride = info.inner.size
    for a, b in info.dims[dim + 1:]:
        stride *= b - a + 1
    for i, v in enumerate(value):
        if dim + 1 == len(info.dims):
            write_value(addr + i * stride, info.inner, v, f"{where}[{lo + i}]")
        else:
            _write_array(addr + i * stride, info, dim + 1, v, where)


def _write_elementary(addr: int, name: str, ctype: Any, value: Any, where: str) -> None:
    if name == "BOOL":
        if value not in (0, 1):   # True/False/0/1
            raise TypeError(f"{where} is BOOL: assign True or False, not {value!r}")
        ctypes.c_uint8.from_address(addr).value = 1 if value else 0
    elif name in INTEGER_RANGES:
        ctype.from_address(addr).value = check_integer(name, value, where)
    elif name in ("REAL", "LREAL"):
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            raise TypeError(f"{where} is {name}: assign a number, not {value!r}")
        ctype.from_address(addr).value = float(value)
    elif name in TIME_TYPES:
        if isinstance(value, bool) or not isinstance(value, int):
            raise TypeError(f"{where} is {name}: assign an int of nanoseconds, not {value!r}")
        t = IecTime.from_address(addr)
        t.tv_sec, t.tv_nsec = divmod(value, 1_000_000_000)
    elif name == "STRING":
        if not isinstance(value, str):
            raise TypeError(f"{where} is STRING: assign a str, not {value!r}")
        data = value.encode("latin-1")
        if len(data) > STRING_CAPACITY:
            raise ValueError(f"{where}: {len(data)} characters do not fit a STRING ({STRING_CAPACITY})")
        s = IecString.from_address(addr)
        ctypes.memmove(ctypes.addressof(s.body), data, len(data))
        s.len = len(data)
    else:
        raise TypeError(f"{where}: cannot assign type {name}")


def check_integer(name: str, value: Any, where: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        raise TypeError(f"{where} is {name}: assign an int, not {value!r}")
    lo, hi = INTEGER_RANGES[name]
    if not lo <= value <= hi:
        raise ValueError(f"{where} is {name}: {value} is out of its range {lo}..{hi}")
    return value


def _enum_index(info: TypeInfo, value: Any, where: str) -> int:
    if isinstance(value, str):
        key = value.upper().split("#")[-1]
        if key not in info.values:
            raise ValueError(f"{where} is {info.name}: {value!r} is not one of {', '.join(info.values)}")
        return info.values.index(key)
    if isinstance(value, int) and not isinstance(value, bool) and 0 <= value < len(info.values):
        return value
    raise TypeError(f"{where} is {info.name}: assign one of {', '.join(info.values)}")
