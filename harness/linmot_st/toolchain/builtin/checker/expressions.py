"""Expressions: variables, fields, array elements, operators and their operand types."""

from __future__ import annotations

from .. import ast as A
from .. import stdfb
from .. import stdfuncs as SF
from .. import types as T


class Expressions:
    def infer_Name(self, e: A.Name) -> T.Type:
        k = e.name.upper()
        v = self.lookup_var(k)
        if v is not None:
            e.sym = v
            return v.ty
        if k == "__CURRENT_TIME" and self._std_mode:
            e.sym = "__CURRENT_TIME"
            return T.TIME
        enums = self.enum_index.get(k)
        if enums:
            if len(enums) > 1:
                self.error(e.pos, f"'{e.name}' is a value of several enumerated types "
                                  f"({', '.join(x.name for x in enums)}): write {enums[0].name}#{e.name}")
            e.sym = ("enum", enums[0])
            return enums[0]
        if self.cur is None:
            self.error(e.pos, f"'{e.name}' is not a constant")
        if k in self.pous or k in stdfb.names():
            self.error(e.pos, f"'{e.name}' is a POU, not a variable")
        if SF.is_std_function(k):
            self.error(e.pos, f"'{e.name}' is a function: call it with ( )")
        self.error(e.pos, f"'{e.name}' is not declared in {self.cur.name}")

    def infer_Member(self, e: A.Member) -> T.Type:
        bt = self.infer(e.base)
        k = e.name.upper()
        b = bt.base() if not isinstance(bt, T.PouType) else bt
        if isinstance(b, T.Struct):
            f = b.field(k)
            if f is None:
                self.error(e.name_pos or e.pos, f"{T.describe(bt)} has no field '{e.name}'")
            e.sym = f
            return f.ty
        if isinstance(b, T.PouType):
            v = b.pou.vars.get(k)
            if v is None:
                self.error(e.name_pos or e.pos, f"{b.name} has no variable '{e.name}'")
            if v.kind in ("VAR_EXTERNAL",):
                self.error(e.name_pos or e.pos, f"'{e.name}' is a VAR_EXTERNAL of {b.name}")
            e.sym = v
            return v.ty
        self.error(e.pos, f"'.{e.name}': {T.describe(bt)} is not a structure or function block")

    def infer_Index(self, e: A.Index) -> T.Type:
        bt = self.infer(e.base)
        arr = bt.base() if not isinstance(bt, T.PouType) else bt
        if not isinstance(arr, T.Array):
            self.error(e.pos, f"indexing a value of type {T.describe(bt)}, which is not an array")
        if len(e.indices) != len(arr.dims):
            self.error(e.pos, f"{T.describe(bt)} has {len(arr.dims)} dimension(s), {len(e.indices)} index(es) given")
        for idx, (lo, hi) in zip(e.indices, arr.dims):
            it = self.concrete(idx)
            if not T.is_int(it):
                self.error(idx.pos, f"an array index must be an integer, not {T.describe(it)}")
            if isinstance(idx, A.Literal) and not lo <= idx.value <= hi:
                self.error(idx.pos, f"index {idx.value} is outside {lo}..{hi}")
        return arr.elem

    def infer_BitAccess(self, e: A.BitAccess) -> T.Type:
        self.error(e.pos, "bit access (x.3) is outside the supported subset (MatIEC); use SHR and AND")

    def infer_Deref(self, e: A.Deref) -> T.Type:
        self.error(e.pos, "dereferencing (^) is outside the supported subset")

    def infer_DirectVar(self, e: A.DirectVar) -> T.Type:
        self.error(e.pos, f"{e.location}: use a located variable (name AT {e.location} : type) instead of a "
                          "direct address in an expression")

    def infer_UnOp(self, e: A.UnOp) -> T.Type:
        t = self.infer(e.operand)
        if isinstance(t, T.Pseudo):
            if e.op == "NOT" and t is not T.LIT_INT:
                self.error(e.pos, f"NOT of a {t.name}")
            return t
        tb = t.base()
        if e.op == "NEG":
            if not ((T.is_num(tb) and T.is_signed(tb)) or tb is T.TIME):
                self.error(e.pos, f"negation of {T.describe(t)} (only signed numbers and TIME; MatIEC)")
            return tb
        if not T.is_bit(tb):
            self.error(e.pos, f"NOT needs a bit string (BOOL, BYTE, WORD...), not {T.describe(t)}")
        return tb

    def infer_BinOp(self, e: A.BinOp) -> T.Type:
        # a left-associative chain (a sum of 5000 terms) is walked iteratively: its left operands
        # nest without bound, unlike anything else (checked against MatIEC's parser stack)
        spine = [e]
        while isinstance(spine[-1].left, A.BinOp):
            spine.append(spine[-1].left)
        self.infer(spine[-1].left)
        for b in reversed(spine):
            b.ty = self.binop_type(b, b.left.ty, self.infer(b.right))
        return e.ty

    def binop_type(self, e: A.BinOp, lt: T.Type, rt: T.Type) -> T.Type:
        """The type of `e`, its operands being typed (lt, rt)."""
        op = e.op
        if op == "**":
            if isinstance(lt, T.Pseudo):
                if lt is not T.LIT_REAL:
                    self.error(e.pos, "'**' needs a REAL or LREAL base (EXPT)")
            elif not T.is_real(lt):
                self.error(e.pos, f"'**' needs a REAL or LREAL base, not {T.describe(lt)}")
            if isinstance(rt, T.Pseudo):
                self.settle(e.right, rt.default)
            elif not T.is_num(rt):
                self.error(e.right.pos, f"'**' needs a numeric exponent, not {T.describe(rt)}")
            return lt if isinstance(lt, T.Pseudo) else lt.base()
        if op in ("+", "-", "*", "/"):
            tt = self.time_arith(e, op, e.left, e.right, lt, rt)
            if tt is not None:
                return tt
        t = self.unify(e.left, e.right, op, e.pos)
        if op in ("=", "<>", "<", ">", "<=", ">="):
            if isinstance(t, T.Pseudo):
                t = self.comparison_type(t, e.left, e.right)
                self.settle(e.left, t)
                self.settle(e.right, t)
            tb = t.base()
            if isinstance(tb, T.Enum):
                if op not in ("=", "<>"):
                    self.error(e.pos, f"'{op}' on enumerated values (only = and <>)")
            elif not (isinstance(tb, T.Elem)):
                self.error(e.pos, f"'{op}' cannot compare values of type {T.describe(t)}")
            return T.BOOL
        if isinstance(t, T.Pseudo):
            if op in ("AND", "OR", "XOR", "MOD") and t is T.LIT_REAL:
                self.error(e.pos, f"{op} of real literals")
            if op == "/" and self._is_zero(e.right):
                self.error(e.right.pos, "division by zero")
            return t
        tb = t.base()
        if op in ("+", "-", "*", "/"):
            if not T.is_num(tb):
                self.error(e.pos, f"'{op}' needs numbers, not {T.describe(t)}" + (
                    " (BYTE, WORD, DWORD, LWORD are bit strings: convert them first)" if T.is_bit(tb) else ""))
            if op == "/" and T.is_int(tb) and self._is_zero(e.right):
                self.error(e.right.pos, "division by zero")
        elif op == "MOD":
            if not T.is_int(tb):
                self.error(e.pos, f"MOD needs integers, not {T.describe(t)}")
        elif op in ("AND", "OR", "XOR"):
            if not T.is_bit(tb):
                self.error(e.pos, f"{op} needs bit strings (BOOL, BYTE, WORD, DWORD, LWORD), not {T.describe(t)}")
        self.check_constant(e, tb)
        return tb

    def check_constant(self, e: A.BinOp, tb: T.Type) -> None:
        """Refuse a constant operation whose value does not fit its type, as MatIEC's constant folding does
        (constfold.py), intermediate results included."""
        v = self.folder.overflow(e, tb)
        if v is not None:
            shown = f"{v:g}" if isinstance(v, float) else str(v)
            held = f"{tb.lo}..{tb.hi}" if T.is_int(tb) else "finite values" if tb is T.LREAL else \
                "-3.4028235E38..3.4028235E38"
            self.error(e.pos, f"constant expression overflows {T.describe(tb)}: '{e.op}' gives {shown} ({held}); "
                              "MatIEC's constant folding refuses it, also when a later operation brings it back")

    def comparison_type(self, t: T.Pseudo, *sides: A.Node) -> T.Type:
        """The type of untyped constants compared with each other. iec2c accepts them when some type holds
        every value they fold to, and its C writes them as C literals: `3000000000 > 0` is compared as a
        C long long (so here as LINT or ULINT when DINT is too small), but `2147483647 + 1` is a C int
        addition that overflows (gcc wraps it: MatIEC's `2147483647 + 1 > 2147483647` is FALSE)."""
        if t is not T.LIT_INT:
            return t.default
        for side in sides:
            bad = self.folder.c_literal_overflow(side)
            if bad is not None:
                node, v = bad
                self.error(node.pos, f"constant expression overflows C's int: '{node.op}' gives {v}; MatIEC builds "
                                     "it but its C computes these untyped constants as C int literals, where "
                                     "this overflows (undefined behaviour, in practice a wrapped value): write a "
                                     "typed literal such as LINT#...")
        found = [v for side in sides for _, v in self.folder.values(side)]
        for cand in (t.default, T.LINT, T.ULINT):
            if all(cand.lo <= v <= cand.hi for v in found):
                return cand
        return t.default

    @staticmethod
    def _is_zero(e: A.Node) -> bool:
        return isinstance(e, A.Literal) and e.kind in ("int", "real") and e.value == 0

    def time_arith(self, e, op, left, right, lt, rt) -> T.Type | None:
        lb = lt.base() if not isinstance(lt, T.Pseudo) else None
        rb = rt.base() if not isinstance(rt, T.Pseudo) else None
        if not ((lb is not None and T.is_time_like(lb)) or (rb is not None and T.is_time_like(rb))):
            return None
        if op in ("*", "/"):
            if lb is not T.TIME:
                self.error(e.pos, f"'{op}' with a duration: write TIME {op} number")
            if isinstance(rt, T.Pseudo):
                self.settle(right, rt.default)
            elif not T.is_num(rb):
                self.error(e.pos, f"TIME {op} {T.describe(rt)}: the second operand must be a number")
            if op == "/" and self._is_zero(right):
                self.error(right.pos, "division by zero")
            e.time = True
            return T.TIME
        table = {
            "+": {(T.TIME, T.TIME): T.TIME, (T.TOD, T.TIME): T.TOD, (T.DT, T.TIME): T.DT},
            "-": {(T.TIME, T.TIME): T.TIME, (T.DATE, T.DATE): T.TIME, (T.TOD, T.TIME): T.TOD,
                  (T.TOD, T.TOD): T.TIME, (T.DT, T.TIME): T.DT, (T.DT, T.DT): T.TIME},
        }[op]
        res = table.get((lb, rb))
        if res is None:
            self.error(e.pos, f"{T.describe(lt)} {op} {T.describe(rt)} is not defined")
        e.time = True
        return res

    def unify(self, left, right, op, pos) -> T.Type:
        lt, rt = left.ty, right.ty
        lp, rp = isinstance(lt, T.Pseudo), isinstance(rt, T.Pseudo)
        if not lp and not rp:
            if isinstance(lt, T.PouType) or isinstance(rt, T.PouType) or not T.same(lt, rt):
                self.error(pos, f"type mismatch: {T.describe(lt)} {op} {T.describe(rt)} (no implicit conversion)")
            return lt.base()
        if lp and not rp:
            self.settle_operand(left, rt, op, pos)
            return rt.base()
        if rp and not lp:
            self.settle_operand(right, lt, op, pos)
            return lt.base()
        if lt.literal and rt.literal and lt is not rt:
            self.error(pos, f"type mismatch: {lt.name} {op} {rt.name}")
        return rt if lt.literal else lt

    def settle_operand(self, e, t: T.Type, op, pos) -> None:
        p = e.ty
        if t.base() not in p.accepts:
            self.error(pos, f"type mismatch: {T.describe(t)} {op} {p.name}")
        self.settle(e, t.base())
