"""Typing core: inferring an expression's type, coercing it to the type its context wants, settling literals."""

from __future__ import annotations

from .. import ast as A
from .. import stdfuncs as SF
from .. import types as T
from ..symbols import Var
from .base import _Abort


def _hint(found: T.Type, want: T.Type) -> str:
    fb, wb = found.base(), want.base()
    if isinstance(fb, T.Elem) and isinstance(wb, T.Elem):
        return f"; convert explicitly, e.g. {fb.name}_TO_{wb.name}(...)"
    return ""


class Coercion:
    def lookup_var(self, key: str) -> Var | None:
        if self.cur is None:
            return None
        v = self.cur.vars.get(key)
        if v is None and self.cur.result is not None and key == self.cur.key:
            return self.cur.result
        return v

    def lvalue(self, e: A.Node, what: str, in_out: bool = False) -> T.Type:
        """Type of an assignable expression; rejects constants, inputs of FUNCTIONs read-only..."""
        if not isinstance(e, (A.Name, A.Member, A.Index)):
            if isinstance(e, (A.BitAccess, A.Deref, A.DirectVar)):
                self.infer(e)
            self.error(e.pos, f"{what}: a variable is required here")
        ty = self.infer(e)
        root = e
        while isinstance(root, (A.Member, A.Index)):
            root = root.base
        if not isinstance(root, A.Name) or not isinstance(root.sym, Var):
            self.error(e.pos, f"{what}: not a variable")
        v = root.sym
        if v.constant:
            self.error(e.pos, f"{what}: '{v.name}' is CONSTANT")
        if v in self.for_vars:
            self.error(e.pos, f"{what}: '{v.name}' is the control variable of an enclosing FOR loop, which its "
                              "body may not change (MatIEC: \"Assignment to FOR control variable is not allowed\")")
        node = e
        while isinstance(node, (A.Member, A.Index)):
            if isinstance(node, A.Member) and isinstance(node.base.ty, T.PouType) and node.sym.kind == "VAR_OUTPUT" \
                    and not in_out and what == "assignment":
                self.error(node.pos, f"assignment to the output '{node.name}' of a function block instance "
                                     "(MatIEC rejects it)")
            node = node.base
        if isinstance(e, A.Name) and v.is_fb_instance and not in_out:
            if what == "assignment":
                self.error(e.pos, "assigning a whole function block instance is outside the supported subset")
        return ty

    def concrete(self, e: A.Node) -> T.Type:
        """Type the expression; an untyped literal gets its default type."""
        ty = self.infer(e)
        if isinstance(ty, T.Pseudo):
            self.settle(e, ty.default)
            return ty.default
        return ty

    def coerce(self, e: A.Node, want: T.Type, what: str) -> None:
        if want is T.ERROR:
            raise _Abort     # the target's declaration was rejected, and reported
        ty = self.infer(e)
        if isinstance(ty, T.Pseudo):
            if want.base() not in ty.accepts:
                self.error(e.pos, f"{what}: type mismatch, expected {T.describe(want)}, found {ty.name}")
            self.settle(e, want)
            return
        if isinstance(want, T.PouType) or isinstance(ty, T.PouType):
            if ty is not want:
                self.error(e.pos, f"{what}: type mismatch, expected {T.describe(want)}, found {T.describe(ty)}")
            return
        if not T.same(ty, want):
            self.error(e.pos, f"{what}: type mismatch, expected {T.describe(want)}, found {T.describe(ty)}"
                              + _hint(ty, want))

    def settle(self, e: A.Node, t: T.Type) -> None:
        """Give a pseudo-typed expression (untyped literals, result-overloaded calls) the type t."""
        rights: list[tuple[A.Node, T.Type]] = []
        chain: list[A.BinOp] = []
        # down a left-associative operator chain iteratively; the right operands are settled after the
        # innermost left one, the order of a recursive walk
        while isinstance(e, A.BinOp) and isinstance(e.ty, T.Pseudo):
            tb = t.base()
            if tb not in e.ty.accepts:
                self.error(e.pos, f"type mismatch: {e.ty.name} used as {T.describe(t)}")
            op = e.op
            if op in ("+", "-", "*", "/") and not T.is_num(tb):
                self.error(e.pos, f"'{op}' needs numbers, not {T.describe(t)}")
            if op == "MOD" and not T.is_int(tb):
                self.error(e.pos, f"MOD needs integers, not {T.describe(t)}")
            if op in ("AND", "OR", "XOR") and not T.is_bit(tb):
                self.error(e.pos, f"{op} needs bit strings (BOOL, BYTE, WORD...), not {T.describe(t)}")
            e.ty = tb
            chain.append(e)
            if op != "**":
                rights.append((e.right, tb))
            e, t = e.left, tb
        self.settle_one(e, t)
        for right, tb in reversed(rights):
            self.settle(right, tb)
        for b in reversed(chain):
            self.check_constant(b, b.ty)

    def settle_one(self, e: A.Node, t: T.Type) -> None:
        p = e.ty
        if not isinstance(p, T.Pseudo):
            return
        tb = t.base()
        if tb not in p.accepts:
            self.error(e.pos, f"type mismatch: {p.name} used as {T.describe(t)}")
        e.ty = t
        if isinstance(e, A.Literal):
            v = e.value
            if e.kind == "int":
                lo, hi = (t.lo, t.hi) if isinstance(t, T.Subrange) else (tb.lo, tb.hi)
                if not lo <= v <= hi:
                    self.error(e.pos, f"the value {e.text} does not fit {T.describe(t)} ({lo}..{hi})")
            elif e.kind == "real" and tb is T.REAL and abs(v) > 3.4028235e38:
                self.error(e.pos, f"the value {e.text} does not fit REAL")
            e.ty = tb
        elif isinstance(e, A.UnOp):
            if e.op == "NEG" and not (T.is_num(tb) and T.is_signed(tb)):
                self.error(e.pos, f"negation needs a signed number, not {T.describe(t)}")
            if e.op == "NOT" and not T.is_bit(tb):
                self.error(e.pos, f"NOT needs a bit string (BOOL, BYTE, WORD...), not {T.describe(t)}")
            e.ty = tb
            self.settle(e.operand, tb)
        elif isinstance(e, A.Call) and isinstance(e.target, SF.StdCall):
            sc = e.target
            e.ty = tb
            self.std_settle(e, sc, tb)

    def infer(self, e: A.Node) -> T.Type:
        method = getattr(self, "infer_" + type(e).__name__)
        ty = method(e)
        if ty is T.ERROR:
            raise _Abort     # a name whose declaration was rejected (and reported): nothing more to say
        e.ty = ty
        return ty
