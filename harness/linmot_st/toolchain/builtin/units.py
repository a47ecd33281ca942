"""The generated C cut into translation units of about equal gcc cost, so that the build's parallel gcc
(toolchain/cc.py compile_shared) keeps every core busy (docs/builtin-compiler.md, "Generated C").

codegen.py hands over chunks in the order of the one-unit C (a callee before its callers): each POU's
init, body and body parts, each long constant initialiser, the names and globals, the configuration and
tables. `split` deals them out to units: the heaviest first, each to the unit it leaves the lightest
(longest processing time first). A small FUNCTION (a "copy" chunk) is not dealt out: each unit gets its
own `static` copy of the ones it calls, so gcc inlines them as it did in one unit. A symbol used in a unit
other than its own loses `static` for hidden visibility (the library exports nothing new) and is declared
in the shared header; the others stay `static`, so gcc still drops what no program reaches. FB bodies and
initialisers were `noinline` already: a call from another unit costs what it did.

Everything follows from the text of the chunks, so the same program gives the same C (cache keys).
"""

from __future__ import annotations

import math
import re
import struct
from dataclasses import dataclass, field

from . import types as T

HIDDEN = '__attribute__((visibility("hidden")))'
HEADER_NAME = "plc_builtin.h"

# gcc's cost per character: a constant initialiser (the PVL dataset) is only parsed, about 1/12 of the
# cost of a character of function code at -O1 (plc_project: 630 KB of code 1.8 s, a 1.8 MB dataset 0.45 s)
DATA_DIVISOR = {"data": 12, "string": 150}     # a string literal: about 0.07 s for a 3 MB dataset
# ... and a long function costs more per character: plc_project's two longest (114 KB and 77 KB) about a
# third more than its short ones; a chunk (one function, mostly) of n characters weighs n + n^2/this
LONG_FUNCTION_CHARS = 150_000
# Below SPLIT_WEIGHT (about 0.3 s of gcc) the C stays one unit: cutting it would save little wall time,
# and each unit costs a parse of the header; tests build hundreds of small programs on busy cores.
SPLIT_WEIGHT = 100_000
UNIT_WEIGHT = 150_000
# Fixed, not the machine's core count: the generated C must not depend on the machine (cache keys).
# Two units use the 2 cores of the reference machine; more would add header parses and calls between
# units for little gain there.
MAX_UNITS = 2
# A FUNCTION up to this many characters is copied into each unit that calls it; a longer one is dealt out
# like a body (compiled once, called across units)
COPY_MAX_CHARS = 8_000

_IDENT = re.compile(r"[A-Za-z_]\w*")
# A constant array of 32-bit words of at least this many words is written as a string (dword_bytes)
DWORD_STRING_MIN = 4096
# C string escapes of each byte: three octal digits always (a digit after it cannot join it), '?' escaped
# (no trigraph)
_ESCAPES = [chr(b) if 32 <= b < 127 and chr(b) not in '"\\?' else f"\\{b:03o}" for b in range(256)]
_BYTES_PER_LINE = 65_536


@dataclass
class Chunk:
    lines: list[str] = field(default_factory=list)
    kind: str = "code"          # "code", "copy" (a small FUNCTION), "data" (a constant initialiser) or
                                # "string" (one written as a string literal)
    defs: dict[str, tuple[int, str]] = field(default_factory=dict)    # symbol -> (its line, header declaration)

    def define(self, symbol: str, line: str, decl: str | None = None) -> None:
        """Append the line defining `symbol` (it starts with, or has an attribute before, `static `).
        `decl`: its declaration in the header when another unit uses it (default: the line as shared + ';')."""
        self.defs[symbol] = (len(self.lines), decl if decl is not None else shared(line) + ";")
        self.lines.append(line)

    @property
    def weight(self) -> int:
        """Its estimated gcc cost, in characters of function code (an int: sums in any order are equal)."""
        size = sum(len(line) + 1 for line in self.lines)
        if self.kind in DATA_DIVISOR:
            return size // DATA_DIVISOR[self.kind]
        return size + size * size // LONG_FUNCTION_CHARS


def shared(line: str) -> str:
    """A `static` definition made visible to the other units of the library, and only to them."""
    return line.replace("static ", HIDDEN + " ", 1)


