"""The C of the standard function calls: the emitters table.py's rows name, and the call that applies a row.

An emitter is `(gen, e, sc, cs, t, fam) -> str`: the code generator (codegen.CodeGen: its `expr`, `new_tmp`,
`site`, `read`, `time_binop`...), the call, its StdCall, the arguments' C, the result's type and the row.
"""

from __future__ import annotations

from .. import ast as A
from .. import types as T
from ..cnames import cname_of, is_time, vtype


def call(gen, e: A.Call, sc, fam) -> str:
    """The C of a checked standard function call (`fam` is the row of its family, sc.name)."""
    args = sc.args
    t = e.ty.base() if e.ty is not None else None
    if fam.rule == "conv":
        return fam.c(gen, e, sc, [], t, fam)
    if isinstance(sc.extra, tuple) and sc.extra and sc.extra[0] == "time":
        fake = A.BinOp(e.pos, fam.op, args[0], args[1])
        fake.ty = e.ty
        fake.time = True
        return gen.time_binop(fake, gen.expr(args[0]))
    # a REAL argument is rounded to REAL, as when MatIEC passes it to its C function
    cs = [f"((REAL)({gen.expr(a)}))" if a.ty is not None and a.ty.base() is T.REAL else gen.expr(a)
          for a in args]
    if fam.c is None:
        raise AssertionError(f"standard function {fam.name}")
    if isinstance(fam.c, str):
        kw = {}
        if "{t}" in fam.c:
            kw["t"] = t.cname
        if "{site}" in fam.c:
            kw["site"] = gen.site(e.pos).args()
        return fam.c.format(*cs, **kw)
    return fam.c(gen, e, sc, cs, t, fam)


def arith(op: str, a: str, b: str, t: T.Elem) -> str:
    if t.kind == "real":
        return f"({a} {op} {b})"
    u = "unsigned long long" if t.bits == 64 else "unsigned"
    return f"(({t.cname})(({u}){a} {op} ({u}){b}))"


def cmp_expr(op: str, a: str, b: str, t: T.Type) -> str:
    cop = {"=": "==", "<>": "!="}.get(op, op)
    tb = t.base()
    if isinstance(tb, T.Elem) and tb.kind == "string":
        return f"(__STRCMP({a}, {b}) {cop} 0)"
    return f"({a} {cop} {b})"


# ------------------------------------------------------------------ numbers
def fold_arith(gen, e, sc, cs, t, fam) -> str:
    acc = cs[0]
    for c in cs[1:]:
        acc = arith(fam.op, acc, c, t)
    return acc


def div(gen, e, sc, cs, t, fam) -> str:
    if t.kind == "real":
        return f"({cs[0]} / {cs[1]})"
    return f"__divf_{t.cname}({cs[0]}, {cs[1]})"


def expt(gen, e, sc, cs, t, fam) -> str:
    return f"(({cname_of(t)})__builtin_pow((double)({cs[0]}), (double)({cs[1]})))"


def abs_(gen, e, sc, cs, t, fam) -> str:
    if t.kind == "uint":
        return cs[0]
    if t.kind == "real":
        return f"({'__builtin_fabsf' if t is T.REAL else '__builtin_fabs'}({cs[0]}))"
    tmp = gen.new_tmp()
    u = "unsigned long long" if t.bits == 64 else "unsigned"
    return f"({{ {t.cname} {tmp} = {cs[0]}; {tmp} < 0 ? ({t.cname})(0 - ({u}){tmp}) : {tmp}; }})"


def trunc(gen, e, sc, cs, t, fam) -> str:
    """TRUNC to t: faults where MatIEC's direct C cast is undefined (the value does not fit t)."""
    a = cs[0]
    site = gen.site(e.pos).args()
    if t.kind == "uint":
        return f"(({t.cname})__trunc_u((double)({a}), {float(2 ** t.bits)!r}, {site}))"
    # the double just below -2^(bits-1), which -2^(bits-1) - 1 rounds to for 64 bits
    lo = -(2.0 ** (t.bits - 1)) - (1.0 if t.bits < 64 else 2048.0)
    return f"(({t.cname})__trunc_s((double)({a}), {lo!r}, {float(2 ** (t.bits - 1))!r}, {site}))"


# ------------------------------------------------------------------ bit strings
def fold_bits(bool_op: str, bit_op: str):
    """AND, OR, XOR of any number of arguments: logical on BOOL, bitwise on the other bit strings."""
    def emit(gen, e, sc, cs, t, fam) -> str:
        acc = cs[0]
        for c in cs[1:]:
            acc = f"({acc} {bool_op} {c})" if t is T.BOOL else f"(({t.cname})({acc} {bit_op} {c}))"
        return acc
    return emit


def not_(gen, e, sc, cs, t, fam) -> str:
    return f"(!{cs[0]})" if t is T.BOOL else f"(({t.cname})~{cs[0]})"


