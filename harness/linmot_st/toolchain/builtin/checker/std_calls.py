"""Calls of the standard functions: the arguments bound to the family's formal parameters, then the typing rule
its row in stdfuncs/table.py names (RULES), which resolves the type variable and the result."""

from __future__ import annotations

from .. import ast as A
from .. import stdfuncs as SF
from .. import types as T

# the typing rules a family's row names (`rule`), and the method of StdCalls that applies each
RULES = {
    "conv": "rule_conv", "arith": "rule_arith", "tvar": "rule_tvar", "math": "rule_math", "multime": "rule_multime",
    "concat_date_tod": "rule_concat_date_tod", "expt": "rule_expt", "trunc": "rule_trunc", "string": "rule_string",
    "shift": "rule_shift", "sel": "rule_sel", "mux": "rule_mux", "compare": "rule_compare",
}


class StdCalls:
    def std_args(self, e: A.Call, fam: SF.Family) -> list:
        """The argument expressions of a standard function call, in formal order."""
        args = e.args
        for a in args:
            if a.name and a.name.upper() in ("EN", "ENO"):
                self.error(a.pos, "EN/ENO on standard function calls is not supported by the builtin compiler")
            if a.output:
                self.error(a.pos, f"{e.name} has no output parameter '{a.name}'")
        formal = [a for a in args if a.name is not None]
        if formal and len(formal) != len(args):
            self.error(e.pos, f"call of {e.name} mixes formal and positional arguments")
        n = len(args)
        names = SF.param_names(fam, n)
        if formal:
            by_name = {a.name.upper(): a for a in args}
            if len(by_name) != len(args):
                self.error(e.pos, f"a parameter of {e.name} is given twice")
            if fam.extensible:
                names = SF.param_names(fam, max(n, len(fam.params)))
            out = []
            for nm in names:
                if nm in by_name:
                    out.append(by_name.pop(nm).value)
                elif not fam.extensible or len(out) < fam.min_args:
                    self.error(e.pos, f"{e.name}: missing parameter {nm}")
                else:
                    break
            if by_name:
                self.error(e.pos, f"{e.name} has no parameter '{next(iter(by_name))}'")
            args_v = out
        else:
            args_v = [a.value for a in args]
        if len(args_v) < fam.min_args or (not fam.extensible and len(args_v) != len(fam.params)):
            self.error(e.pos, f"{e.name} takes {len(fam.params)}{' or more' if fam.extensible else ''} "
                              f"arguments, {len(args_v)} given")
        return args_v

    def std_call(self, e: A.Call, lk: SF.Lookup) -> T.Type:
        fam = lk.family
        args = self.std_args(e, fam)
        sc = SF.StdCall(fam.name, args, kind=lk.kind, extra=lk.extra)
        e.target = sc
        name = e.name.upper()
        if lk.kind == "time_arith":             # ADD_TOD_TIME...: the types are the name's
            (a_t, b_t), res = lk.extra
            self.coerce(args[0], a_t, f"IN1 of {name}")
            self.coerce(args[1], b_t, f"IN2 of {name}")
            sc.ty = a_t
            sc.extra = ("time", res)
            return res
        return getattr(self, RULES[fam.rule])(e, lk, sc, fam, args, name)

    def rule_conv(self, e, lk, sc, fam, args, name) -> T.Type:
        if lk.conv is not None:
            src, dst = lk.conv
            self.coerce(args[0], src, f"argument of {name}")
            sc.conv = (src, dst)
            return dst
        if lk.kind == "bcd_decode":          # BCD_TO_USINT(ANY_NBIT)
            t = self.concrete_as(args[0], T.LWORD)
            if t.base() not in T.NBITS:
                self.error(args[0].pos, f"{name} needs BYTE, WORD, DWORD or LWORD")
            sc.conv = (t.base(), lk.extra)
            return lk.extra
        src = lk.extra                       # USINT_TO_BCD: result BYTE..LWORD from context
        self.coerce(args[0], src, f"argument of {name}")
        default = {T.USINT: T.BYTE, T.UINT: T.WORD, T.UDINT: T.DWORD, T.ULINT: T.LWORD}[src]
        sc.conv = (src, None)
        return T.poly(T.NBITS, default)

    def rule_arith(self, e, lk, sc, fam, args, name) -> T.Type:
        """ADD, SUB, MUL, DIV: of durations and dates as the operators are, else of numbers (rule_tvar)."""
        if lk.fixed is None:
            tys = [self.infer(a) for a in args]
            firsts = [t for t in tys if not isinstance(t, T.Pseudo)]
            if firsts and T.is_time_like(firsts[0]) or (tys and not isinstance(tys[0], T.Pseudo) and T.is_time_like(tys[0])):
                if len(args) != 2:
                    self.error(e.pos, f"{name} of durations takes two arguments")
                fake = A.BinOp(e.pos, fam.op, args[0], args[1])
                res = self.time_arith(fake, fake.op, args[0], args[1], tys[0], tys[1])
                sc.ty = tys[0].base()
                sc.extra = ("time", res)
                return res
        return self.rule_tvar(e, lk, sc, fam, args, name)

    def rule_tvar(self, e, lk, sc, fam, args, name) -> T.Type:
        """All arguments and the result of one type, which the row's `accepts` allows."""
        pred, what = fam.accepts
        return self.tvar(e, sc, args, lk.fixed, pred, what, name)

    def rule_math(self, e, lk, sc, fam, args, name) -> T.Type:
        t = self.rule_tvar(e, lk, sc, fam, args, name)
        if isinstance(t, T.Pseudo) and t is T.LIT_INT:
            self.error(e.pos, f"{name} needs a REAL or LREAL argument")
        return t

    def rule_multime(self, e, lk, sc, fam, args, name) -> T.Type:
        self.coerce(args[0], T.TIME, f"IN1 of {name}")
        t = self.concrete(args[1])
        if lk.fixed is not None and not T.same(t, lk.fixed):
            self.error(args[1].pos, f"IN2 of {name} must be {lk.fixed.name}")
        if not T.is_num(t):
            self.error(args[1].pos, f"IN2 of {name} must be a number")
        sc.ty = T.TIME
        sc.extra = ("time", T.TIME)
        return T.TIME

    def rule_concat_date_tod(self, e, lk, sc, fam, args, name) -> T.Type:
        self.coerce(args[0], T.DATE, "IN1 of CONCAT_DATE_TOD")
        self.coerce(args[1], T.TOD, "IN2 of CONCAT_DATE_TOD")
        return T.DT

    def rule_expt(self, e, lk, sc, fam, args, name) -> T.Type:
        fake = A.BinOp(e.pos, "**", args[0], args[1])
        t = self.infer_BinOp(fake)
        if lk.fixed is not None:
            self.coerce(args[0], lk.fixed, f"IN1 of {name}")
            t = lk.fixed
        sc.ty = t if not isinstance(t, T.Pseudo) else None
        return t

    def rule_trunc(self, e, lk, sc, fam, args, name) -> T.Type:
        t = self.concrete_as(args[0], T.LREAL)
        if not T.is_real(t):
            self.error(args[0].pos, f"TRUNC needs a REAL or LREAL, not {T.describe(t)}")
        return fam.result()

    def rule_string(self, e, lk, sc, fam, args, name) -> T.Type:
        """The string functions: each argument a STRING or an integer (the row's layout)."""
        for a, kind in zip(args, SF.string_layout(fam, len(args))):
            if kind == "S":
                self.coerce(a, T.STRING, f"argument of {name}")
            else:
                t = self.concrete(a)
                if not T.is_int(t):
                    self.error(a.pos, f"{name}: an integer is expected, not {T.describe(t)}")
        return fam.result() if fam.result is not None else T.STRING

    def rule_shift(self, e, lk, sc, fam, args, name) -> T.Type:
        nt = self.concrete(args[1])
        if not T.is_int(nt):
            self.error(args[1].pos, f"N of {name} must be an integer, not {T.describe(nt)}")
        pred, what = fam.accepts
        return self.tvar(e, sc, [args[0]], lk.fixed, pred, what, name)

    def rule_sel(self, e, lk, sc, fam, args, name) -> T.Type:
        self.coerce(args[0], T.BOOL, f"G of {name}")
        pred, what = fam.accepts
        return self.tvar(e, sc, args[1:], lk.fixed, pred, what, name)

    def rule_mux(self, e, lk, sc, fam, args, name) -> T.Type:
        kt = self.concrete(args[0])
        if lk.kind == "mux_k" and not T.same(kt, lk.extra):
            self.error(args[0].pos, f"K of {name} must be {lk.extra.name}")
        if not T.is_int(kt):
            self.error(args[0].pos, f"K of MUX must be an integer, not {T.describe(kt)}")
        if len(args) < 2:
            self.error(e.pos, "MUX needs at least one input")
        pred, what = fam.accepts
        return self.tvar(e, sc, args[1:], lk.fixed, pred, what, name)

    def rule_compare(self, e, lk, sc, fam, args, name) -> T.Type:
        pred, what = fam.accepts
        t = self.tvar(e, sc, args, lk.fixed, pred, what, name)
        if isinstance(t, T.Pseudo):
            for a in args:
                self.settle(a, t.default)
            sc.ty = t.default
        return T.BOOL

    def concrete_as(self, e, default: T.Type) -> T.Type:
        t = self.infer(e)
        if isinstance(t, T.Pseudo):
            if default.base() not in t.accepts:
                default = t.default
            self.settle(e, default)
            return default
        return t

    def tvar(self, e, sc, targs, fixed, pred, what, name) -> T.Type:
        """Resolve a type variable shared by `targs` (and the result)."""
        sc.tvar_args = targs
        sc.pred = (pred, what)
        if fixed is not None:
            for a in targs:
                self.coerce(a, fixed, f"argument of {name}")
            sc.ty = fixed
            return fixed
        tys = [self.infer(a) for a in targs]
        concrete = [(a, t) for a, t in zip(targs, tys) if not isinstance(t, T.Pseudo)]
        if concrete:
            a0, t0 = concrete[0]
            for a, t in concrete[1:]:
                if not T.same(t, t0) or isinstance(t, T.PouType):
                    self.error(a.pos, f"{name}: arguments of different types ({T.describe(t0)} and {T.describe(t)})")
            for a, t in zip(targs, tys):
                if isinstance(t, T.Pseudo):
                    if t0.base() not in t.accepts:
                        self.error(a.pos, f"{name}: {t.name} where {T.describe(t0)} is expected")
                    self.settle(a, t0.base())
            if not pred(t0):
                self.error(e.pos, f"{name} needs {what}, not {T.describe(t0)}")
            sc.ty = t0.base()
            return t0.base()
        # only literals: the result is a literal too, settled by its context
        kinds = {t for t in tys}
        if len(kinds) > 1 and all(t.literal for t in kinds):
            self.error(e.pos, f"{name}: arguments of different types")
        t = tys[0]
        if not any(pred(x) for x in t.accepts):
            self.error(e.pos, f"{name} needs {what}")
        return t

    def std_settle(self, e: A.Call, sc: SF.StdCall, t: T.Type) -> None:
        if getattr(sc, "pred", None) is not None:
            pred, what = sc.pred
            if not pred(t):
                self.error(e.pos, f"{e.name} needs {what}, not {T.describe(t)}")
            for a in sc.tvar_args:
                self.settle(a, t)
            sc.ty = t
        elif sc.name == "EXPT":
            self.settle(sc.args[0], t)
            sc.ty = t
        elif sc.name == "CONV" and sc.conv is not None:
            sc.conv = (sc.conv[0], t)
        else:
            sc.ty = t
