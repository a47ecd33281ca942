"""Calls of the standard functions (stdfuncs.py's table): arguments, the type variable, the result."""

from __future__ import annotations

from .. import ast as A
from .. import stdfuncs as SF
from .. import types as T


def _shiftable(t) -> bool:
    return T.is_bit(t) and not T.same(t, T.BOOL)


def _selectable(t: T.Type) -> bool:
    tb = t.base()
    return isinstance(tb, T.Elem)


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
        n = fam.name

        def arg_types():
            return [self.infer(a) for a in args]

        if n == "CONV":
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
        if lk.kind == "time_arith":
            (a_t, b_t), res = lk.extra
            self.coerce(args[0], a_t, f"IN1 of {name}")
            self.coerce(args[1], b_t, f"IN2 of {name}")
            sc.ty = a_t
            sc.extra = ("time", res)
            return res
        if n in ("ADD", "SUB", "MUL", "DIV") and lk.fixed is None:
            tys = arg_types()
            firsts = [t for t in tys if not isinstance(t, T.Pseudo)]
            if firsts and T.is_time_like(firsts[0]) or (tys and not isinstance(tys[0], T.Pseudo) and T.is_time_like(tys[0])):
                if len(args) != 2:
                    self.error(e.pos, f"{name} of durations takes two arguments")
                fake = A.BinOp(e.pos, {"ADD": "+", "SUB": "-", "MUL": "*", "DIV": "/"}[n], args[0], args[1])
                res = self.time_arith(fake, fake.op, args[0], args[1], tys[0], tys[1])
                sc.ty = tys[0].base()
                sc.extra = ("time", res)
                return res
        if n in ("MULTIME", "DIVTIME"):
            self.coerce(args[0], T.TIME, f"IN1 of {name}")
            t = self.concrete(args[1])
            if lk.fixed is not None and not T.same(t, lk.fixed):
                self.error(args[1].pos, f"IN2 of {name} must be {lk.fixed.name}")
            if not T.is_num(t):
                self.error(args[1].pos, f"IN2 of {name} must be a number")
            sc.ty = T.TIME
            sc.extra = ("time", T.TIME)
            return T.TIME
        if n == "CONCAT_DATE_TOD":
            self.coerce(args[0], T.DATE, "IN1 of CONCAT_DATE_TOD")
            self.coerce(args[1], T.TOD, "IN2 of CONCAT_DATE_TOD")
            return T.DT
        if n == "EXPT":
            fake = A.BinOp(e.pos, "**", args[0], args[1])
            t = self.infer_BinOp(fake)
            if lk.fixed is not None:
                self.coerce(args[0], lk.fixed, f"IN1 of {name}")
                t = lk.fixed
            sc.ty = t if not isinstance(t, T.Pseudo) else None
            return t
        if n == "TRUNC":
            t = self.concrete_as(args[0], T.LREAL)
            if not T.is_real(t):
                self.error(args[0].pos, f"TRUNC needs a REAL or LREAL, not {T.describe(t)}")
            return T.poly(T.INTS, T.DINT)
        if n in ("LEN", "FIND", "LEFT", "RIGHT", "MID", "CONCAT", "INSERT", "DELETE", "REPLACE"):
            return self.string_call(e, sc, n, args)
        if n in ("SHL", "SHR", "ROL", "ROR"):
            nt = self.concrete(args[1])
            if not T.is_int(nt):
                self.error(args[1].pos, f"N of {name} must be an integer, not {T.describe(nt)}")
            # no BOOL: iec2c accepts SHL(b, 1) but calls SHL__BOOL__BOOL__SINT, which its headers do not define
            return self.tvar(e, sc, [args[0]], lk.fixed, _shiftable,
                             "a bit string other than BOOL (BYTE, WORD, DWORD or LWORD: iec2c accepts a BOOL, but "
                             "MatIEC's C defines no shift or rotate of a BOOL and does not compile)", name)
        if n == "SEL":
            self.coerce(args[0], T.BOOL, f"G of {name}")
            return self.tvar(e, sc, args[1:], lk.fixed, _selectable, "an elementary value", name)
        if n == "MUX":
            kt = self.concrete(args[0])
            if lk.kind == "mux_k" and not T.same(kt, lk.extra):
                self.error(args[0].pos, f"K of {name} must be {lk.extra.name}")
            if not T.is_int(kt):
                self.error(args[0].pos, f"K of MUX must be an integer, not {T.describe(kt)}")
            if len(args) < 2:
                self.error(e.pos, "MUX needs at least one input")
            return self.tvar(e, sc, args[1:], lk.fixed, _selectable, "an elementary value", name)
        if n in ("GT", "GE", "EQ", "LE", "LT", "NE"):
            t = self.tvar(e, sc, args, lk.fixed, _selectable, "an elementary value", name)
            if isinstance(t, T.Pseudo):
                for a in args:
                    self.settle(a, t.default)
                sc.ty = t.default
            return T.BOOL
        rules = {
            "ADD": (T.is_num, "a number"), "MUL": (T.is_num, "a number"), "SUB": (T.is_num, "a number"),
            "DIV": (T.is_num, "a number"), "MOD": (T.is_int, "an integer"), "ABS": (T.is_num, "a number"),
            "AND": (T.is_bit, "a bit string"), "OR": (T.is_bit, "a bit string"), "XOR": (T.is_bit, "a bit string"),
            "NOT": (T.is_bit, "a bit string"), "MOVE": (_selectable, "an elementary value"),
            "MAX": (_selectable, "an elementary value"), "MIN": (_selectable, "an elementary value"),
            "LIMIT": (_selectable, "an elementary value"),
        }
        for m in SF.MATH_1:
            rules[m] = (T.is_real, "a REAL or LREAL")
        pred, what = rules[n]
        t = self.tvar(e, sc, args, lk.fixed, pred, what, name)
        if n in SF.MATH_1 and isinstance(t, T.Pseudo) and t is T.LIT_INT:
            self.error(e.pos, f"{name} needs a REAL or LREAL argument")
        if n == "DIV" and self._is_zero(args[1]) and (isinstance(t, T.Pseudo) or T.is_int(t)):
            pass    # DIV(x, 0) is defined (0, as MatIEC's DIV function returns); only the operator faults
        return t

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

    def string_call(self, e, sc, n, args) -> T.Type:
        name = e.name.upper()
        layout = {
            "LEN": "S", "FIND": "SS", "LEFT": "SI", "RIGHT": "SI", "MID": "SII", "CONCAT": "S" * len(args),
            "INSERT": "SSI", "DELETE": "SII", "REPLACE": "SSII",
        }[n]
        for a, kind in zip(args, layout):
            if kind == "S":
                self.coerce(a, T.STRING, f"argument of {name}")
            else:
                t = self.concrete(a)
                if not T.is_int(t):
                    self.error(a.pos, f"{name}: an integer is expected, not {T.describe(t)}")
        if n in ("LEN", "FIND"):
            return T.poly(T.INTS, T.INT)
        return T.STRING