# ------------------------------------------------------------------ selection and comparison
def extreme(gen, e, sc, cs, t, fam) -> str:
    """MAX (op <: a greater value replaces the accumulator) and MIN (op >)."""
    t = sc.ty.base() if sc.ty else t
    vt = vtype(t)
    acc = gen.new_tmp()
    parts = [f"{vt} {acc} = {cs[0]}"]
    for c in cs[1:]:
        x = gen.new_tmp()
        parts.append(f"{vt} {x} = {c}")
        parts.append(f"if ({cmp_expr(fam.op, acc, x, t)}) {acc} = {x}")
    return "({ " + "; ".join(parts) + f"; {acc}; }})"


def limit(gen, e, sc, cs, t, fam) -> str:
    vt = vtype(t)
    mn, x, mx = (gen.new_tmp() for _ in range(3))
    gt = cmp_expr(">", x, mn, t)
    lt = cmp_expr("<", x, mx, t)
    return f"({{ {vt} {mn} = {cs[0]}, {x} = {cs[1]}, {mx} = {cs[2]}; {gt} ? ({lt} ? {x} : {mx}) : {mn}; }})"


def mux(gen, e, sc, cs, t, fam) -> str:
    k = gen.new_tmp()
    vt = vtype(t)
    default = gen.read(gen.c_value_expr(t, gen.default_value(t)), t) if is_time(t) else \
        gen.c_value_expr(t, gen.default_value(t))
    chain = default
    for i in range(len(cs) - 1, 0, -1):
        chain = f"({k} == {i - 1} ? {cs[i]} : {chain})"
    return f"({{ long long {k} = (long long)({cs[0]}); ({vt}){chain}; }})"


def compare(gen, e, sc, cs, t, fam) -> str:
    """GT, GE, EQ, LE, LT of a chain (each argument against the next), NE of two."""
    at = sc.ty.base()
    if len(cs) == 2:
        return cmp_expr(fam.op, cs[0], cs[1], at)
    tmps = [gen.new_tmp() for _ in cs]
    decl = f"{vtype(at)} " + ", ".join(f"{tn} = {c}" for tn, c in zip(tmps, cs))
    chain = " && ".join(cmp_expr(fam.op, tmps[i], tmps[i + 1], at) for i in range(len(tmps) - 1))
    return f"({{ {decl}; ({chain}); }})"


# ------------------------------------------------------------------ character strings
def concat(gen, e, sc, cs, t, fam) -> str:
    acc = cs[0]
    for c in cs[1:]:
        acc = f"__str_concat2({acc}, {c})"
    return acc


# ------------------------------------------------------------------ conversions
_TO_STRING = {
    "bool": "__str_from_bool({a})", "sint": "__str_from_sint((long long)({a}))",
    "uint": "__str_from_uint((unsigned long long)({a}))", "bit": "__str_from_bits((unsigned long long)({a}))",
    "real": "__str_from_real((double)({a}))", "time": "__str_from_time({a})",
    "date": "__str_from_date({a})", "tod": "__str_from_tod({a})", "dt": "__str_from_dt({a})",
}
_DATED = ("time", "date", "tod", "dt")


def conversion(gen, e, sc, cs, t, fam) -> str:
    """X_TO_Y, and BCD: as MatIEC's C (a faulting site where its C cast is undefined)."""
    src, dst = sc.conv
    if dst is None:
        dst = e.ty.base()
    dst = dst.base()
    a = gen.expr(sc.args[0])
    if src is T.REAL:
        a = f"((REAL)({a}))"
    if sc.kind == "bcd_decode":
        return f"(({dst.cname})__bcd_to_uint((unsigned long long)({a})))"
    if sc.kind == "bcd_encode":
        return f"(({dst.cname})__uint_to_bcd((unsigned long long)({a})))"
    s, d = src.kind, dst.kind
    if src is dst:
        return a
    if d == "string":
        return _TO_STRING[s].format(a=a)
    if s == "string":
        if d == "bool":
            return f"__str_to_bool({a})"
        if d in ("sint", "uint", "bit"):
            return f"(({dst.cname})__str_to_int({a}))"
        if d == "real":
            return f"(({dst.cname})__str_to_real({a}))"
        return f"__str_to_time({a})"
    if d == "bool":
        return f"({a} != 0)"
    if s in _DATED:
        if d in _DATED:
            if s == "dt" and d == "tod":
                return f"__dt_to_tod({a})"
            if s == "dt" and d == "date":
                return f"__dt_to_date({a})"
            return a
        if d == "real":
            return f"(({dst.cname})((double)({a}) / 1e9))"
        return f"(({dst.cname})(({a}) / 1000000000LL))"
    if d in _DATED:
        if s == "real":
            return f"__r2time((double)({a}), {gen.site(e.pos).args()})"
        if s == "uint" or s == "bit":
            return f"((__ns_t)((unsigned long long)({a}) * 1000000000ULL))"
        return f"((__ns_t)((unsigned long long)(long long)({a}) * 1000000000ULL))"
    if s == "real" and d in ("sint",):
        return f"(({dst.cname})__r2i((double)({a}), {gen.site(e.pos).args()}))"
    if s == "real" and d in ("uint", "bit"):
        return f"(({dst.cname})__r2u((double)({a}), {gen.site(e.pos).args()}))"
    return f"(({dst.cname})({a}))"
