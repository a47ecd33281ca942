"""C generation from a checked program, and its manifest (docs/architecture.md 1.1, 1.2).

A shared header and one or more translation units (units.py cuts the C by size), no system header.
Layout as MatIEC's: each POU variable is a
`{T value; BYTE flags;}` wrapper whose writes are skipped while the force flag (0x02) is set,
external and located variables are `{T *value; BYTE flags;}`, FB instances are nested structs,
arrays are `struct { T table[n]...; }`. Durations and dates are stored as {tv_sec, tv_nsec} and
computed as 64-bit nanoseconds. Division by zero and indices out of range call
plc_raise_fault(kind, pou, file, line).

Every POU is a `static` C function, so gcc drops what no program reaches; what another unit calls is
hidden instead (units.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from . import ast as A
from . import stdfuncs as SF
from . import types as T
from . import units as U
from .cnames import cname_of, is_time
from .errors import BuiltinCompileError, Diagnostic
from .param_refs import by_reference
from .symbols import PouSym, Program, Var

FORCE = "__FORCED"
# operators of a left-associative chain per C sub-expression (gcc parses nesting recursively)
CHAIN_CHUNK = 200


def c_string(data: bytes) -> str:
    out = []
    for b in data:
        c = chr(b)
        if c == '"' or c == "\\":
            out.append("\\" + c)
        elif 32 <= b < 127 and c != "?":
            out.append(c)
        else:
            out.append(f"\\{b:03o}")
    return '"' + "".join(out) + '"'


# A PROGRAM or FUNCTION_BLOCK body longer than this many C lines is cut into functions of about this
# length at statement boundaries: gcc's time and memory grow faster than linearly with one function's
# length (docs/builtin-compiler.md, "Long bodies").
BODY_PART_LINES = 1000
# the file name of the C between ST bodies in a coverage build (line_reset): not a .st, so left out of reports
GENERATED_FILE = "plc_builtin.generated.c"
# A constant initialiser longer than this (a PVL dataset) is a file-scope constant of its own, which
# units.py may put in another unit than the code that copies it
DATA_CHUNK_CHARS = 20_000


def c_int(v: int, t: T.Type) -> str:
    tb = t.base()
    bits = tb.bits if isinstance(tb, T.Elem) else 32
    if bits == 64:
        if v == -(1 << 63):
            return "(-9223372036854775807LL - 1)"
        return f"{v}ULL" if tb.kind in ("uint", "bit") else f"{v}LL"
    if v == -(1 << 31):
        return "(-2147483647 - 1)"
    if tb.kind in ("uint", "bit") and bits == 32:
        return f"{v}U"
    return str(v)


def c_real(v: float, text: str | None = None) -> str:
    if math.isinf(v) or math.isnan(v):
        raise ValueError("non-finite real literal")
    r = repr(float(v))
    if "e" not in r and "." not in r:
        r += ".0"
    return r


@dataclass
class Site:
    pou: str      # C name of the POU's name string
    file: str     # C name of the file string
    line: int

    def args(self) -> str:
        return f"{self.pou}, {self.file}, {self.line}"


class CodeGen:
    def __init__(self, prog: Program, backend_version: str, line_directives: bool = False):
        self.prog = prog
        self.version = backend_version
        # `#line` before each statement (and ELSIF, UNTIL, FOR step), so gcc's line table and gcov's counts
        # name ST lines (coverage builds, docs/coverage.md); the C after a body goes back to GENERATED_FILE
        self.line_directives = line_directives
        self.generated_line = 0
        self.st_line: str | None = None       # the `#line` of the statement being generated
        self.lines: list[str] = []
        self.wrapped: list[str] = []          # C types needing __DECLARE_V, in order
        self._wrapped_set: set[str] = set()
        self.file_ids: dict[str, str] = {}
        self.pou_ids: dict[str, str] = {}
        self.pou: PouSym | None = None
        self.tmp = 0
        self.label = 0
        self.loops: list[tuple[str, str]] = []
        self.body: list[str] = []
        self.indent = 1
        self.needed_types: set = set()
        self.gflag_index: dict[str, int] = {}
        self.chunks: list[U.Chunk] = []
        self.pending_data: list[U.Chunk] = []     # constants of the chunk being generated: placed before it
        self.data_names = 0                         # __data0, __data1 ...: one per constant chunk
        self.by_ref = by_reference(prog)            # FB parameters passed as pointers (param_refs.py)

    # ------------------------------------------------------------------ helpers
    def is_ref(self, v: Var) -> bool:
        """Whether v is an FB parameter held as a pointer to the actual (param_refs.py), not a copy."""
        return v.kind in ("VAR_IN_OUT", "VAR_INPUT") and v.pou is not None and (v.pou.key, v.key) in self.by_ref

    def wrap(self, t: T.Type) -> str:
        c = cname_of(t)
        if c not in self._wrapped_set:
            self._wrapped_set.add(c)
            self.wrapped.append(c)
        return c

    def file_id(self, name: str) -> str:
        if name not in self.file_ids:
            self.file_ids[name] = f"__file{len(self.file_ids)}"
        return self.file_ids[name]

    def site(self, pos: A.Pos) -> Site:
        return Site(self.pou_ids[self.pou.key], self.file_id(pos.file), pos.line)

    def new_tmp(self) -> str:
        self.tmp += 1
        return f"__t{self.tmp}"

    def emit(self, text: str) -> None:
        if self.st_line is not None:
            # each C line its own directive: a statement's C may take several lines, all of its ST line
            self.body.append(self.st_line)
        self.body.append("  " * self.indent + text)

    def line_at(self, pos: A.Pos) -> None:
        """The C emitted next is the code of this ST position (coverage builds)."""
        if self.line_directives:
            self.st_line = f"#line {pos.line} {c_string(pos.file.encode())}"

    def line_reset(self, lines: list[str]) -> None:
        """The C that follows is no ST line's: it counts on lines of GENERATED_FILE, which reports leave out
        (a distinct line per reset, so gcov never merges two of them)."""
        if self.line_directives:
            self.st_line = None
            self.generated_line += 1
            lines.append(f'#line {self.generated_line} "{GENERATED_FILE}"')

    # ------------------------------------------------------------------ values (initial values, defaults)
    def default_value(self, t: T.Type):
        """A value tree of the default value of t."""
        if isinstance(t, T.Alias):
            if t.init is not None:
                return self.value_of(t.init, t.of)
            return self.default_value(t.of)
        if isinstance(t, T.Subrange):
            if getattr(t, "init", None) is not None:
                return self.value_of(t.init, t)
            return t.lo
        if isinstance(t, T.Enum):
            return getattr(t, "init", 0) or 0
        if isinstance(t, T.Array):
            if getattr(t, "init", None) is not None:
                return self.value_of(t.init, t)
            d = self.default_value(t.elem)
            return [d] * t.count
        if isinstance(t, T.Struct):
            return [self.value_of(f.init, f.ty) if f.init is not None else self.default_value(f.ty) for f in t.fields]
        if isinstance(t, T.Elem):
            if t.kind == "string":
                return b""
            if t.kind == "real":
                return 0.0
            return 0
        raise AssertionError(f"no default value for {t}")

    def value_of(self, init: A.Node, t: T.Type):
        if init is None:
            return self.default_value(t)
        if isinstance(init, A.ArrayInit) and init.ints is not None:
            d = self.default_value(t.elem)
            return list(init.ints.values) + [d] * (t.count - len(init.ints.values))
        if isinstance(init, A.ArrayInit):
            vals = []
            for count, v in init.items:
                item = self.value_of(v, t.elem) if v is not None else self.default_value(t.elem)
                vals.extend([item] * count)
            d = self.default_value(t.elem)
            vals.extend([d] * (t.count - len(vals)))
            return vals
        if isinstance(init, A.StructInit):
            given = {k.upper(): v for k, _, v in init.items}
            if isinstance(t, T.PouType):
                return given
            return [self.value_of(given[f.key], f.ty) if f.key in given else
                    (self.value_of(f.init, f.ty) if f.init is not None else self.default_value(f.ty)) for f in t.fields]
        if isinstance(init, A.Literal):
            if init.kind == "real":
                return float(init.value)
            return init.value
        if isinstance(init, (A.EnumLit, A.Name)):
            en = t.base()
            return en.values.index((init.value if isinstance(init, A.EnumLit) else init.name).upper())
        raise AssertionError(f"unsupported initial value {init}")

    @staticmethod
    def is_zero(v) -> bool:
        if isinstance(v, list):
            return all(CodeGen.is_zero(x) for x in v)
        if isinstance(v, bytes):
            return v == b""
        return v == 0

    def c_init(self, t: T.Type, v) -> str:
        """A C initializer for a value tree of type t."""
        tb = t.base() if isinstance(t, (T.Alias, T.Subrange)) else t
        if isinstance(tb, T.Array):
            if self.is_zero(v):
                return "{{0}}"
            eb = tb.elem.base()
            if isinstance(eb, T.Elem) and eb.kind in ("uint", "bit") and eb.bits == 32:
                return "{{" + ",".join([f"{x}U" for x in v]) + "}}"    # the dataset's DWORDs: c_int, fast
            return "{{" + ", ".join(self.c_init(tb.elem, x) for x in v) + "}}"
        if isinstance(tb, T.Struct):
            if self.is_zero(v):
                return "{0}"
            return "{" + ", ".join(self.c_init(f.ty, x) for f, x in zip(tb.fields, v)) + "}"
        if isinstance(tb, T.Enum):
            return str(v)
        if tb.kind == "string":
            return "{" + f"{len(v)}, {c_string(v)}" + "}"
        if tb.kind in ("time", "date", "tod", "dt"):
            sec = abs(v) // 10**9 * (1 if v >= 0 else -1)      # truncated toward zero, as the runtime does
            return "{" + f"{sec}L, {v - sec * 10**9}L" + "}"
        if tb.kind == "real":
            return c_real(v)
        return c_int(int(v), tb)

    def c_value_expr(self, t: T.Type, v) -> str:
        """A C expression (storage type) for a value tree."""
        tb = t.base() if isinstance(t, (T.Alias, T.Subrange)) else t
        if isinstance(tb, (T.Array, T.Struct)) or (isinstance(tb, T.Elem) and tb.kind in ("string", "time", "date", "tod", "dt")):
            return f"(({cname_of(tb)}){self.c_init(tb, v)})"
        return self.c_init(tb, v)

    # ------------------------------------------------------------------ program
    def generate(self) -> tuple[str, dict]:
        """(the C as one text, the manifest)."""
        header, units, manifest = self.generate_units(max_units=1)
        return header + units[0].split("\n", 1)[1], manifest

    def generate_units(self, max_units: int | None = None) -> tuple[str, list[str], dict]:
        """(the shared header plc_builtin.h, the text of each translation unit, the manifest)."""
        prog = self.prog
        out: list[str] = []
        out.append(f"/* Generated by the linmot_st builtin ST compiler {self.version}. Do not edit. */")
        out.append('#include "builtin_rt.h"')
        out.append("")
        out.append("/* ---- types */")
        for t in prog.types:
            out.extend(self.type_decl(t))
        pous = [p for p in prog.pous if not p.no_code]     # {disable code generation}: checked, not generated
        for p in pous:
            self.pou_ids[p.key] = f"__pou_{p.key}"
        # POU structs (their members need wrappers first)
        structs: list[str] = []
        for p in pous:
            if p.kind != "FUNCTION":
                structs.extend(self.pou_struct(p))
        names = U.Chunk()                   # the names and globals, first: every POU may use them
        self.chunks = [names]
        globals_decl = self.global_decls()
        for p in pous:
            try:
                self.pou_code(p)
            except RecursionError:      # a backstop: the checker bounds the nesting (nesting.py)
                raise BuiltinCompileError([Diagnostic(p.pos.file, p.pos.line, p.pos.col,
                                                      f"expression nested too deeply in {p.name}")]) from None
        config = self.config_code()
        tables, manifest = self.tables_and_manifest()
        self.add_chunk(U.Chunk(config + tables))
        out.append("/* ---- variable wrappers */")
        for c in self.wrapped:
            out.append(f"__DECLARE_V({c})")
        out.append("")
        out.extend(structs)
        names.lines.append("/* ---- names for fault reports */")
        for name, cid in self.file_ids.items():
            names.define(cid, f"static const char {cid}[] = {c_string(name.encode())};",
                         f"extern {U.HIDDEN} const char {cid}[];")
        for p in pous:
            cid = self.pou_ids[p.key]
            names.define(cid, f"static const char {cid}[] = {c_string(p.key.encode())};",
                         f"extern {U.HIDDEN} const char {cid}[];")
        names.lines.append("")
        for sym, line, decl in globals_decl:
            if sym is None:
                names.lines.append(line)
            else:
                names.define(sym, line, decl)
        header, units = U.split(out, self.chunks, max_units)
        return header, units, manifest

    def add_chunk(self, chunk: U.Chunk) -> None:
        """Append a chunk of C, after the constants its generation hoisted out (assign_value)."""
        self.chunks += self.pending_data
        self.pending_data = []
        self.chunks.append(chunk)

    def type_decl(self, t: T.Type) -> list[str]:
        if isinstance(t, T.Enum):
            return [f"typedef int {t.cname};   /* {', '.join(t.values)} */"]
        if isinstance(t, T.Array):
            dims = "".join(f"[{hi - lo + 1}]" for lo, hi in t.dims)
            return [f"typedef struct {{ {cname_of(t.elem)} table{dims}; }} {t.cname};"]
        if isinstance(t, T.Struct):
            fields = " ".join(f"{cname_of(f.ty)} {f.key};" for f in t.fields)
            return [f"typedef struct {{ {fields} }} {t.cname};"]
        return []

    def member_decl(self, v: Var) -> str:
        if v.is_fb_instance:
            if v.kind == "VAR_EXTERNAL":
                return f"  {v.ty.cname} *{v.key};"
            return f"  {v.ty.cname} {v.key};"
        c = self.wrap(v.ty)
        if v.kind == "VAR_EXTERNAL" or v.location or self.is_ref(v):
            return f"  __P_{c} {v.key};"
        return f"  __V_{c} {v.key};"

    def pou_struct(self, p: PouSym) -> list[str]:
        lines = [f"typedef struct {{   /* {p.kind} {p.name} */"]
        members = p.layout()
        for v in members:
            lines.append(self.member_decl(v))
        if not members:
            lines.append("  BYTE __empty;")
        lines.append(f"}} {p.ty.cname};")
        lines.append("")
        return lines

    # ------------------------------------------------------------------ globals
    def global_vars(self):
        cfg = self.prog.config
        if cfg is None:
            return
        for v in cfg.globals.values():
            yield f"{cfg.key}__{v.key}", f"{cfg.key}.{v.key}", v, None
        for r in cfg.resources:
            for v in r.globals.values():
                yield f"{r.key}__{v.key}", f"{r.path()}.{v.key}", v, r

    def global_decls(self) -> list[tuple[str | None, str, str | None]]:
        """(symbol, its defining line, its declaration for other units) of each global; None: a plain line."""
        lines: list[tuple[str | None, str, str | None]] = [(None, "/* ---- located variables, globals, program instances */", None)]

        def var(ctype: str, cname: str) -> None:
            lines.append((cname, f"static {ctype} {cname};", f"extern {U.HIDDEN} {ctype} {cname};"))

        for cell in self.prog.located.values():
            var(cname_of(cell.ty), cell.cname)
        for cname, _, v, _ in self.global_vars():
            if v.is_fb_instance:
                var(v.ty.cname, cname)
                continue
            c = self.wrap(v.ty)
            kind = "__P_" if v.location else "__V_"
            var(f"{kind}{c}", cname)
        cfg = self.prog.config
        if cfg is not None:
            for r in cfg.resources:
                for inst in r.programs:
                    var(inst.pou.ty.cname, f"{r.key}__{inst.key}")
        # the force flags of each global, for writes through VAR_EXTERNAL (0: none, for unbound ones)
        flags = ["&__no_gflag"] + [f"&{cname}.flags" for cname, _, v, _ in self.global_vars() if not v.is_fb_instance]
        self.gflag_index = {cname: i + 1 for i, (cname, _, v, _) in
                            enumerate(g for g in self.global_vars() if not g[2].is_fb_instance)}
        var("BYTE", "__no_gflag")
        lines.append(("__gflags", f"static BYTE *const __gflags[] = {{{', '.join(flags)}}};",
                      f"extern {U.HIDDEN} BYTE *const __gflags[];"))
        lines.append((None, "", None))
        return lines

    # ------------------------------------------------------------------ POU code
    def pou_code(self, p: PouSym) -> None:
        """Add the POU's chunks: a FUNCTION; or an init, the parts of a long body, the body."""
        self.pou = p
        self.tmp = 0
        self.label = 0
        if p.kind == "FUNCTION":
            lines = self.function_code(p)
            small = sum(len(x) + 1 for x in lines) <= U.COPY_MAX_CHARS
            self.add_chunk(self.code_chunk(lines, [p.key], "copy" if small else "code"))
            return
        self.add_chunk(self.code_chunk(self.init_code(p), [f"{p.key}_init__"]))
        for name, lines in self.body_code(p):
            self.add_chunk(self.code_chunk(lines, [name]))

    @staticmethod
    def code_chunk(lines: list[str], names: list[str], kind: str = "code") -> U.Chunk:
        """A chunk of functions; lines[k] is the definition of names[k] when it is the first line of the
        form `...static <type> name(` in `lines`."""
        chunk = U.Chunk(kind=kind)
        heads = {}
        for name in names:
            heads[next(k for k, line in enumerate(lines) if "static " in line and f" {name}(" in line
                       and not line.startswith(" "))] = name
        for k, line in enumerate(lines):
            if k in heads:
                chunk.define(heads[k], line, U.shared(line) + ";")
            else:
                chunk.lines.append(line)
        return chunk

    def local_name(self, v: Var) -> str:
        return f"l_{v.key}"

    def function_code(self, p: PouSym) -> list[str]:
        params = ["BOOL *o_ENO"]
        for v in p.params:
            c = cname_of(v.ty)
            if v.kind == "VAR_INPUT":
                params.append(f"{c} {self.local_name(v)}")
            elif v.kind == "VAR_IN_OUT":
                params.append(f"{c} *{self.local_name(v)}")
            else:
                params.append(f"{c} *o_{v.key}")
        rt = cname_of(p.return_type)
        lines = [f"static {rt} {p.key}({', '.join(params) or 'void'})", "{"]
        for v in p.vars.values():
            if v.kind in ("VAR", "VAR_TEMP", "VAR_OUTPUT") or v.implicit:      # EN is TRUE: the body runs
                val = self.value_of(v.init, v.ty) if v.init is not None else self.default_value(v.ty)
                lines.append(f"  {cname_of(v.ty)} {self.local_name(v)} = {self.c_init(v.ty, val)};")
        lines.append(f"  {rt} l_{p.key} = {self.c_init(p.return_type, self.default_value(p.return_type))};")
        self.body = []
        self.indent = 1
        self.statements(p.ast.body)
        lines.extend(self.body)
        self.line_reset(lines)
        lines.append("__end: ;")
        for v in p.params:
            if v.kind == "VAR_OUTPUT":
                lines.append(f"  if (o_{v.key}) *o_{v.key} = {self.local_name(v)};")
        lines.append("  if (o_ENO) *o_ENO = l_ENO;")
        lines.append(f"  return l_{p.key};")
        lines.append("}")
        lines.append("")
        return lines

    def init_code(self, p: PouSym) -> list[str]:
        # not inlined: one init per POU type keeps config_init__ small (and gcc fast)
        lines = [f"__attribute__((noinline, cold)) static void {p.key}_init__({p.ty.cname} *data__, int res__)",
                 "{", "  (void)res__;"]
        for v in p.layout():
            lines.extend(self.init_member(v, "data__->"))
        lines.append("}")
        lines.append("")
        return lines

    def init_member(self, v: Var, prefix: str) -> list[str]:
        lines = []
        if v.is_fb_instance and v.kind == "VAR_EXTERNAL":
            lines.append(f"  {prefix}{v.key} = 0;")
            cases = self.external_targets(v)
            if cases:
                lines.append("  switch (res__) {")
                for idx, target, _ in cases:
                    lines.append(f"  case {idx}: {prefix}{v.key} = &{target}; break;")
                lines.append("  }")
            return lines
        if v.is_fb_instance:
            lines.append(f"  {v.ty.pou.key}_init__(&{prefix}{v.key}, res__);")
            if isinstance(v.init, A.StructInit):
                given = self.value_of(v.init, v.ty)
                for k, node in given.items():
                    mv = v.ty.pou.vars[k]
                    val = self.value_of(node, mv.ty)
                    lines.append(f"  {prefix}{v.key}.{k}.value = {self.c_value_expr(mv.ty, val)};")
            return lines
        if v.kind == "VAR_EXTERNAL":
            lines.append(f"  {prefix}{v.key}.flags = 0;")
            lines.append(f"  {prefix}{v.key}.gflag = 0;")
            lines.append(f"  {prefix}{v.key}.value = 0;")
            cases = self.external_targets(v)
            if cases:
                lines.append("  switch (res__) {")
                for idx, target, gcname in cases:
                    lines.append(f"  case {idx}: {prefix}{v.key}.value = &{target}; "
                                 f"{prefix}{v.key}.gflag = {self.gflag_index[gcname]}; break;")
                lines.append("  }")
            return lines
        if self.is_ref(v):          # set by each call before the body runs
            return [f"  {prefix}{v.key}.flags = 0;", f"  {prefix}{v.key}.value = 0;"]
        val = self.value_of(v.init, v.ty) if v.init is not None else self.default_value(v.ty)
        if v.location:
            cell = self.prog.located[v.location]
            lines.append(f"  {prefix}{v.key}.flags = 0;")
            lines.append(f"  {prefix}{v.key}.value = &{cell.cname};")
            lines.append(f"  {cell.cname} = {self.c_value_expr(v.ty, val)};")
            return lines
        lines.append(f"  {prefix}{v.key}.flags = 0;")
        lines.append(self.assign_value(f"{prefix}{v.key}.value", v.ty, val))
        return lines

    def assign_value(self, place: str, t: T.Type, val) -> str:
        tb = t.base() if isinstance(t, (T.Alias, T.Subrange)) else t
        if isinstance(tb, (T.Array, T.Struct)):
            if self.is_zero(val):
                return f"  __builtin_memset(&{place}, 0, sizeof {place});"
            name = f"__data{self.data_names}"        # taken (counted) only by a constant chunk below
            words = U.dword_bytes(tb, val)
            if words is not None:
                self.data_names += 1
                # as a string: gcc reads it about 6 times faster than the list of integers
                data = U.Chunk(kind="string")
                data.define(name, f"static const char {name}[{len(words)}] __attribute__((aligned(8))) = "
                                  f"{U.c_bytes(words)};", f"extern {U.HIDDEN} const char {name}[{len(words)}];")
                data.lines.append(f"_Static_assert(sizeof({cname_of(tb)}) == {len(words)}, \"{name}\");")
                self.pending_data.append(data)
                return "\n".join([f"  __builtin_memcpy(&{place}, {name}, sizeof {place});",
                                  "#if __BYTE_ORDER__ == __ORDER_BIG_ENDIAN__    /* the string is little-endian */",
                                  f"  {{ DWORD *__w = (DWORD *)&{place}; unsigned long __k;",
                                  f"    for (__k = 0; __k < sizeof {place} / 4; __k++) __w[__k] = __builtin_bswap32(__w[__k]); }}",
                                  "#endif"])
            init = self.c_init(tb, val)
            if len(init) > DATA_CHUNK_CHARS:
                self.data_names += 1
                data = U.Chunk(kind="data")
                data.define(name, f"static const {cname_of(tb)} {name} = {init};",
                            f"extern {U.HIDDEN} const {cname_of(tb)} {name};")
                self.pending_data.append(data)
                return f"  {place} = {name};"
            return f"  {{ static const {cname_of(tb)} __init = {init}; {place} = __init; }}"
        return f"  {place} = {self.c_value_expr(tb, val)};"

    def external_targets(self, v: Var) -> list[tuple[int, str, str]]:
        """(resource index, C lvalue of the global's value, C name of the global) for each resource."""
        cfg = self.prog.config
        if cfg is None:
            return []
        out = []
        for i, r in enumerate(cfg.resources):
            g = r.globals.get(v.key)
            if g is not None:
                target = f"{r.key}__{g.key}"
            else:
                g = cfg.globals.get(v.key)
                if g is None:
                    continue
                target = f"{cfg.key}__{g.key}"
            if g.is_fb_instance:
                out.append((i, target, target))
            else:
                out.append((i, f"(*{target}.value)" if g.location else f"{target}.value", target))
        return out

    def body_code(self, p: PouSym) -> list[tuple[str, list[str]]]:
        """(function name, C lines) of each part of a long body, then of the body."""
        # FB bodies are not inlined into their callers: gcc's time grows faster than linearly with the
        # size of a function, and a call costs a few nanoseconds
        lines = [f"__attribute__((noinline)) static void {p.key}_body__({p.ty.cname} *data__)", "{"]
        self.body = []
        self.indent = 1
        if p.kind == "FUNCTION_BLOCK":
            lines.append("  if (!data__->EN.value) {")
            lines.append(f"    if (!(data__->ENO.flags & {FORCE})) data__->ENO.value = 0;")
            lines.append("    return;")
            lines.append("  }")
            lines.append(f"  if (!(data__->ENO.flags & {FORCE})) data__->ENO.value = 1;")
        for v in p.layout():
            if v.kind == "VAR_TEMP":
                lines.extend(self.init_member(v, "data__->"))
        parts = self.body_parts(p.ast.body)
        head = []
        if len(parts) == 1:
            lines.extend(parts[0])
            self.line_reset(lines)
        else:
            # a long body: each part its own function (gcc's cost grows faster than the length of one);
            # a RETURN inside a part ends the part with 1, and the body with it
            for k, part in enumerate(parts, 1):
                name = f"{p.key}_body__part{k}"
                reset: list[str] = []
                self.line_reset(reset)
                head.append((name, [f"__attribute__((noinline)) static int {name}({p.ty.cname} *data__)", "{",
                                    *part, *reset, "  return 0;", "__end: return 1;", "}", ""]))
                lines.append(f"  if ({name}(data__)) goto __end;")
        lines.append("__end: ;")
        lines.append("}")
        lines.append("")
        return head + [(f"{p.key}_body__", lines)]

    def body_parts(self, stmts: list[A.Node]) -> list[list[str]]:
        """The C lines of a body's statements, cut after the statement that passes BODY_PART_LINES."""
        parts = []
        self.body = []
        for s in stmts:
            self.line_at(s.pos)
            getattr(self, "st_" + type(s).__name__)(s)
            if len(self.body) >= BODY_PART_LINES:
                parts.append(self.body)
                self.body = []
        if self.body or not parts:
            parts.append(self.body)
        return parts

    # ------------------------------------------------------------------ places (lvalues)
    def place(self, e: A.Node) -> tuple[str, str | None]:
        """(C lvalue of the storage, C expression of the force flags guarding it, or None)."""
        if isinstance(e, A.Name):
            v = e.sym
            if v.kind == "RESULT":
                return f"l_{v.key}", None
            if v.pou is not None and v.pou.kind == "FUNCTION":
                if v.kind == "VAR_IN_OUT":
                    return f"(*{self.local_name(v)})", None
                return self.local_name(v), None
            if v.is_fb_instance:
                if v.kind == "VAR_EXTERNAL":
                    return f"(*data__->{v.key})", None
                return f"data__->{v.key}", None
            if v.kind == "VAR_EXTERNAL":
                return f"(*data__->{v.key}.value)", self.external_flags(f"data__->{v.key}")
            if v.location or self.is_ref(v):
                return f"(*data__->{v.key}.value)", f"data__->{v.key}.flags"
            return f"data__->{v.key}.value", f"data__->{v.key}.flags"
        if isinstance(e, A.Member):
            bp, bflags = self.place(e.base)
            bt = e.base.ty
            if isinstance(bt, T.PouType):
                v = e.sym
                if v.is_fb_instance:
                    return f"{bp}.{v.key}", None
                if v.kind == "VAR_EXTERNAL":
                    return f"(*{bp}.{v.key}.value)", self.external_flags(f"{bp}.{v.key}")
                if v.location or self.is_ref(v):
                    return f"(*{bp}.{v.key}.value)", f"{bp}.{v.key}.flags"
                return f"{bp}.{v.key}.value", f"{bp}.{v.key}.flags"
            return f"{bp}.{e.sym.key}", bflags
        if isinstance(e, A.Index):
            bp, bflags = self.place(e.base)
            arr = e.base.ty.base()
            idx = "".join(f"[{self.index(i, lo, hi)}]" for i, (lo, hi) in zip(e.indices, arr.dims))
            return f"{bp}.table{idx}", bflags
        raise AssertionError(f"not a place: {e}")

    @staticmethod
    def external_flags(wrapper: str) -> str:
        """The force flags guarding a write through a VAR_EXTERNAL: its own and its global's."""
        return f"({wrapper}.flags | *__gflags[{wrapper}.gflag])"

    def index(self, e: A.Node, lo: int, hi: int) -> str:
        if isinstance(e, A.Literal):
            return str(e.value - lo)
        c = self.expr(e)
        t = e.ty.base()
        fn = "__ixu" if (isinstance(t, T.Elem) and t.kind == "uint" and t.bits == 64) else "__ix"
        return f"{fn}({c}, {lo}, {hi}, {self.site(e.pos).args()})"

    def store(self, place: str, flags: str | None, t: T.Type, value: str) -> None:
        if is_time(t):
            value = f"__ns2t({value})"
        if flags is None:
            self.emit(f"{place} = {value};")
        else:
            self.emit(f"if (!({flags} & {FORCE})) {place} = {value};")

    # ------------------------------------------------------------------ statements
    def statements(self, stmts: list[A.Node]) -> None:
        for s in stmts:
            self.line_at(s.pos)
            getattr(self, "st_" + type(s).__name__)(s)

    def st_Assign(self, s: A.Assign) -> None:
        value = self.expr(s.value)
        p, flags = self.place(s.target)
        self.store(p, flags, s.target.ty, value)

    def st_CallStmt(self, s: A.CallStmt) -> None:
        call = s.call
        if isinstance(call.target, tuple) and call.target[1] is not None:
            self.fb_call(call)
        else:
            self.emit(f"(void)({self.expr(call)});")

    def fb_call(self, call: A.Call) -> None:
        pou, inst, bound = call.target
        ip, _ = self.inst_place(call, inst)
        posts = []
        # in the FB's declaration order (EN first), not the call's, as MatIEC (generate_c_st.cc,
        # fb_invocation_c): an argument's side effect (a FUNCTION's in-out) and which of two copies-out to
        # the same variable wins depend on it
        order = {k: i for i, k in enumerate(pou.vars)}
        for p, a in sorted(bound, key=lambda pa: order[pa[0].key]):
            if self.is_ref(p):
                src, sflags = self.place(a.value)
                self.emit(f"{ip}.{p.key}.value = &{src};")
                if sflags is not None and p.kind == "VAR_IN_OUT":
                    # a forced actual: the body works on a copy that is dropped, as copy-in/copy-out leaves
                    # the actual; static, so that the pointer (and those passed on from it) stay valid and
                    # read what the body left in it, as the copy would
                    tmp, ct = self.new_tmp(), cname_of(p.ty)
                    self.emit(f"if (__builtin_expect({sflags} & {FORCE}, 0)) "
                              f"{{ static {ct} {tmp}; {tmp} = {src}; {ip}.{p.key}.value = &{tmp}; }}")
                continue
            if p.kind == "VAR_INPUT":
                if p.is_fb_instance:
                    self.emit(f"{ip}.{p.key} = {self.expr(a.value)};")
                else:
                    self.store(f"{ip}.{p.key}.value", f"{ip}.{p.key}.flags", p.ty, self.expr(a.value))
            elif p.kind == "VAR_IN_OUT":
                src, sflags = self.place(a.value)
                if p.is_fb_instance:
                    self.emit(f"{ip}.{p.key} = {src};")
                    posts.append((src, sflags, f"{ip}.{p.key}", p.ty, False))
                else:
                    self.emit(f"if (!({ip}.{p.key}.flags & {FORCE})) {ip}.{p.key}.value = {src};")
                    posts.append((src, sflags, f"{ip}.{p.key}.value", p.ty, False))
            else:
                posts.append((None, None, f"{ip}.{p.key}.value", p.ty, a.value))
        self.emit(f"{pou.key}_body__(&{ip});")
        for src, sflags, member, ty, target in posts:
            if target is False:
                self.emit_copy(src, sflags, member)
            else:
                tp, tflags = self.place(target)
                value = f"__T2NS({member})" if is_time(ty) else member
                self.store(tp, tflags, target.ty, value)

    def emit_copy(self, dst: str, flags: str | None, src: str) -> None:
        if flags is None:
            self.emit(f"{dst} = {src};")
        else:
            self.emit(f"if (!({flags} & {FORCE})) {dst} = {src};")

    def inst_place(self, call: A.Call, inst: Var) -> tuple[str, None]:
        name = A.Name(call.pos, inst.name)
        name.sym = inst
        return self.place(name)

    def nested(self, body: list[A.Node], loop: int | None = None) -> None:
        """The statements of a block one level deeper. In the body of loop `loop`, EXIT and CONTINUE jump to
        its labels, and the continue label ends the body."""
        self.indent += 1
        if loop is not None:
            self.loops.append((f"__exit{loop}", f"__cont{loop}"))
        self.statements(body)
        if loop is not None:
            self.loops.pop()
            self.emit(f"__cont{loop}: ;")
        self.indent -= 1

    def st_If(self, s: A.If) -> None:
        for i, (cond, body) in enumerate(s.branches):
            kw = "if" if i == 0 else "} else if"
            if i:
                self.line_at(cond.pos)      # the ELSIF's test is its line's code, not the arm's before
            self.emit(f"{kw} ({self.cond(cond)}) {{")
            self.nested(body)
        if s.else_body is not None:
            self.emit("} else {")
            self.nested(s.else_body)
        self.emit("}")

    def cond(self, e: A.Node) -> str:
        c = self.expr(e)
        if c.startswith("(") and not c.startswith("({") and c.endswith(")") and _balanced(c[1:-1]):
            return c[1:-1]
        return c

    def st_Case(self, s: A.Case) -> None:
        sel_t = s.selector.ty.base()
        unsigned64 = isinstance(sel_t, T.Elem) and sel_t.kind == "uint" and sel_t.bits == 64
        sel_c = f"(unsigned long long)({self.expr(s.selector)})" if unsigned64 else f"(long long)({self.expr(s.selector)})"
        groups = []
        for labels, body in s.elements:
            rngs = []
            for lab in labels:
                lo = self.case_value(lab.lo, sel_t)
                hi = self.case_value(lab.hi, sel_t) if lab.hi is not None else lo
                rngs.append((lo, hi))
            groups.append((rngs, body))
        flat = sorted(r for g in groups for r in g[0])
        overlap = any(b[0] <= a[1] for a, b in zip(flat, flat[1:]))
        tmp = self.new_tmp()
        ctype = "unsigned long long" if unsigned64 else "long long"
        if overlap:
            # first matching label wins, as in MatIEC's if-chain
            self.emit(f"{{ {ctype} {tmp} = {sel_c};")
            first = True
            for rngs, body in groups:
                conds = " || ".join(
                    f"{tmp} == {self.case_lit(lo, unsigned64)}" if lo == hi else
                    f"({tmp} >= {self.case_lit(lo, unsigned64)} && {tmp} <= {self.case_lit(hi, unsigned64)})"
                    for lo, hi in rngs if not (unsigned64 and hi < 0)) or "0"
                self.line_at(s.pos)         # each label test is the CASE line's code
                self.emit(f"{'if' if first else '} else if'} ({conds}) {{")
                first = False
                self.nested(body)
            if s.else_body is not None:
                self.emit("} else {")
                self.nested(s.else_body)
            self.emit("} }")
            return
        self.emit(f"switch ({sel_c}) {{")
        for rngs, body in groups:
            labs = []
            for lo, hi in rngs:
                if unsigned64:
                    if hi < 0:
                        continue
                    lo = max(lo, 0)
                labs.append(f"case {self.case_lit(lo, unsigned64)}:" if lo == hi else
                            f"case {self.case_lit(lo, unsigned64)} ... {self.case_lit(hi, unsigned64)}:")
            if not labs:
                continue
            self.emit(" ".join(labs) + " {")
            self.indent += 1
            self.statements(body)
            self.emit("break;")
            self.indent -= 1
            self.emit("}")
        self.line_at(s.pos)                 # no ELSE: its jump out is the CASE line's code
        self.emit("default: {")
        self.indent += 1
        if s.else_body is not None:
            self.statements(s.else_body)
        self.emit("break;")
        self.indent -= 1
        self.emit("}")
        self.emit("}")

    @staticmethod
    def case_lit(v: int, unsigned64: bool) -> str:
        if unsigned64:
            return f"{v}ULL"
        if v == -(1 << 63):
            return "(-9223372036854775807LL - 1)"
        return f"{v}LL"

    def case_value(self, e: A.Node, sel_t: T.Type) -> int:
        if isinstance(sel_t, T.Enum):
            name = e.value if isinstance(e, A.EnumLit) else e.name
            return sel_t.values.index(name.upper())
        return e.value

    def new_label(self) -> str:
        self.label += 1
        return str(self.label)

    def st_For(self, s: A.For) -> None:
        # a step of 0 counts as downward, as in MatIEC's C (`by > 0 ? up : down`): the loop runs while the
        # control variable is >= the end, i.e. never or until an EXIT
        n = self.new_label()
        t = s.var.ty.base()
        wide = "__int128" if t.bits == 64 else "long long"
        cvar, flags = self.place(s.var)
        self.store(cvar, flags, t, self.expr(s.start))
        step = self.expr(s.step) if s.step is not None else "1"
        self.emit(f"{{ {wide} __e{n} = ({wide})({self.expr(s.end)}), __b{n} = ({wide})({step});")
        self.indent += 1
        self.emit(f"if (__b{n} > 0 ? ({wide}){cvar} <= __e{n} : ({wide}){cvar} >= __e{n}) for (;;) {{")
        self.indent += 1
        self.loops.append((f"__exit{n}", f"__cont{n}"))
        self.statements(s.body)
        self.loops.pop()
        self.emit(f"__cont{n}: ;")
        self.line_at(s.pos)                 # the step and the end test are the FOR line's code
        self.emit(f"__e{n} = ({wide})({self.expr(s.end)}); __b{n} = ({wide})({step});")
        self.emit(f"{{ {wide} __n{n} = ({wide}){cvar} + __b{n};")
        self.indent += 1
        self.store(cvar, flags, t, f"({cname_of(t)})__n{n}")
        self.emit(f"if (__b{n} > 0 ? __n{n} > __e{n} : __n{n} < __e{n}) break; }}")
        self.indent -= 1
        self.indent -= 1
        self.emit("}")
        self.indent -= 1
        self.emit("}")
        self.emit(f"__exit{n}: ;")

    def st_While(self, s: A.While) -> None:
        n = self.new_label()
        self.emit(f"while ({self.cond(s.cond)}) {{")
        self.nested(s.body, loop=n)
        self.emit("}")
        self.emit(f"__exit{n}: ;")

    def st_Repeat(self, s: A.Repeat) -> None:
        n = self.new_label()
        self.emit("do {")
        self.nested(s.body, loop=n)
        self.line_at(s.cond.pos)            # the UNTIL test is its line's code
        self.emit(f"}} while (!({self.cond(s.cond)}));")
        self.emit(f"__exit{n}: ;")

    def st_Exit(self, s: A.Exit) -> None:
        self.emit(f"goto {self.loops[-1][0]};")

    def st_Continue(self, s: A.Continue) -> None:
        self.emit(f"goto {self.loops[-1][1]};")

    def st_Return(self, s: A.Return) -> None:
        self.emit("goto __end;")

    # ------------------------------------------------------------------ expressions
    def expr(self, e: A.Node) -> str:
        return getattr(self, "ex_" + type(e).__name__)(e)

    def read(self, place: str, t: T.Type) -> str:
        return f"__T2NS({place})" if is_time(t) else place

    def ex_Name(self, e: A.Name) -> str:
        sym = e.sym
        if sym == "__CURRENT_TIME":
            return "__T2NS(__CURRENT_TIME)"
        if isinstance(sym, tuple):
            return str(sym[1].values.index(e.name.upper()))
        p, _ = self.place(e)
        return self.read(p, e.ty)

    ex_Member = ex_Index = lambda self, e: self.read(self.place(e)[0], e.ty)

    def ex_EnumLit(self, e: A.EnumLit) -> str:
        return str(e.ty.base().values.index(e.value.upper()))

    def ex_Literal(self, e: A.Literal) -> str:
        t = e.ty.base() if not isinstance(e.ty, T.Pseudo) else e.ty.default
        if e.kind == "bool":
            return "1" if e.value else "0"
        if e.kind == "int":
            if t.kind == "real":
                return c_real(float(e.value))
            return f"(({t.cname}){c_int(e.value, t)})" if t.bits < 32 and e.value < 0 else c_int(e.value, t)
        if e.kind == "real":
            return c_real(e.value)
        if e.kind == "string":
            return f"((STRING){{{len(e.value)}, {c_string(e.value)}}})"
        if e.kind in ("time", "date", "tod", "dt"):
            return f"((__ns_t){e.value}LL)"
        raise AssertionError(e.kind)

    def ex_UnOp(self, e: A.UnOp) -> str:
        a = self.expr(e.operand)
        t = e.ty.base()
        if e.op == "NOT":
            if t is T.BOOL:
                return f"(!{a})"
            return f"(({t.cname})~{a})"
        if is_time(t):
            return f"(-{a})"
        if t.kind == "real":
            return f"(-{a})"
        u = "unsigned long long" if t.bits == 64 else "unsigned"
        return f"(({t.cname})(0 - ({u}){a}))"

    def ex_BinOp(self, e: A.BinOp) -> str:
        # a left-associative chain (a sum of 16,000 terms) is walked iteratively: its left operands nest
        # without bound. gcc's parser recurses on each nested parenthesis and crashes beyond some thousands,
        # so every CHAIN_CHUNK operators the partial result goes into a temporary of exactly its C type
        # (__auto_type): each operator keeps its own C (its wrap to the node's type, its fault site), and
        # the operands are still evaluated left to right.
        spine = [e]
        while isinstance(spine[-1].left, A.BinOp):
            spine.append(spine[-1].left)
        acc = self.expr(spine[-1].left)
        steps = []
        for i, node in enumerate(reversed(spine), 1):
            acc = self.binop(node, acc)
            if i % CHAIN_CHUNK == 0 and i < len(spine):
                tmp = self.new_tmp()
                steps.append(f"__auto_type {tmp} = {acc};")
                acc = tmp
        return "({ " + " ".join(steps) + f" {acc}; }})" if steps else acc

    def binop(self, e: A.BinOp, a: str) -> str:
        """C of `e`, its left operand's C being `a`."""
        op = e.op
        if getattr(e, "time", False):
            return self.time_binop(e, a)
        b = self.expr(e.right)
        if op in ("=", "<>", "<", ">", "<=", ">="):
            cop = {"=": "==", "<>": "!="}.get(op, op)
            lt = e.left.ty.base()
            if isinstance(lt, T.Elem) and lt.kind == "string":
                return f"(__STRCMP({a}, {b}) {cop} 0)"
            return f"({a} {cop} {b})"
        t = e.ty.base()
        if op == "**":
            rt = cname_of(t)
            return f"(({rt})__builtin_pow((double)({a}), (double)({b})))"
        if op in ("AND", "OR", "XOR"):
            if t is T.BOOL:
                return f"({a} {'&&' if op == 'AND' else '||' if op == 'OR' else '^'} {b})"
            cop = {"AND": "&", "OR": "|", "XOR": "^"}[op]
            return f"(({t.cname})({a} {cop} {b}))"
        if t.kind == "real":
            return f"({a} {op if op != 'MOD' else '%'} {b})"
        if op == "/":
            return f"__div_{t.cname}({a}, {b}, {self.site(e.pos).args()})"
        if op == "MOD":
            return f"__mod_{t.cname}({a}, {b})"
        u = "unsigned long long" if t.bits == 64 else "unsigned"
        return f"(({t.cname})(({u}){a} {op} ({u}){b}))"

    def time_binop(self, e: A.BinOp, a: str) -> str:
        b = self.expr(e.right)
        op = e.op
        if op in ("+", "-"):
            return f"({a} {op} {b})"
        k = f"(double)({b})"
        if op == "*":       # by an integer too: MatIEC's C multiplies in double (__time_mul) either way
            return f"__time_mul({a}, {k}, {self.site(e.pos).args()})"
        return f"__time_div({a}, {k}, {self.site(e.pos).args()})"

    # ------------------------------------------------------------------ calls
    def ex_Call(self, e: A.Call) -> str:
        if isinstance(e.target, SF.StdCall):
            return SF.c_call(self, e, e.target)      # stdfuncs/: its table and C
        pou, _, bound = e.target
        by_param = {p.key: a for p, a in bound}
        args, pre, post = [], [], []
        en_arg, eno_arg = by_param.get("EN"), by_param.get("ENO")
        en = None
        if en_arg is not None:
            # MatIEC evaluates every argument, then skips the body when EN is FALSE
            en = self.new_tmp()
            pre.append(f"BOOL {en} = {self.expr(en_arg.value)};")
        eno = None
        if eno_arg is not None:
            eno = self.new_tmp()
            pre.append(f"BOOL {eno} = 1;")
        args.append(f"&{eno}" if eno else "0")
        # VAR_IN_OUT is passed by reference, which means the same as MatIEC's copy-in/copy-out unless two
        # in-out arguments overlap (then: copies) or the actual is forced (then: a throw-away copy)
        roots = [_root(a.value) for p, a in bound if p.kind == "VAR_IN_OUT"]
        by_ref = len({id(r) for r in roots}) == len(roots)
        for p in pou.params:
            a = by_param.get(p.key)
            if p.kind == "VAR_INPUT":
                if a is None:
                    val = self.value_of(p.init, p.ty) if p.init is not None else self.default_value(p.ty)
                    args.append(self.c_value_expr(p.ty, val))
                else:
                    v = self.expr(a.value)
                    v = f"__ns2t({v})" if is_time(p.ty) else v
                    if en is not None:
                        tmp = self.new_tmp()
                        pre.append(f"{cname_of(p.ty)} {tmp} = {v};")
                        v = tmp
                    args.append(v)
            elif p.kind == "VAR_IN_OUT" and a is not None and by_ref:
                src, flags = self.place(a.value)
                if flags is None:
                    args.append(f"&{src}")
                else:
                    ptr, tmp = self.new_tmp(), self.new_tmp()
                    ct = cname_of(p.ty)
                    pre.append(f"{ct} *{ptr} = &{src}, {tmp};")
                    pre.append(f"if (__builtin_expect({flags} & {FORCE}, 0)) {{ {tmp} = *{ptr}; {ptr} = &{tmp}; }}")
                    args.append(ptr)
            elif p.kind == "VAR_IN_OUT":
                tmp = self.new_tmp()
                if a is None:
                    val = self.default_value(p.ty)
                    pre.append(f"{cname_of(p.ty)} {tmp} = {self.c_value_expr(p.ty, val)};")
                else:
                    src, flags = self.place(a.value)
                    pre.append(f"{cname_of(p.ty)} {tmp} = {src};")
                    post.append(f"if (!({flags} & {FORCE})) {src} = {tmp};" if flags else f"{src} = {tmp};")
                args.append(f"&{tmp}")
            else:
                if a is None:
                    args.append("0")
                else:
                    tmp = self.new_tmp()
                    pre.append(f"{cname_of(p.ty)} {tmp};")
                    args.append(f"&{tmp}")
                    tp, tflags = self.place(a.value)
                    post.append(f"if (!({tflags} & {FORCE})) {tp} = {tmp};" if tflags else f"{tp} = {tmp};")
        call = f"{pou.key}({', '.join(args)})"
        if eno_arg is not None:
            tp, tflags = self.place(eno_arg.value)
            store = f"if (!({tflags} & {FORCE})) {tp} = {eno};" if tflags else f"{tp} = {eno};"
        if en is not None:
            r = self.new_tmp()
            rt = cname_of(pou.return_type)
            default = self.c_value_expr(pou.return_type, self.default_value(pou.return_type))
            text = "({ " + " ".join(pre) + f" {rt} {r}; if ({en}) {{ {r} = {call}; " + " ".join(post) + \
                f" }} else {{ {r} = {default};{f' {eno} = 0;' if eno else ''} }}" + \
                (f" {store}" if eno_arg is not None else "") + f" {r}; }})"
            return self.read(text, pou.return_type)
        if eno_arg is not None:
            post.append(store)
        if pre or post:
            r = self.new_tmp()
            call = "({ " + " ".join(pre) + f" {cname_of(pou.return_type)} {r} = {call}; " + " ".join(post) + f" {r}; }})"
        return self.read(call, pou.return_type)

    # ------------------------------------------------------------------ configuration
    def config_code(self) -> list[str]:
        cfg = self.prog.config
        lines = ["/* ---- configuration */"]
        intervals = [t.interval_ns for r in (cfg.resources if cfg else []) for t in r.tasks if t.interval_ns]
        tick = 0
        for i in intervals:
            tick = math.gcd(tick, i)
        self.tick_ns = tick or 1_000_000
        lines.append(f"unsigned long long common_ticktime__ = {self.tick_ns}ULL; /* ns */")
        lines.append("unsigned long greatest_tick_count__ = 0UL;")
        lines.append("void config_init__(void)")
        lines.append("{")
        self.pou = None
        if cfg is not None:
            for cname, _, v, r in self.global_vars():
                lines.extend(self.init_global(cname, v, cfg.resources.index(r) if r is not None else 0))
            for ri, r in enumerate(cfg.resources):
                for inst in r.programs:
                    lines.append(f"  {inst.pou.key}_init__(&{r.key}__{inst.key}, {ri});")
        lines.append("}")
        lines.append("")
        lines.append("void config_run__(unsigned long tick)")
        lines.append("{")
        if cfg is not None:
            for r in cfg.resources:
                flags = {}
                for t in r.tasks:
                    if t.interval_ns:
                        flags[t.key] = f"__task_{r.key}_{t.key}"
                        lines.append(f"  int {flags[t.key]} = !(tick % {t.interval_ns // self.tick_ns}UL);")
                for inst in r.programs:
                    call = f"{inst.pou.key}_body__(&{r.key}__{inst.key});"
                    if inst.task is not None and inst.task.key in flags:
                        lines.append(f"  if ({flags[inst.task.key]}) {call}")
                    elif inst.task is not None:
                        lines.append(f"  /* {inst.name}: task {inst.task.name} has no INTERVAL */")
                    else:
                        lines.append(f"  {call}")
        lines.append("  (void)tick;")
        lines.append("}")
        lines.append("")
        return lines

    def init_global(self, cname: str, v: Var, res_index: int = 0) -> list[str]:
        if v.is_fb_instance:
            lines = [f"  {v.ty.pou.key}_init__(&{cname}, {res_index});"]
            if isinstance(v.init, A.StructInit):
                for k, node in self.value_of(v.init, v.ty).items():
                    mv = v.ty.pou.vars[k]
                    lines.append(f"  {cname}.{k}.value = {self.c_value_expr(mv.ty, self.value_of(node, mv.ty))};")
            return lines
        val = self.value_of(v.init, v.ty) if v.init is not None else self.default_value(v.ty)
        lines = [f"  {cname}.flags = 0;"]
        if v.location:
            cell = self.prog.located[v.location]
            lines.append(f"  {cname}.value = &{cell.cname};")
            lines.append(self.assign_value(cell.cname, v.ty, val))
        else:
            lines.append(self.assign_value(f"{cname}.value", v.ty, val))
        return lines

    # ------------------------------------------------------------------ manifest and tables
    def type_ref(self, t: T.Type, types: dict) -> str:
        if isinstance(t, (T.Alias, T.Subrange)):
            return self.type_ref(t.base(), types)
        if isinstance(t, T.Elem):
            return t.name
        name = t.cname
        if name not in types:
            if isinstance(t, T.Enum):
                types[name] = {"kind": "enum", "values": list(t.values)}
            elif isinstance(t, T.Array):
                types[name] = None
                types[name] = {"kind": "array", "elem": self.type_ref(t.elem, types), "dims": [list(d) for d in t.dims]}
            elif isinstance(t, T.Struct):
                types[name] = None
                types[name] = {"kind": "struct", "fields": [{"name": f.key, "type": self.type_ref(f.ty, types)}
                                                            for f in t.fields]}
            elif isinstance(t, T.PouType):
                types[name] = None
                types[name] = {"kind": "fb" if t.pou.kind == "FUNCTION_BLOCK" else "program",
                               "fields": [{"name": v.key, "type": self.member_ref(v, types)} for v in t.pou.layout()]}
        return name

    def member_ref(self, v: Var, types: dict) -> str:
        inner = self.type_ref(v.ty, types)
        if v.is_fb_instance:
            return "ref:" + inner if v.kind == "VAR_EXTERNAL" else inner
        if v.kind == "VAR_EXTERNAL" or v.location or self.is_ref(v):
            return "ptr:" + inner
        return "var:" + inner

    def ctype_of_ref(self, ref: str) -> str:
        if ref.startswith("var:"):
            return "__V_" + self.ctype_of_ref(ref[4:])
        if ref.startswith("ptr:"):
            return "__P_" + self.ctype_of_ref(ref[4:])
        return ref

    def tables_and_manifest(self) -> tuple[list[str], dict]:
        types: dict = {}
        roots: list[tuple[str, str, str]] = []     # (path, type ref, C address expression)
        cfg = self.prog.config
        for p in self.prog.pous:
            if p.kind != "FUNCTION" and not p.no_code:
                self.type_ref(p.ty, types)
        for t in self.prog.types:
            self.type_ref(t, types)
        for cname, path, v, _ in self.global_vars():
            if v.is_fb_instance:
                ref = self.type_ref(v.ty, types)
            else:
                ref = ("ptr:" if v.location else "var:") + self.type_ref(v.ty, types)
            roots.append((path, ref, f"&{cname}"))
        if cfg is not None:
            for r in cfg.resources:
                for inst in r.programs:
                    roots.append((f"{r.path()}.{inst.key}", self.type_ref(inst.pou.ty, types),
                                  f"&{r.key}__{inst.key}"))
        for cell in self.prog.located.values():
            roots.append((cell.location, self.type_ref(cell.ty, types), f"&{cell.cname}"))
        size_checks: list[str] = []
        seen = set()

        def add_check(ref: str):
            if ref not in seen and not ref.startswith("ref:"):
                seen.add(ref)
                size_checks.append(ref)

        for name in types:
            add_check(name)
        for _, ref, _ in roots:
            add_check(ref)
        for spec in types.values():
            for f in spec.get("fields", []):
                add_check(f["type"])
            if spec["kind"] == "array":
                add_check(spec["elem"])
        # wrappers of the elementary types only exist in C if used; make sure each checked one is declared
        for ref in size_checks:
            base = ref.split(":", 1)[1] if ":" in ref else None
            if base is not None:
                c = base
                if c not in self._wrapped_set:
                    self._wrapped_set.add(c)
                    self.wrapped.append(c)
        lines = ["/* ---- tables for the loader (docs/architecture.md 1.1) */",
                 "void *plc_root_addr(int i)", "{", "  switch (i) {"]
        for i, (_, _, addr) in enumerate(roots):
            lines.append(f"  case {i}: return (void *){addr};")
        lines += ["  default: return 0;", "  }", "}", "",
                  "unsigned long plc_type_size(int i)", "{", "  switch (i) {"]
        for i, ref in enumerate(size_checks):
            lines.append(f"  case {i}: return sizeof({self.ctype_of_ref(ref)});")
        lines += ["  default: return 0;", "  }", "}", ""]
        pous = {}
        for p in self.prog.pous:
            if not p.std and not p.no_code:
                pous[p.key] = {"file": p.pos.file, "line": p.pos.line, "kind": p.kind}
        manifest = {
            "schema": 1,
            "backend": "builtin",
            "backend_version": self.version,
            "tick_ns": self.tick_ns,
            "types": types,
            "roots": [{"path": path, "type": ref} for path, ref, _ in roots],
            "size_checks": size_checks,
            "pous": pous,
        }
        return lines, manifest


def _root(e: A.Node):
    """The variable an lvalue expression belongs to."""
    while isinstance(e, (A.Member, A.Index)):
        e = e.base
    return e.sym


def _balanced(s: str) -> bool:
    depth = 0
    for c in s:
        if c == "(":
            depth += 1
        elif c == ")":
            depth -= 1
            if depth < 0:
                return False
    return depth == 0