def unit_count(total_weight: int, max_units: int | None = None) -> int:
    limit = MAX_UNITS if max_units is None else max_units
    if total_weight < SPLIT_WEIGHT:
        return 1
    return max(1, min(limit, math.ceil(total_weight / UNIT_WEIGHT)))


def split(head: list[str], chunks: list[Chunk], max_units: int | None = None) -> tuple[str, list[str]]:
    """(the shared header, the text of each unit). Unit 0 holds what no unit calls (gcc drops it)."""
    weights = [c.weight for c in chunks]
    n = unit_count(sum(weights), max_units)
    if n == 1:
        return _header(head, []), [_unit(chunks, range(len(chunks)), set())]
    owner = {sym: i for i, c in enumerate(chunks) for sym in c.defs}
    uses = [set() if c.kind in DATA_DIVISOR else {s for s in set(_IDENT.findall("\n".join(c.lines))) if s in owner}
            for c in chunks]
    copies = [i for i, c in enumerate(chunks) if c.kind == "copy"]
    closure: dict[int, set[int]] = {}

    def copies_of(i: int) -> set[int]:
        """The copy chunks chunk i needs in its unit: the FUNCTIONs it calls, theirs, and so on."""
        if i not in closure:
            closure[i] = set()
            todo = [owner[s] for s in uses[i]]
            while todo:
                k = todo.pop()
                if chunks[k].kind == "copy" and k not in closure[i] and k != i:
                    closure[i].add(k)
                    todo += [owner[s] for s in uses[k]]
        return closure[i]

    load = [0] * n
    have: list[set[int]] = [set() for _ in range(n)]
    placed: list[set[int]] = [set() for _ in range(n)]
    for i in sorted((i for i, c in enumerate(chunks) if c.kind != "copy"), key=lambda i: (-weights[i], i)):
        need = copies_of(i)
        cost = [load[u] + weights[i] + sum(weights[k] for k in need - have[u]) for u in range(n)]
        u = cost.index(min(cost))
        load[u] = cost[u]
        have[u] |= need
        placed[u].add(i)
    used = set().union(*have)
    have[0] |= {k for k in copies if k not in used}
    unit_of = {i: u for u in range(n) for i in placed[u]}
    members = [sorted(placed[u] | have[u]) for u in range(n)]
    # symbols of a dealt-out chunk used in another unit: shared (copies are defined in every unit using them)
    out: set[str] = set()
    for u in range(n):
        for i in members[u]:
            out |= {s for s in uses[i] if chunks[owner[s]].kind != "copy" and unit_of[owner[s]] != u}
    decls = [chunks[i].defs[s][1] for i in range(len(chunks)) for s in chunks[i].defs if s in out]
    return _header(head, decls), [_unit(chunks, m, out) for m in members]


def _header(head: list[str], decls: list[str]) -> str:
    lines = list(head)
    if decls:
        lines += ["/* ---- defined in one unit, used in another (hidden: the library does not export them) */",
                  *decls, ""]
    return "\n".join(lines) + "\n"


def _unit(chunks: list[Chunk], members, out: set[str]) -> str:
    lines = [f'#include "{HEADER_NAME}"', ""]
    for i in members:
        c = chunks[i]
        rewrite = {at: shared(c.lines[at]) for s, (at, _) in c.defs.items() if s in out}
        if rewrite:
            lines += [rewrite.get(k, line) for k, line in enumerate(c.lines)]
        else:
            lines += c.lines
    return "\n".join(lines) + "\n"


def dword_bytes(t: T.Type, value) -> bytes | None:
    """The little-endian bytes of a long constant array of 32-bit unsigned words (a PVL dataset); None for
    any other type or a shorter array."""
    if not isinstance(t, T.Array) or not isinstance(value, list) or len(value) < DWORD_STRING_MIN:
        return None
    elem = t.elem.base()
    if not (isinstance(elem, T.Elem) and elem.kind in ("uint", "bit") and elem.bits == 32):
        return None
    return struct.pack(f"<{len(value)}I", *value)


def c_bytes(data: bytes) -> str:
    """A C string literal of exactly these bytes (adjacent literals, one per line of _BYTES_PER_LINE)."""
    text = data.decode("latin-1")
    return "\n  ".join('"' + text[k:k + _BYTES_PER_LINE].translate(_ESCAPES) + '"'
                       for k in range(0, len(text), _BYTES_PER_LINE))
