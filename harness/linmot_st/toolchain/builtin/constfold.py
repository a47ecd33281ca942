"""Constant folding as MatIEC does it, to refuse the constant expressions MatIEC refuses.

MatIEC (stage 3, constant folding) computes the value of every operator whose operands are literals,
typed (INT#200) or not (200); named constants (VAR CONSTANT) are not propagated. A `+ - * / MOD` node
keeps a type only if its value lies in that type's range, so an intermediate result that overflows
refuses the whole expression even when the end result comes back in range (`32767 + 1 - 1` into INT,
`SINT#100 + SINT#100 - SINT#100`). Negation folds without that check (`-INT#-32768` is accepted, but
`-INT#-32768 + 0` is not). Reals fold in double precision: a REAL node beyond +-3.4028235E38, or an
LREAL node that becomes infinite, is refused. Measured with iec2c (MatIEC HEAD): docs/builtin-compiler.md.
"""

from __future__ import annotations

import math

from . import ast as A
from . import types as T

FLT_MAX = 3.4028234663852886e38
CHECKED_OPS = ("+", "-", "*", "/", "MOD")
_UNKNOWN = object()


class Folder:
    """Values of constant expressions, memoised per node (a sum of thousands of terms is folded once)."""

    def __init__(self):
        self._memo: dict[int, object] = {}

    def value(self, e: A.Node) -> int | float | None:
        """The folded value of `e`, or None when it is not a constant expression MatIEC folds."""
        v = self._memo.get(id(e), _UNKNOWN)
        if v is not _UNKNOWN:
            return v
        # a left-associative chain is folded from its innermost node outwards, without recursion
        spine = [e]
        while isinstance(spine[-1], A.BinOp) and isinstance(spine[-1].left, A.BinOp) \
                and id(spine[-1].left) not in self._memo:
            spine.append(spine[-1].left)
        for node in reversed(spine):
            self._memo[id(node)] = self._fold(node)
        return self._memo[id(e)]

    def _fold(self, e: A.Node) -> int | float | None:
        if isinstance(e, A.Literal):
            return e.value if e.kind in ("int", "real") else None
        if isinstance(e, A.UnOp):
            v = self.value(e.operand)
            return -v if e.op == "NEG" and v is not None else None
        if isinstance(e, A.BinOp) and e.op in CHECKED_OPS and not getattr(e, "time", False):
            a, b = self.value(e.left), self.value(e.right)
            if a is None or b is None:
                return None
            return _apply(e.op, a, b)
        return None

    def values(self, e: A.Node):
        """(node, folded value) of the literals and checked operators in `e` (an explicit stack: chains are long)."""
        stack = [e]
        while stack:
            node = stack.pop()
            if isinstance(node, (A.Literal, A.BinOp)) and (isinstance(node, A.Literal) or node.op in CHECKED_OPS):
                v = self.value(node)
                if v is not None:
                    yield node, v
            if isinstance(node, A.BinOp):
                stack += [node.left, node.right]
            elif isinstance(node, A.UnOp):
                stack.append(node.operand)

    def c_literal_overflow(self, e: A.Node) -> tuple[A.BinOp, int] | None:
        """The first operator of `e` (untyped integer constants) whose value does not fit the C type C gives
        it when the constants are written as C literals, as MatIEC's C writes untyped constants compared with
        each other: int up to 2147483647, else long long; an operator takes the wider of its operands."""
        bits: dict[int, int] = {}
        stack = [(e, False)]
        while stack:
            node, done = stack.pop()
            if not done and isinstance(node, (A.BinOp, A.UnOp)):
                kids = [node.left, node.right] if isinstance(node, A.BinOp) else [node.operand]
                stack += [(node, True)] + [(k, False) for k in reversed(kids)]
                continue
            v = self.value(node)
            if isinstance(node, A.BinOp):
                width = max(bits[id(node.left)], bits[id(node.right)])
                if isinstance(v, int) and node.op in CHECKED_OPS and not -2 ** (width - 1) <= v < 2 ** (width - 1):
                    return node, v
            elif isinstance(node, A.UnOp):
                width = bits[id(node.operand)]
            else:
                width = 32 if isinstance(v, int) and -2 ** 31 <= v < 2 ** 31 else 64
            bits[id(node)] = width
        return None

    def overflow(self, e: A.BinOp, ty: T.Type) -> int | float | None:
        """The value of `e` when it is a constant that does not fit `ty` (its type), else None."""
        if e.op not in CHECKED_OPS:
            return None
        v = self.value(e)
        if v is None:
            return None
        tb = ty.base()
        if T.is_int(tb):
            return v if isinstance(v, int) and not tb.lo <= v <= tb.hi else None
        if T.is_real(tb) and isinstance(v, float):
            limit_exceeded = math.isinf(v) or (tb is T.REAL and abs(v) > FLT_MAX)
            return v if limit_exceeded or math.isnan(v) else None
        return None


def _apply(op: str, a, b):
    """a op b with C's integer division (truncation towards zero); None where MatIEC does not fold."""
    if op == "+":
        return a + b
    if op == "-":
        return a - b
    if op == "*":
        return a * b
    if b == 0:
        return None        # division by zero is reported by the checker (or, for MOD, defined as 0)
    if isinstance(a, float) or isinstance(b, float):
        if op == "/":
            try:
                return a / b
            except OverflowError:
                return math.inf
        return None
    q = abs(a) // abs(b) * (1 if (a < 0) == (b < 0) else -1)
    return q if op == "/" else a - b * q
