"""Long array initialisers of plain integer literals, read without the grammar.

A PVL dataset is one `ARRAY[1..n] OF DWORD := [16#..., ...]` of up to hundreds of thousands of words
(docs/commissioning.md); through the LALR parser and the checker each word costs tens of microseconds.
Before parsing, `extract` finds every initialiser `:= [ ... ]` of at least MIN_ITEMS unsigned integer
literals (decimal or 2#/8#/16#, comments between them allowed), reads its values with one regular
expression, and leaves a one-element initialiser `[0]` in its place, padded so that every later line
and column stays where it was. The parser's array_init callback swaps the values back in by the
placeholder's position (A.ArrayInit.ints); anything the fast path does not vouch for (a value that does
not fit, an element type other than an integer or bit string) goes the ordinary way, item by item, with
the ordinary diagnostics (`BulkInts.items`).
"""

from __future__ import annotations

import re
from bisect import bisect_right

from . import ast as A

MIN_ITEMS = 32
_GAP = r"(?>(?:\s+|\(\*[\s\S]*?\*\))*)"          # white space and comments, as the lexer ignores them
_LIT = r"(?:(?:2|8|16)#[0-9A-Fa-f_]+|[0-9](?:_?[0-9])*)"
_ITEM = re.compile(_GAP + "(" + _LIT + ")" + _GAP + r"([,\]])")
_OPEN = re.compile(r":=" + _GAP + r"\[")
_COMMENT = re.compile(r"\(\*[\s\S]*?\*\)")


class BulkInts:
    """The values of one initialiser read by `extract`; `start` is where its first literal may begin.
    Equal to another when the values are (the source text and positions are not part of the value)."""

    __slots__ = ("values", "start", "text", "lines")

    def __init__(self, values: list[int], start: int, text: str, lines: _Lines) -> None:
        self.values, self.start, self.text, self.lines = values, start, text, lines

    def __eq__(self, other: object) -> bool:
        return isinstance(other, BulkInts) and other.values == self.values

    __hash__ = None

    def __repr__(self) -> str:
        return f"BulkInts({len(self.values)} values)"

    def items(self, file: str) -> list[tuple[int, A.Node]]:
        """The initialiser as the grammar would have built it: (1, Literal) per value, each at its place."""
        out, pos = [], self.start
        for v in self.values:
            m = _ITEM.match(self.text, pos)
            line, col = self.lines.at(m.start(1))
            out.append((1, A.Literal(A.Pos(file, line, col), "int", v, None, m.group(1))))
            pos = m.end()
        return out

    def first_pos(self) -> tuple[int, int]:
        return self.lines.at(_ITEM.match(self.text, self.start).start(1))


class _Lines:
    """Offset -> (line, column), both 1-based as lark counts them."""

    def __init__(self, text: str) -> None:
        self.starts = [0] + [m.end() for m in re.finditer("\n", text)]

    def at(self, offset: int) -> tuple[int, int]:
        i = bisect_right(self.starts, offset) - 1
        return i + 1, offset - self.starts[i] + 1


_ALLOWED = str.maketrans("", "", "0123456789ABCDEFabcdef#_, \t\r\n\f\v")


def _value(word: str) -> int:
    """An ST integer literal's value; ValueError where Python's int() and the ST grammar might differ."""
    if "#" in word:
        base, digits = word.split("#", 1)
        if base not in ("2", "8", "16") or not digits or digits[0] == "_":
            raise ValueError(word)
        return int(digits, int(base))
    return int(word)


def _list_end(text: str, pos: int) -> int:
    """The offset just after the first ']' at or after pos outside comments, -1 if there is none."""
    while True:
        close, comment = text.find("]", pos), text.find("(*", pos)
        if close < 0:
            return -1
        if comment < 0 or close < comment:
            return close + 1
        pos = text.find("*)", comment + 2)
        if pos < 0:
            return -1
        pos += 2


def extract(text: str) -> tuple[str, dict[tuple[int, int], BulkInts]]:
    """(text with each long literal initialiser replaced by a placeholder, {placeholder (line, col): values})."""
    if text.count(",") < MIN_ITEMS:
        return text, {}
    lines = None
    found: dict[tuple[int, int], BulkInts] = {}
    parts, last = [], 0
    for m in _OPEN.finditer(text):
        start = m.end() - 1                                   # the '['
        if start < last:
            continue
        end = _list_end(text, m.end())
        if end < 0:
            continue
        span = text[start:end]
        if span.count(",") + 1 < MIN_ITEMS:
            continue
        body = _COMMENT.sub(" ", span[1:-1])
        if body.translate(_ALLOWED):                          # anything but literals, commas and white space
            continue
        words = [w.strip() for w in body.split(",")]
        try:   # each word a literal: int() rejects what the grammar rejects (the slow path then reports it)
            values = [int(w[3:], 16) if w[:3] == "16#" and w[3:4] != "_" else _value(w) for w in words]
        except ValueError:
            continue
        lines = lines or _Lines(text)
        newlines = span.count("\n")
        if newlines:   # the same line breaks, and the last line as long as before
            placeholder = "[0" + "\n" * newlines + " " * (len(span) - span.rfind("\n") - 2) + "]"
        else:
            placeholder = "[0" + " " * (len(span) - 3) + "]"
        found[lines.at(start + 1)] = BulkInts(values, m.end(), text, lines)
        parts.append(text[last:start])
        parts.append(placeholder)
        last = end
    if not found:
        return text, {}
    parts.append(text[last:])
    return "".join(parts), found
