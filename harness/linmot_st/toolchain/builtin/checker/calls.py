"""Calls of function blocks and user FUNCTIONs: the callee, its arguments bound to its parameters."""

from __future__ import annotations

from .. import ast as A
from .. import stdfb
from .. import stdfuncs as SF
from .. import types as T
from ..symbols import PouSym, Var
from .base import _Abort


def _has_index(e: A.Node) -> bool:
    while isinstance(e, (A.Member, A.Index)):
        if isinstance(e, A.Index):
            return True
        e = e.base
    return False


class Calls:
    def call_statement(self, call: A.Call) -> None:
        k = call.name.upper()
        if k in self.failed_pous and self.lookup_var(k) is None:
            raise _Abort     # its declaration was rejected, and reported
        v = self.lookup_var(k)
        if v is not None:
            if v.ty is T.ERROR:
                raise _Abort     # its declaration was rejected, and reported
            if not v.is_fb_instance:
                self.error(call.pos, f"'{call.name}' is not a function block instance")
            self.fb_call(call, v)
            return
        if k in self.pous and self.pous[k].kind != "FUNCTION":
            self.error(call.pos, f"'{call.name}' is a {self.pous[k].kind}: declare an instance and call that")
        if k in stdfb.names():
            self.error(call.pos, f"'{call.name}' is a function block: declare an instance and call that")
        if not self._std_mode and ((k in self.pous and self.pous[k].kind == "FUNCTION") or SF.lookup(k) is not None):
            self.error(call.pos, f"a call of the function {call.name} used as a statement: MatIEC allows function "
                                 "calls only inside expressions (\"Function invocation in ST code is not allowed "
                                 "outside an expression\"); assign its result, e.g. x := "
                                 f"{call.name}(...)")
        self.infer(call)

    def fb_call(self, call: A.Call, inst: Var) -> None:
        pou = inst.ty.pou
        bound = self.bind_args(call, pou.params, pou, allow_en=True)
        call.target = (pou, inst, bound)
        self.note_callee(pou)

    def note_callee(self, pou: PouSym) -> None:
        if self.cur is not None:
            self.cur.callees.add(pou)

    def bind_args(self, call: A.Call, params: list[Var], pou: PouSym, allow_en: bool) -> list:
        """Bind call arguments to formal parameters; check their types. Returns [(Var, Arg)]."""
        args = call.args
        formal = [a for a in args if a.name is not None]
        if formal and len(formal) != len(args):
            self.error(call.pos, f"call of {pou.name} mixes formal (name := value) and positional arguments")
        bound: list = []
        seen: set[str] = set()
        if not formal:
            if len(args) > len(params):
                self.error(call.pos, f"{pou.name} takes {len(params)} parameters, {len(args)} given")
            for p, a in zip(params, args):
                if p.kind == "VAR_OUTPUT":
                    a = A.Arg(a.pos, p.name, a.value, output=True)
                bound.append((p, a))
        else:
            for a in args:
                k = a.name.upper()
                if k in seen:
                    self.error(a.pos, f"parameter '{a.name}' given twice")
                seen.add(k)
                if k in ("EN", "ENO"):
                    if not allow_en:
                        self.error(a.pos, f"{k} in a function call is not supported by the builtin compiler")
                    p = pou.vars[k]
                else:
                    p = next((q for q in params if q.key == k), None)
                    if p is None:
                        self.error(a.pos, f"{pou.name} has no parameter '{a.name}'")
                if a.output != (p.kind == "VAR_OUTPUT"):
                    self.error(a.pos, f"'{a.name}' is {'an output: use =>' if p.kind == 'VAR_OUTPUT' else 'an input: use :='}")
                if a.negated:
                    self.error(a.pos, "negated outputs (NOT q => x) are outside the supported subset")
                bound.append((p, a))
        for p, a in bound:
            try:
                what = f"parameter '{p.name}' of {pou.name}"
                if p.kind == "VAR_INPUT":
                    if isinstance(p.ty, T.PouType):
                        t = self.infer(a.value)
                        if t is not p.ty:
                            self.error(a.value.pos, f"{what}: expected an instance of {p.ty.name}")
                    else:
                        self.coerce(a.value, p.ty, what)
                elif p.kind == "VAR_IN_OUT":
                    if pou.kind == "FUNCTION" and _has_index(a.value):
                        self.error(a.value.pos, f"{what}: an array element as VAR_IN_OUT of a FUNCTION is outside the "
                                                "supported subset (MatIEC generates C that does not compile); copy "
                                                "it to a variable first")
                    t = self.lvalue(a.value, what, in_out=True)
                    if not T.same(t, p.ty) or (isinstance(p.ty, T.PouType) and t is not p.ty):
                        self.error(a.value.pos, f"{what}: type mismatch, expected {T.describe(p.ty)}, "
                                                f"found {T.describe(t)} (VAR_IN_OUT needs a variable of the same type)")
                else:
                    t = self.lvalue(a.value, what)
                    if not T.same(t, p.ty):
                        self.error(a.value.pos, f"{what}: type mismatch, {T.describe(t)} => receives "
                                                f"{T.describe(p.ty)}")
            except _Abort:
                pass
        return bound

    def infer_Call(self, e: A.Call) -> T.Type:
        k = e.name.upper()
        if k in self.failed_pous:
            raise _Abort     # its declaration was rejected, and reported
        if self.cur is not None and k == self.cur.key:
            self.error(e.pos, f"recursive call of {self.cur.name} (recursion is outside the supported subset)")
        v = self.lookup_var(k)
        if v is not None:
            self.error(e.pos, f"'{e.name}' is a variable: a function block instance is called as a statement")
        pou = self.pous.get(k)
        if pou is not None and pou.kind == "FUNCTION" and k in SF.USER_NAMEABLE:
            pou = None      # MatIEC calls its standard function of that name, never the user's
        if pou is not None:
            if pou.kind != "FUNCTION":
                self.error(e.pos, f"'{e.name}' is a {pou.kind}, not a FUNCTION")
            if self.cur is not None and pou is self.cur:
                self.error(e.pos, f"recursive call of {pou.name} (recursion is outside the supported subset)")
            if not e.args:
                self.error(e.pos, f"a call of FUNCTION {pou.name} needs at least one argument (MatIEC)")
            self.check_has_code(pou, e.pos)
            bound = self.bind_args(e, pou.params, pou, allow_en=True)
            if isinstance(pou.return_type.base(), T.Struct):
                outs = [p for p, _ in bound if p.kind in ("VAR_OUTPUT", "VAR_IN_OUT")]
                if outs:
                    self.error(e.pos, f"{pou.name} returns a STRUCT: a call of it cannot pass "
                                      f"{'VAR_IN_OUT' if outs[0].kind == 'VAR_IN_OUT' else 'outputs'} ('{outs[0].name}'), "
                                      "because MatIEC's C for such a call does not compile (it loses the STRUCT's "
                                      "type name); return the values through a VAR_IN_OUT of a FUNCTION that "
                                      "returns an elementary value, or use a FUNCTION_BLOCK")
            e.target = (pou, None, bound)
            self.note_callee(pou)
            return pou.return_type
        if self.cur is not None and k == self.cur.key:
            self.error(e.pos, f"recursive call of {self.cur.name} (recursion is outside the supported subset)")
        lk = SF.lookup(k)
        if lk is not None:
            return self.std_call(e, lk)
        if k in stdfb.names() or k in stdfb.NON_STANDARD:
            self.error(e.pos, f"'{e.name}' is a function block, not a function")
        if k in SF.MISSING_IN_MATIEC_C:
            self.error(e.pos, f"{e.name} is outside the supported subset (MatIEC declares it but its C library lacks "
                              f"it); call the overloaded {k.split('_')[0]}")
        if k in SF.UNSUPPORTED_FUNCTIONS:
            self.error(e.pos, f"{SF.UNSUPPORTED_FUNCTIONS[k]} is outside the supported subset (MatIEC)")
        self.error(e.pos, f"unknown function '{e.name}' (functions must be declared before they are used)")
