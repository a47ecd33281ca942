"""Semantic checks and typing: accepts exactly what the builtin backend compiles, rejects the rest.

The rules are MatIEC's (docs/builtin-compiler.md lists them): strict typing with no implicit
conversion, untyped literals that take the type of their context (and must fit it), ANY_BIT types
without arithmetic, array types compared by name, declaration before use, no recursion. Constructs
outside the subset are rejected with a message that says so. Errors are collected, one per
statement or declaration at most, and raised together as a BuiltinCompileError.

The checker annotates the AST in place (`Expr.ty`, `Name.sym`, `Call.target`) for codegen.py.
"""

from __future__ import annotations

import functools
import json
import re
from pathlib import Path

from . import ast as A
from . import constfold, matiec_c_macros, nesting, stdfb
from . import stdfuncs as SF
from . import types as T
from .errors import BuiltinCompileError, Diagnostic
from .parser import C_PRAGMA, is_c_pragma
from .symbols import ConfigSym, LocatedCell, PouSym, ProgInst, Program, ResourceSym, TaskSym, Var

KEYWORDS = {
    "ACTION", "END_ACTION", "ARRAY", "OF", "AT", "CASE", "ELSE", "END_CASE", "CONFIGURATION", "END_CONFIGURATION",
    "CONSTANT", "EN", "ENO", "EXIT", "FALSE", "F_EDGE", "FOR", "TO", "BY", "DO", "END_FOR", "FUNCTION",
    "END_FUNCTION", "FUNCTION_BLOCK", "END_FUNCTION_BLOCK", "IF", "THEN", "ELSIF", "END_IF", "INITIAL_STEP",
    "END_STEP", "NOT", "MOD", "AND", "XOR", "OR", "PROGRAM", "WITH", "END_PROGRAM", "R_EDGE", "READ_ONLY",
    "READ_WRITE", "REPEAT", "UNTIL", "END_REPEAT", "RESOURCE", "ON", "END_RESOURCE", "RETAIN", "NON_RETAIN",
    "RETURN", "STEP", "STRUCT", "END_STRUCT", "TASK", "TRANSITION", "FROM", "END_TRANSITION", "TRUE", "TYPE",
    "END_TYPE", "VAR", "END_VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP", "VAR_EXTERNAL",
    "VAR_ACCESS", "VAR_CONFIG", "VAR_GLOBAL", "WHILE", "END_WHILE", "CONTINUE", "REF_TO", "TIME_OF_DAY",
    "DATE_AND_TIME", "EXTENDS", "IMPLEMENTS", "METHOD", "END_METHOD", "INTERFACE", "END_INTERFACE", "THIS",
    "SUPER", "POINTER", "REFERENCE", "NULL",
}
# parameters MatIEC accepts as identifiers although they look reserved
NOT_RESERVED = {"Q", "IN", "PT", "PRIORITY", "INTERVAL", "SINGLE"}
# words the builtin knows only to explain them (types and object-oriented constructs outside the subset)
# that iec2c, with the build's flags (no -r), reads as ordinary identifiers: it builds them as the name of
# a variable, field, POU, type, enumerated value, task, resource or instance (tests/test_builtin_matiec_names.py)
MATIEC_IDENTIFIERS = {
    "CHAR", "WCHAR", "LTIME", "LDATE", "LTOD", "LDT", "LTIME_OF_DAY", "LDATE_AND_TIME",
    "METHOD", "END_METHOD", "INTERFACE", "END_INTERFACE", "EXTENDS", "IMPLEMENTS", "THIS", "SUPER",
    "POINTER", "REFERENCE", "REF_TO",
}
# functions outside the subset that people reach for: a clear message instead of "unknown function"
UNSUPPORTED_FUNCTIONS = {
    "SIZEOF": "SIZEOF", "ADR": "ADR", "REF": "REF()", "LOWER_BOUND": "LOWER_BOUND", "UPPER_BOUND": "UPPER_BOUND",
    "MEMCPY": "MEMCPY", "ASC": "ASC", "CHR": "CHR", "LEN_WSTRING": "WSTRING functions", "NEW": "__NEW",
}


@functools.lru_cache(maxsize=1)
def matiec_library_names() -> frozenset[str]:
    """Identifiers of MatIEC's standard library that cannot name a POU, a type or the configuration
    (matiec_lib_names.json says why)."""
    data = json.loads((Path(__file__).with_name("matiec_lib_names.json")).read_text())
    return frozenset(data["names"])


# what iec2c writes into its C under the ST name itself (enumerated values, program instances, resources, the
# configuration and its globals get a prefix there): these cannot take a C macro's name. A global's VAR_EXTERNAL
# is a variable, so only a global that no POU uses can be named so
C_NAMED = {"variable", "field", "type", "function", "function block", "program", "task"}

# MatIEC's library declares these blocks beyond IEC's (stdfb.NON_STANDARD), and iec2c knows their names before
# it reads the user's code: as a user's identifier each is a syntax error (or an internal error of iec2c)
NON_STANDARD_NAME = ("'{name}' cannot name {what}: it is the name of a function block of MatIEC's own library "
                     "(not an IEC standard block, and not provided by the builtin compiler), which iec2c refuses "
                     "as an identifier; choose another name")

FLT_MAX, FLT_MIN = 3.4028234663852886e38, 1.1754943508222875e-38


def outside_float_range(text: str) -> bool:
    """Whether MatIEC rejects this real literal: it reads every real literal with C's strtof (a defect:
    its test of which strtoX to use is always true), whatever the type, and refuses one that sets ERANGE,
    i.e. beyond +-3.4E38 or, non-zero, below 1.18E-38 in magnitude: so even `LREAL#1.0E300`."""
    fn = _strtof()
    if fn is not None:
        import ctypes
        ctypes.set_errno(0)
        fn(text.replace("_", "").encode("ascii", "replace"), None)
        return ctypes.get_errno() != 0
    v = abs(float(text.replace("_", "")))     # without a C library: the same bounds, to a rounding
    return v > FLT_MAX or 0 < v < FLT_MIN


@functools.lru_cache(maxsize=1)
def _strtof():
    try:
        import ctypes
        fn = ctypes.CDLL(None, use_errno=True).strtof
    except (OSError, AttributeError):
        return None
    fn.restype, fn.argtypes = ctypes.c_float, [ctypes.c_char_p, ctypes.c_void_p]
    return fn


# MatIEC's pragmas that turn the generation of C off and on for the POUs between them (types are still
# generated): matched as its lexer does, case-insensitively and exactly as spelled
DISABLE_CODE = re.compile(r"(?i)\{disable code generation\}")
ENABLE_CODE = re.compile(r"(?i)\{enable code generation\}")

LOCATION_RE = re.compile(r"%([IQM])([XBWDL]?)(\d+(?:\.\d+)*)$")
SIZE_BITS = {"X": 1, "B": 8, "W": 16, "D": 32, "L": 64}


class _Abort(Exception):
    """Stops checking the current statement or declaration after an error was recorded."""


class Checker:
    def __init__(self) -> None:
        self.diags: list[Diagnostic] = []
        self.types: dict[str, T.Type] = {}
        self.type_order: list[T.Type] = []
        self.pous: dict[str, PouSym] = {}
        self.enum_index: dict[str, list[T.Enum]] = {}
        self.config: ConfigSym | None = None
        self.located: dict[str, LocatedCell] = {}
        self.cur: PouSym | None = None
        self.loops = 0
        self.for_vars: list[Var] = []       # control variables of the FOR loops around the statement
        self.anon = 0
        self._std_ast: dict[str, A.Pou] | None = None
        self.folder = constfold.Folder()
        self._std_mode = False
        self.config_names: set[str] = set()
        self.externals_reported: set[Var] = set()   # VAR_EXTERNALs already reported as without a global
        self.failed_tasks: set[str] = set()  # tasks whose declaration was rejected: uses are not reported
        self.failed_pous: set[str] = set()   # POUs whose declaration was rejected: uses are not reported
        self.code_generation = True          # off between {disable code generation} and {enable ...}

    # ------------------------------------------------------------------ diagnostics
    def error(self, pos: A.Pos, msg: str):
        self.report(pos, msg)
        raise _Abort

    def report(self, pos: A.Pos, msg: str) -> None:
        d = Diagnostic(pos.file, pos.line, pos.col, msg)
        if d not in self.diags:
            self.diags.append(d)

    # ------------------------------------------------------------------ entry
    def check(self, elements: list[A.Node], files: list[str]) -> Program:
        # iec2c -p reads the configuration's name before the POUs: no other identifier may take it
        self.config_names = {el.name.upper() for el in elements if isinstance(el, A.Configuration)}
        for el in elements:
            try:
                if isinstance(el, A.TypeBlock):
                    for decl in el.decls:
                        try:
                            self.declare_type(decl)
                        except _Abort:
                            self.types.setdefault(decl.name.upper(), T.ERROR)
                elif isinstance(el, A.Pou):
                    self.declare_pou(el)
                elif isinstance(el, A.Configuration):
                    self.declare_config(el)
                elif isinstance(el, A.Pragma) and DISABLE_CODE.fullmatch(el.text):
                    self.code_generation = False
                elif isinstance(el, A.Pragma) and ENABLE_CODE.fullmatch(el.text):
                    self.code_generation = True
                elif isinstance(el, A.Pragma) and is_c_pragma(el.text):
                    self.error(el.pos, C_PRAGMA)
                elif isinstance(el, A.Pragma):
                    self.error(el.pos, f"pragma {el.text!r} is outside the supported subset (only "
                                       "{#include \"file\"}, {disable code generation} and {enable code generation} "
                                       "are supported)")
            except _Abort:
                pass
        if self.config is not None or not self.config_names:    # (a rejected CONFIGURATION declares nothing)
            self.check_externals_declared()
        if self.diags:
            raise BuiltinCompileError(self.diags)
        return Program(self.type_order, list(self.pous.values()), self.config, self.located, files)

    # ------------------------------------------------------------------ names
    def check_identifier(self, name: str, pos: A.Pos, what: str) -> str:
        k = name.upper()
        if "__" in name and not self._std_mode:
            self.error(pos, f"identifier '{name}' contains a double underscore, which MatIEC rejects")
        if k in NOT_RESERVED:
            return k
        reserved = k in KEYWORDS or k in T.ELEMENTARY or k in T.ELEMENTARY_ALIASES or k in T.UNSUPPORTED_ELEMENTARY
        if reserved and k not in MATIEC_IDENTIFIERS:
            self.error(pos, f"'{name}' is a reserved word and cannot name a {what}")
        if (SF.is_std_function(k) or k in SF.MISSING_IN_MATIEC_C) and not (what == "function" and k in SF.USER_NAMEABLE):
            self.error(pos, f"'{name}' is the name of a standard function and cannot name a {what}")
        if k in stdfb.NON_STANDARD and what != "field" and not self._std_mode:
            self.error(pos, NON_STANDARD_NAME.format(name=name, what=_a(what)))
        if k in stdfb.names() and what != "field" and not self._std_mode:
            self.error(pos, f"'{name}' is the name of a standard function block and cannot name {_a(what)} (MatIEC "
                            "refuses it: iec2c reads the name as the block's)")
        if k in matiec_c_macros.names() and what in C_NAMED and not self._std_mode:
            self.error(pos, f"'{name}' cannot name {_a(what)}: it is a C macro of the headers MatIEC's generated C "
                            f"includes, and iec2c writes the name into that C as it is ({k}), where the preprocessor "
                            "replaces it and the C does not compile; choose another name")
        if k in self.config_names and what != "configuration" and not self._std_mode:
            self.error(pos, f"'{name}' is the name of the CONFIGURATION and cannot name a {what} (MatIEC rejects "
                            "it: with -p, iec2c knows the configuration's name before it reads the POUs)")
        return k

    def check_global_name(self, name: str, pos: A.Pos, what: str) -> str:
        k = self.check_identifier(name, pos, what)
        if k in matiec_library_names() and not self._std_mode:
            self.error(pos, f"'{name}' cannot name a {what}: it is a variable name in MatIEC's standard library, "
                            "and iec2c -p (which the build uses, as Beremiz does) then fails to parse that library "
                            "('standard_functions.txt: invalid input variable(s) declaration'); choose a longer name")
        if k in self.types:
            self.error(pos, f"'{name}' is already declared as a type")
        if k in self.pous:
            self.error(pos, f"'{name}' is already declared as a {self.pous[k].kind}")
        return k

    # ------------------------------------------------------------------ types
    def declare_type(self, decl: A.TypeDecl) -> None:
        k = self.check_global_name(decl.name, decl.pos, "type")
        spec = decl.spec
        if isinstance(spec, A.NamedSpec):
            target = self.resolve_named(spec)
            if isinstance(target, T.PouType):
                self.error(spec.pos, "a type cannot be an alias of a function block")
            if T.is_elementary(target) or isinstance(target, T.Enum):
                ty: T.Type = T.Alias(k, target, decl.init)
                if decl.init is not None:
                    self.const_value(decl.init, target)
            else:
                if decl.init is not None:
                    self.error(decl.init.pos, "an initial value is allowed on an alias of an elementary type only")
                ty = target
        elif isinstance(spec, A.ArraySpec):
            ty = self.array_type(spec, k)
            if decl.init is not None:
                ty.init = decl.init              # type: ignore[attr-defined]
                self.const_value(decl.init, ty)
        elif isinstance(spec, A.StructSpec):
            ty = self.struct_type(spec, k)
            if decl.init is not None:
                self.error(decl.init.pos, "initialise the fields of a STRUCT type in its declaration")
        elif isinstance(spec, A.EnumSpec):
            ty = self.enum_type(spec, k)
            if decl.init is not None:
                ty.init = self.enum_value_of(decl.init, ty)      # type: ignore[attr-defined]
        elif isinstance(spec, A.SubrangeSpec):
            ty = self.subrange_type(spec, k)
            if decl.init is not None:
                ty.init = decl.init                # type: ignore[attr-defined]
                self.const_value(decl.init, ty)
        else:
            ty = self.resolve_spec(spec, k)
        self.types[k] = ty
        if ty not in self.type_order and not isinstance(ty, (T.Elem, T.Alias, T.Subrange)):
            self.type_order.append(ty)

    def resolve_named(self, spec: A.NamedSpec) -> T.Type:
        k = spec.name.upper()
        if k in T.ELEMENTARY:
            return T.ELEMENTARY[k]
        if k in T.ELEMENTARY_ALIASES:
            return T.ELEMENTARY_ALIASES[k]
        if k in self.types:
            return self.types[k]
        if k in self.failed_pous:
            raise _Abort     # its declaration was rejected, and reported
        if k in self.pous:
            pou = self.pous[k]
            if pou.kind == "FUNCTION_BLOCK":
                self.check_has_code(pou, spec.pos)
                return pou.ty
            self.error(spec.pos, f"'{spec.name}' is a {pou.kind}, not a type")
        if k in stdfb.names():
            return self.std_fb(k, spec.pos).ty
        if k in stdfb.NON_STANDARD:
            self.error(spec.pos, f"'{spec.name}' is a MatIEC extension block that the builtin compiler does not provide")
        if k in T.UNSUPPORTED_ELEMENTARY:
            self.error(spec.pos, f"type {k} is outside the supported subset")
        self.error(spec.pos, f"unknown type '{spec.name}' (types must be declared before they are used)")

    def resolve_spec(self, spec: A.Node, name: str | None = None) -> T.Type:
        if isinstance(spec, A.NamedSpec):
            return self.resolve_named(spec)
        if isinstance(spec, A.ArraySpec):
            return self.array_type(spec, name)
        if isinstance(spec, A.StructSpec):
            if name is None:
                self.error(spec.pos, "an anonymous STRUCT is outside the supported subset; declare a STRUCT type")
            return self.struct_type(spec, name)
        if isinstance(spec, A.EnumSpec):
            if name is None:
                self.error(spec.pos, "an anonymous enumeration is outside the supported subset; declare a type")
            return self.enum_type(spec, name)
        if isinstance(spec, A.SubrangeSpec):
            return self.subrange_type(spec, name)
        if isinstance(spec, A.StringLenSpec):
            self.error(spec.pos, f"{spec.base.upper()}[{spec.length}]: string length declarations are outside "
                                 "the supported subset (MatIEC); use STRING (126 bytes)")
        if isinstance(spec, A.UnsupportedSpec):
            self.error(spec.pos, f"{spec.what} is outside the supported subset")
        self.error(spec.pos, "unsupported type specification")

    def array_type(self, spec: A.ArraySpec, name: str | None) -> T.Array:
        if spec.star:
            self.error(spec.pos, "ARRAY[*] is outside the supported subset")
        dims = []
        for lo, hi in spec.ranges:
            for b in (lo, hi):
                if isinstance(b, A.Name):
                    self.error(b.pos, "array bounds must be integer literals (MatIEC does not accept constants)")
            if hi < lo:
                self.error(spec.pos, f"empty array range {lo}..{hi}")
            dims.append((lo, hi))
        elem = self.resolve_spec(spec.elem)
        if isinstance(elem, T.Array):
            self.error(spec.elem.pos, "an array of arrays is outside the supported subset; use a multi-dimensional array")
        if isinstance(elem, T.PouType):
            self.error(spec.elem.pos, "arrays of function block instances are outside the supported subset (MatIEC)")
        count = 1
        for lo, hi in dims:
            count *= hi - lo + 1
        if count > 1 << 24:
            self.error(spec.pos, "array too large")
        if name is None:
            self.anon += 1
            cname = f"__ARRAY{self.anon}"
            ty = T.Array(cname, elem, dims, cname, anonymous=True)
            self.type_order.append(ty)
        else:
            ty = T.Array(name, elem, dims, name)
        return ty

    def struct_type(self, spec: A.StructSpec, name: str) -> T.Struct:
        st = T.Struct(name, [], name)
        seen = set()
        for f in spec.fields:
            k = self.check_identifier(f.name, f.pos, "field")
            if k in seen:
                self.error(f.pos, f"duplicate field '{f.name}'")
            seen.add(k)
            fty = self.resolve_spec(f.spec)
            if isinstance(fty, T.PouType):
                self.error(f.spec.pos, "function block instances inside a STRUCT are outside the supported subset")
            if f.init is not None:
                self.const_value(f.init, fty)
            st.fields.append(T.Field(f.name, k, fty, f.init, f.pos))
        return st

    def enum_type(self, spec: A.EnumSpec, name: str) -> T.Enum:
        if spec.explicit:
            self.error(spec.pos, "enumerated values with explicit numbers (A := 1) are outside the supported subset (MatIEC)")
        values, spelled = [], []
        for v, pos in spec.values:
            k = self.check_identifier(v, pos, "enumerated value")
            if k in values:
                self.error(pos, f"duplicate enumerated value '{v}'")
            values.append(k)
            spelled.append(v)
        en = T.Enum(name, values, spelled)
        for v in values:
            self.enum_index.setdefault(v, []).append(en)
        return en

    def subrange_type(self, spec: A.SubrangeSpec, name: str | None) -> T.Subrange:
        base = T.ELEMENTARY.get(spec.base.upper())
        if base is None or not T.is_int(base):
            self.error(spec.pos, f"a subrange needs an integer base type, not '{spec.base}'")
        if spec.lo > spec.hi:
            self.error(spec.pos, f"empty subrange {spec.lo}..{spec.hi}")
        for b in (spec.lo, spec.hi):
            if not T.fits(b, base):
                self.error(spec.pos, f"subrange bound {b} does not fit {base.name}")
        return T.Subrange(name or f"{base.name}({spec.lo}..{spec.hi})", base, spec.lo, spec.hi)

    # ------------------------------------------------------------------ constant initial values
    def const_value(self, init: A.Node, ty: T.Type) -> None:
        """Check an initial value against its type (the value itself is computed by codegen)."""
        tb = ty.base() if not isinstance(ty, T.Subrange) else ty
        if isinstance(init, A.ArrayInit) and init.ints is not None:
            if _bulk_fits(init.ints.values, ty):
                return
            init.items, init.ints = init.entries(), None    # the ordinary checks and messages
        if isinstance(init, A.ArrayInit):
            if not isinstance(ty, T.Array):
                self.error(init.pos, f"an array initialiser for a variable of type {T.describe(ty)}")
            if isinstance(ty.elem.base(), T.Enum):
                self.error(init.pos, "initial values for an array of enumerated values are outside the supported "
                                     "subset (iec2c stops with an internal error)")
            total = 0
            for count, value in init.items:
                if count < 1:
                    self.error(init.pos, "a repetition count must be at least 1")
                total += count
                if isinstance(value, A.StructInit) and isinstance(ty.elem.base(), T.Struct):
                    self.error(value.pos, "STRUCT initialisers as elements of an array initialiser are outside the "
                                          "supported subset (MatIEC rejects them); assign the elements in the body")
                if value is not None:
                    self.const_value(value, ty.elem)
            if total > ty.count:
                self.error(init.pos, f"too many initial values: {total} for {ty.count} elements")
            return
        if isinstance(init, A.StructInit):
            if not isinstance(ty, (T.Struct, T.PouType)):
                self.error(init.pos, f"a structure initialiser for a variable of type {T.describe(ty)}")
            if isinstance(ty, T.Struct):
                dated = _date_field(ty)
                if dated is not None:
                    self.error(init.pos, f"{ty.name} holds a {dated[1].name} ('{dated[0]}'): a STRUCT initialiser of "
                                         "a type with a DATE or DT inside is outside the supported subset (MatIEC's "
                                         "C initialises those with a function call where C needs a constant); give "
                                         "the fields defaults in the STRUCT type, or assign them in the body")
            seen = set()
            for fname, pos, value in init.items:
                k = fname.upper()
                if k in seen:
                    self.error(pos, f"field '{fname}' initialised twice")
                seen.add(k)
                if isinstance(ty, T.Struct):
                    self.struct_field_init(ty, fname, pos, value)
                else:
                    v = ty.pou.vars.get(k)
                    if v is None or v.kind not in ("VAR_INPUT", "VAR_OUTPUT", "VAR") or v.implicit:
                        self.error(pos, f"'{ty.name}' has no variable '{fname}' that can be initialised")
                    self.const_value(value, v.ty)
            return
        if isinstance(ty, (T.Array, T.Struct)):
            self.error(init.pos, f"a variable of type {T.describe(ty)} needs an array or structure initialiser")
        if isinstance(ty, T.PouType):
            self.error(init.pos, "a function block instance is initialised with (name := value, ...)")
        if not isinstance(init, (A.Literal, A.EnumLit, A.Name)):
            self.error(init.pos, "an initial value must be a literal (MatIEC accepts no constant expressions here)")
        if isinstance(init, A.Name):
            if isinstance(tb.base(), T.Enum):
                self.enum_value_of(init, tb.base())
                return
            self.error(init.pos, f"'{init.name}' is not a constant this compiler can use as an initial value")
        saved, self.cur = self.cur, None
        try:
            self.coerce(init, ty, "initial value")
        finally:
            self.cur = saved

    def struct_field_init(self, st: T.Struct, fname: str, pos: A.Pos, value: A.Node) -> None:
        """One `field := value` of a STRUCT initialiser, within what MatIEC checks and compiles right.

        MatIEC (HEAD 2024-10) finds the field an initialiser names as the first field, in declaration
        order, whose upper-case name sorts at or after the given one (its list lookup uses the `<` of its
        name map as if it were `==`), and checks the value against that field's type; its C then
        initialises the right field. So an initialiser is accepted here only where that lookup finds the
        field itself, which is always the case when the fields are declared in alphabetical order."""
        k = fname.upper()
        f = st.field(k)
        if f is None:
            self.error(pos, f"'{T.describe(st)}' has no field '{fname}'")
        found = next((g for g in st.fields if g.key >= k), None)
        if found is not f:
            self.error(pos, f"field '{fname}' of {st.name} cannot be initialised here: MatIEC looks it up as the "
                            f"first field, in declaration order, whose name sorts at or after '{f.key}', which is "
                            f"'{found.name}', and checks the value against that field's type; declare the fields "
                            f"in alphabetical order, or give '{fname}' a default in the STRUCT type, or assign it in "
                            "the body")
        fb = f.ty.base()
        if isinstance(fb, T.Array):
            self.error(pos, f"field '{fname}' is an ARRAY ({T.describe(f.ty)}): array values in a STRUCT initialiser "
                            "are outside the supported subset (MatIEC rejects them); give the field a default in "
                            "the STRUCT type or assign it in the body")
        if isinstance(fb, T.Enum):
            self.error(pos, f"field '{fname}' is an enumeration ({T.describe(f.ty)}): enumerated values in a STRUCT "
                            "initialiser are outside the supported subset (iec2c crashes on them); give the field "
                            "a default in the STRUCT type or assign it in the body")
        self.const_value(value, f.ty)

    def enum_value_of(self, e: A.Node, en: T.Enum) -> int:
        if isinstance(e, A.EnumLit):
            if e.type_name != en.name:
                self.error(e.pos, f"'{e.type_name}#{e.value}' is not a value of {en.name}")
            k = e.value.upper()
        elif isinstance(e, A.Name):
            k = e.name.upper()
        else:
            self.error(e.pos, f"expected a value of {en.name}")
        if k not in en.values:
            self.error(e.pos, f"'{k}' is not a value of {en.name}")
        e.ty = en
        return en.values.index(k)

    # ------------------------------------------------------------------ standard function blocks
    def std_fb(self, key: str, pos: A.Pos) -> PouSym:
        if key in self.pous:
            return self.pous[key]
        if self._std_ast is None:
            from .parser import parse
            self._std_ast = {p.name.upper(): p for p in parse(stdfb.source(), stdfb.SOURCE_NAME)
                             if isinstance(p, A.Pou)}
        saved = (self.cur, self.loops, self._std_mode)
        self._std_mode = True
        try:
            pou = self._std_ast[key]
            pou.std = True
            self.declare_pou(pou)
        finally:
            self.cur, self.loops, self._std_mode = saved
        return self.pous[key]

    # ------------------------------------------------------------------ POUs
    def declare_pou(self, node: A.Pou) -> None:
        try:
            k = self.check_global_name(node.name, node.pos, node.kind.lower().replace("_", " "))
            if not node.blocks and not node.std:
                self.error(node.pos, f"{node.kind} {node.name} declares no variables: MatIEC's grammar needs at "
                                     "least one VAR... END_VAR block in every POU (iec2c refuses it with a syntax "
                                     "error)")
        except _Abort:
            if node.name.upper() not in self.pous:     # a duplicate leaves the first declaration usable
                self.failed_pous.add(node.name.upper())
            raise
        pou = PouSym(node.name, k, node.kind, node.pos, node, std=node.std,
                     no_code=not self.code_generation and not node.std)
        if node.kind != "FUNCTION":
            pou.ty = T.PouType(k, pou)
        saved = self.cur
        self.cur = pou
        try:
            if node.kind == "FUNCTION":
                if node.return_spec is None:
                    self.error(node.pos, f"FUNCTION {node.name} needs a return type (VOID functions are outside the subset)")
                rt = self.resolve_spec(node.return_spec)
                if isinstance(rt, T.PouType):
                    self.error(node.return_spec.pos, "a FUNCTION cannot return a function block")
                if isinstance(rt, T.Array) and rt.anonymous:
                    self.error(node.return_spec.pos, "a FUNCTION must return a named array type")
                pou.return_type = rt
                pou.result = Var(node.name, k, rt, "RESULT", node.pos, pou=pou)
                true = A.Literal(node.pos, "bool", True, None, "TRUE")
                pou.vars["EN"] = Var("EN", "EN", T.BOOL, "VAR_INPUT", node.pos, init=true, pou=pou, implicit=True)
                pou.vars["ENO"] = Var("ENO", "ENO", T.BOOL, "VAR_OUTPUT", node.pos, init=true, pou=pou,
                                      implicit=True)
            else:
                en = Var("EN", "EN", T.BOOL, "VAR_INPUT", node.pos, pou=pou, implicit=True)
                en.init = A.Literal(node.pos, "bool", True, None, "TRUE")
                pou.vars["EN"] = en
                if node.kind == "FUNCTION_BLOCK":
                    eno = Var("ENO", "ENO", T.BOOL, "VAR_OUTPUT", node.pos, pou=pou, implicit=True)
                    eno.init = en.init          # TRUE before the first call, as MatIEC initialises it
                    pou.vars["ENO"] = eno
                else:
                    del pou.vars["EN"]     # programs have no EN/ENO
            for block in node.blocks:
                try:
                    self.declare_block(pou, block)
                except _Abort:
                    pass
            pou.params = [v for v in pou.vars.values()
                          if v.kind in ("VAR_INPUT", "VAR_IN_OUT", "VAR_OUTPUT") and not v.implicit]
        except _Abort:
            self.failed_pous.add(k)
            return
        finally:
            self.cur = saved
        self.pous[k] = pou
        self.check_body(pou)

    def declare_block(self, pou: PouSym, block: A.VarBlock) -> None:
        kind, qual = block.kind, block.qualifier
        allowed = {
            "FUNCTION": {"VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT"},
            "FUNCTION_BLOCK": {"VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP", "VAR_EXTERNAL"},
            "PROGRAM": {"VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP", "VAR_EXTERNAL"},
        }[pou.kind]
        if kind == "VAR_TEMP" and pou.kind == "FUNCTION":
            kind = "VAR"     # declared all the same, so that their uses add no "not declared"
            self.report(block.pos, "VAR_TEMP is not allowed in a FUNCTION: MatIEC refuses it (its grammar has no "
                                  "VAR_TEMP in a FUNCTION, whose VAR variables are temporary anyway); use VAR")
        if kind not in allowed:
            self.error(block.pos, f"{kind} is not allowed in a {pou.kind} (outside the supported subset)")
        if not pou.std:
            self.check_not_empty(block)
        if qual == "CONSTANT" and kind not in ("VAR", "VAR_EXTERNAL"):
            self.error(block.pos, f"{kind} CONSTANT is outside the supported subset")
        if qual == "PERSISTENT":
            self.error(block.pos, "PERSISTENT is outside the supported subset")
        located = [d for d in block.decls if d.location]
        if located and len(located) != len(block.decls):
            self.error(block.pos, "located variables must be declared in a VAR block of their own (MatIEC)")
        for decl in block.decls:
            try:
                self.declare_var(pou, kind, qual, decl)
            except _Abort:
                pass

    def check_not_empty(self, block: A.VarBlock) -> None:
        if not block.decls:
            self.error(block.pos, f"an empty {block.kind} ... END_VAR block: MatIEC refuses a block that declares no "
                                  "variable ('no variable declared'); remove it")

    def declare_var(self, pou: PouSym | None, kind: str, qual: str | None, decl: A.VarDecl,
                    scope=None, table: dict | None = None) -> list[Var]:
        if decl.edge:
            self.error(decl.pos, f"{decl.edge} declarations are outside the supported subset; use R_TRIG/F_TRIG")
        if not decl.names:
            self.error(decl.pos, "a located variable needs a name")
        table = pou.vars if table is None else table
        # one type for the whole declaration: `a, b : ARRAY[..] OF INT` gives a and b the same type
        try:
            ty = self.resolve_spec(decl.spec)
        except _Abort:
            # declared all the same, with the error type, so that their uses add no "not declared"
            self.declare_names(pou, kind, qual, decl, T.ERROR, None, scope, table)
            raise
        if ty is T.ERROR:
            self.declare_names(pou, kind, qual, decl, T.ERROR, None, scope, table)
            return []
        try:
            return self.declare_checked(pou, kind, qual, decl, ty, scope, table)
        except _Abort:
            self.declare_names(pou, kind, qual, decl, ty, None, scope, table)
            raise

    def declare_names(self, pou, kind, qual, decl, ty, init, scope, table) -> None:
        """Declare a rejected declaration's names that are still free (no further diagnostic)."""
        for name, pos in decl.names:
            k = name.upper()
            if k not in table and not (pou is not None and pou.result is not None and k == pou.key):
                table[k] = Var(name, k, ty, kind, pos, constant=(qual == "CONSTANT"), init=init,
                               location=None, pou=pou, scope=scope)

    def declare_checked(self, pou, kind, qual, decl, ty, scope, table) -> list[Var]:
        owner = pou.kind if pou else "resource"
        if isinstance(ty, T.PouType):
            if ty.pou.kind == "PROGRAM":
                self.error(decl.spec.pos, "a PROGRAM cannot be instantiated as a variable")
            if pou is not None and pou.kind == "FUNCTION":
                self.error(decl.spec.pos, "a FUNCTION cannot hold function block instances")
            if decl.location:
                self.error(decl.pos, "a located function block instance is outside the supported subset")
            if kind in ("VAR_OUTPUT", "VAR_TEMP"):
                self.error(decl.spec.pos, f"function block instances in {kind} are outside the supported subset")
            if kind in ("VAR_INPUT", "VAR_IN_OUT"):
                self.error(decl.spec.pos, f"a function block instance as {kind} is outside the supported subset "
                                          "(iec2c crashes on calls that pass one)")
            if qual == "CONSTANT":
                self.error(decl.pos, "a function block instance cannot be CONSTANT")
            if pou is not None and ty.pou is pou:
                self.error(decl.spec.pos, f"{pou.name} cannot contain an instance of itself")
            if len(decl.names) > 2:
                self.error(decl.names[2][1], "declare at most two function block instances in one declaration "
                                             "(iec2c crashes on three or more): write one declaration per instance")
        if decl.location:
            self.check_location(decl.location, ty, decl.pos, owner)
        if pou is not None and pou.kind == "FUNCTION" and kind == "VAR_INPUT" and isinstance(ty, T.Array):
            self.error(decl.spec.pos, "an ARRAY as VAR_INPUT of a FUNCTION is outside the supported subset (MatIEC "
                                      "generates C that does not compile); use VAR_IN_OUT")
        if decl.init is not None:
            if kind in ("VAR_EXTERNAL", "VAR_IN_OUT"):
                self.error(decl.init.pos, f"a {kind} variable cannot have an initial value")
            if kind == "VAR_TEMP":
                self.error(decl.init.pos, "VAR_TEMP variables cannot have an initial value (MatIEC rejects it)")
            self.const_value(decl.init, ty)
        out = []
        for name, pos in decl.names:
            k = self.check_identifier(name, pos, "variable" if pou is not None else "global variable")
            if k in ("EN", "ENO"):
                self.error(pos, f"'{name}' is reserved (implicit parameter of every POU)")
            if k in self.types:
                self.error(pos, f"variable '{name}' has the name of a type (MatIEC rejects this)")
            if k in self.pous:
                self.error(pos, f"variable '{name}' has the name of a POU (MatIEC rejects this)")
            if pou is not None and pou.result is None and k == pou.key:
                self.error(pos, f"variable '{name}' has the name of its own {pou.kind}: MatIEC refuses it (iec2c "
                                "reads the name as the POU's, reports a syntax error, and may then crash)")
            if k in table or (pou is not None and pou.result is not None and k == pou.key):
                self.error(pos, f"duplicate declaration of '{name}'")
            v = Var(name, k, ty, kind, pos, constant=(qual == "CONSTANT"), init=decl.init,
                    location=decl.location, pou=pou, scope=scope)
            table[k] = v
            out.append(v)
            if decl.location:
                self.locate(v)
        return out

    def check_location(self, loc: str, ty: T.Type, pos: A.Pos, owner: str) -> None:
        if owner == "FUNCTION_BLOCK" or owner == "FUNCTION":
            self.error(pos, f"located variables are not allowed in a {owner} (IEC 61131-3)")
        m = LOCATION_RE.match(loc)
        if not m:
            self.error(pos, f"invalid location {loc}")
        size = m.group(2)
        if isinstance(ty, T.Array):
            self.error(pos, "located arrays are outside the supported subset (MatIEC)")
        if isinstance(ty, T.Struct) or isinstance(ty, T.PouType):
            if size:
                self.error(pos, f"a STRUCT can be located only at a location without size (e.g. %I{m.group(3)})")
            return
        tb = ty.base()
        if isinstance(tb, T.Enum):
            bits = 32
        elif isinstance(tb, T.Elem):
            bits = {"bool": 1, "string": 0}.get(tb.kind, tb.bits)
        else:
            bits = 0
        if size and SIZE_BITS[size] != bits and not (size == "B" and bits == 1):
            self.error(pos, f"the size of {loc} does not match the type {T.describe(ty)}")

    def locate(self, v: Var) -> None:
        cell = self.located.get(v.location)
        if cell is not None:
            self.error(v.pos, f"{v.location} is already declared at {cell.pos.file}:{cell.pos.line} "
                              "(MatIEC rejects a second variable at the same address)")
        self.located[v.location] = LocatedCell(v.location, v.ty, v.pos)

    # ------------------------------------------------------------------ configuration
    def declare_config(self, node: A.Configuration) -> None:
        if self.config is not None:
            self.error(node.pos, "only one CONFIGURATION is supported")
        k = self.check_global_name(node.name, node.pos, "configuration")
        cfg = ConfigSym(node.name, k, node.pos)
        for block in node.globals:
            self.declare_globals(block, cfg, cfg.globals)
        if not node.resources:
            self.error(node.pos, "a CONFIGURATION needs at least one RESOURCE, or at least one PROGRAM instance")
        resource_names = {r.name.upper(): r for r in node.resources}
        for g in cfg.globals.values():
            if g.key in resource_names:
                self.report(g.pos, f"global '{g.name}' has the name of resource {resource_names[g.key].name} "
                                   "(MatIEC rejects it)")
        for rnode in node.resources:
            rk = rnode.name.upper() if rnode.implicit else self.check_identifier(rnode.name, rnode.pos, "resource")
            if any(r.key == rk for r in cfg.resources):
                self.error(rnode.pos, f"duplicate resource '{rnode.name}'")
            res = ResourceSym(rnode.name, rk, rnode.pos, config=cfg, implicit=rnode.implicit)
            for block in rnode.globals:
                self.declare_globals(block, res, res.globals)
            for g in res.globals.values():
                if g.key in resource_names:
                    self.report(g.pos, f"global '{g.name}' has the name of resource "
                                       f"{resource_names[g.key].name} (MatIEC rejects it)")
            for tnode in rnode.tasks:
                try:
                    res.tasks.append(self.declare_task(tnode, res))
                except _Abort:
                    self.failed_tasks.add(tnode.name.upper())
            for pnode in rnode.programs:
                try:
                    res.programs.append(self.declare_program_instance(pnode, res))
                except _Abort:
                    pass
            for g in list(res.globals.values()) + list(cfg.globals.values()):
                if g.is_fb_instance:
                    self.check_externals(g.ty.pou, res, g.pos, set())
            cfg.resources.append(res)
        if not any(t.interval_ns for r in cfg.resources for t in r.tasks) and not self.failed_tasks:
            self.report(node.pos, "at least one periodic TASK (with an INTERVAL) is required (MatIEC)")
        self.config = cfg

    def declare_globals(self, block: A.VarBlock, scope, table: dict) -> None:
        if block.kind != "VAR_GLOBAL":
            self.error(block.pos, f"{block.kind} is not allowed here (only VAR_GLOBAL)")
        self.check_not_empty(block)
        located = [d for d in block.decls if d.location]
        if located and len(located) != len(block.decls):
            self.error(block.pos, "located variables must be declared in a VAR_GLOBAL block of their own (MatIEC)")
        if block.qualifier == "PERSISTENT":
            self.error(block.pos, "PERSISTENT is outside the supported subset")
        for decl in block.decls:
            try:
                for v in self.declare_var(None, "VAR_GLOBAL", block.qualifier, decl, scope=scope, table=table):
                    if isinstance(scope, ResourceSym) and v.key in scope.config.globals:
                        self.report(v.pos, f"global '{v.name}' hides the configuration's global of the same name")
            except _Abort:
                pass

    def declare_task(self, node: A.TaskDecl, res: ResourceSym) -> TaskSym:
        k = self.check_identifier(node.name, node.pos, "task")
        if any(t.key == k for t in res.tasks):
            self.error(node.pos, f"duplicate task '{node.name}'")
        interval, priority = None, 0
        for pname, ppos, value in node.params:
            pk = pname.upper()
            if pk == "INTERVAL":
                if not (isinstance(value, A.Literal) and value.kind == "time"):
                    self.error(value.pos, "INTERVAL must be a duration literal such as T#10ms")
                else:
                    self.check_duration_units(value)      # a task's INTERVAL too (iec2c: "invalid task initialization")
                if value.value <= 0:
                    self.error(value.pos, "INTERVAL must be positive")
                interval = value.value
            elif pk == "PRIORITY":
                if not (isinstance(value, A.Literal) and value.kind == "int"):
                    self.error(value.pos, "PRIORITY must be an integer literal")
                priority = value.value
            elif pk == "SINGLE":
                self.error(ppos, "event tasks (SINGLE) are outside the supported subset")
            else:
                self.error(ppos, f"unknown task parameter '{pname}'")
        return TaskSym(node.name, k, node.pos, interval, priority)

    def declare_program_instance(self, node: A.ProgramConfig, res: ResourceSym) -> ProgInst:
        k = self.check_identifier(node.name, node.pos, "program instance")
        if any(p.key == k for p in res.programs) or k in res.globals:
            self.error(node.pos, f"duplicate name '{node.name}' in {res.described}")
        if k in res.config.globals:
            self.error(node.pos, f"program instance '{node.name}' has the name of a global of the configuration "
                                 "(MatIEC rejects it)")
        if any(r.key == k for r in res.config.resources) or k == res.key:
            self.error(node.pos, f"program instance '{node.name}' has the name of a resource (MatIEC rejects it)")
        pou = self.pous.get(node.type_name.upper())
        if pou is None and node.type_name.upper() in self.failed_pous:
            raise _Abort     # its declaration was rejected, and reported
        if pou is None or pou.kind != "PROGRAM":
            self.error(node.type_pos, f"'{node.type_name}' is not a PROGRAM declared before the configuration")
        self.check_has_code(pou, node.type_pos)
        task = None
        if node.task:
            task = next((t for t in res.tasks if t.key == node.task.upper()), None)
            if task is None and node.task.upper() in self.failed_tasks:
                raise _Abort     # its declaration was rejected, and reported
            if task is None:
                self.error(node.pos, f"unknown task '{node.task}'")
        if node.bindings:
            self.error(node.bindings[0][1], "binding program parameters in the configuration is outside the "
                                            "supported subset (MatIEC generates C that does not compile)")
        self.check_externals(pou, res, node.pos, set())
        return ProgInst(node.name, k, node.pos, pou, task)

    def resolve_global(self, res: ResourceSym, key: str) -> Var | None:
        return res.globals.get(key) or res.config.globals.get(key)

    def check_has_code(self, pou: PouSym, pos: A.Pos) -> None:
        """A POU declared with code generation off can be used only by others declared so."""
        if pou.no_code and not (self.cur is not None and self.cur.no_code):
            self.error(pos, f"{pou.name} is declared between {{disable code generation}} and {{enable code "
                            f"generation}}: no C is generated for it (by MatIEC either), so it cannot be "
                            f"{'called' if pou.kind == 'FUNCTION' else 'instantiated'} here")

    def check_externals(self, pou: PouSym, res: ResourceSym, pos: A.Pos, seen: set) -> None:
        if pou.key in seen:
            return
        seen.add(pou.key)
        for ext in pou.externals:
            g = self.resolve_global(res, ext.key)
            where = f" (used by {pou.name})"
            if g is None:
                self.report(pos, f"VAR_EXTERNAL '{ext.name}' of {pou.name} has no VAR_GLOBAL in {res.described}")
                self.externals_reported.add(ext)
                continue
            if T.ERROR in (g.ty, ext.ty):
                continue
            if not T.same(g.ty, ext.ty):
                self.report(ext.pos, f"VAR_EXTERNAL '{ext.name}' is {T.describe(ext.ty)} but the global is "
                                     f"{T.describe(g.ty)}{where}")
            if g.constant and not ext.constant:
                self.report(ext.pos, f"the global '{ext.name}' is CONSTANT: declare it VAR_EXTERNAL CONSTANT{where}")
        for inst in pou.instances:
            self.check_externals(inst.ty.pou, res, pos, seen)
        for v in pou.vars.values():
            if v.kind in ("VAR_INPUT", "VAR_IN_OUT") and v.is_fb_instance:
                self.check_externals(v.ty.pou, res, pos, seen)

    def check_externals_declared(self) -> None:
        """Every VAR_EXTERNAL of a POU that gets C needs a VAR_GLOBAL of that name somewhere in the CONFIGURATION:
        iec2c accepts one without, but its C then calls __GET_GLOBAL_<name>, which nothing declares."""
        declared: set[str] = set()
        if self.config is not None:
            declared.update(self.config.globals)
            for res in self.config.resources:
                declared.update(res.globals)
        for pou in self.pous.values():
            if pou.std or pou.no_code:
                continue
            for ext in pou.externals:
                if ext.key in declared or ext in self.externals_reported:
                    continue
                where = ("the CONFIGURATION has no VAR_GLOBAL of that name" if self.config else
                         "there is no CONFIGURATION to declare its VAR_GLOBAL")
                self.report(ext.pos, f"VAR_EXTERNAL '{ext.name}' of {pou.name}: {where}. MatIEC's iec2c accepts "
                                     f"this, but the C it generates does not compile (__GET_GLOBAL_{ext.key} is "
                                     "never declared); build the POU with a CONFIGURATION that declares the global")

    # ------------------------------------------------------------------ bodies
    def check_body(self, pou: PouSym) -> None:
        too_deep = [] if pou.std else nesting.check_body(pou.kind, pou.ast.body)
        for exc in too_deep:
            hint = ("compute parts of it into variables first" if exc.what == "expression" else
                    "move the inner part into a FUNCTION or FUNCTION_BLOCK, or flatten the conditions")
            self.report(exc.pos, f"{exc.what} nested too deeply: MatIEC's parser keeps at most "
                                 f"{nesting.LIMIT} symbols pending and this needs {exc.need} here; {hint}")
        if too_deep:     # the rest of the body is not checked: its walk could go as deep as its nesting
            pou.checked = True
            return
        saved = (self.cur, self.loops, self.for_vars)
        self.cur, self.loops, self.for_vars = pou, 0, []
        try:
            if not pou.ast.body:
                self.report(pou.ast.pos, f"{pou.kind} {pou.name} has no statements (MatIEC rejects an empty body)")
            self.statements(pou.ast.body)
        finally:
            self.cur, self.loops, self.for_vars = saved
        pou.checked = True

    def statements(self, stmts: list[A.Node]) -> None:
        for s in stmts:
            try:
                self.statement(s)
            except _Abort:
                pass
            except RecursionError:      # a backstop: nesting.py bounds the depth of what gets here
                self.report(s.pos, "expression nested too deeply")

    def statement(self, s: A.Node) -> None:
        if isinstance(s, A.Assign):
            ty = self.lvalue(s.target, "assignment")
            if isinstance(ty, T.PouType):
                self.error(s.pos, "assigning a whole function block instance is outside the supported subset")
            self.coerce(s.value, ty, "assignment")
        elif isinstance(s, A.CallStmt):
            self.call_statement(s.call)
        elif isinstance(s, A.If):
            for cond, body in s.branches:
                try:
                    self.coerce(cond, T.BOOL, "IF condition")
                except _Abort:
                    pass
                self.statements(body)
            if s.else_body is not None:
                self.statements(s.else_body)
        elif isinstance(s, A.Case):
            self.case(s)
        elif isinstance(s, A.For):
            self.for_loop(s)
        elif isinstance(s, A.While):
            self.coerce(s.cond, T.BOOL, "WHILE condition")
            self.loops += 1
            self.statements(s.body)
            self.loops -= 1
        elif isinstance(s, A.Repeat):
            self.loops += 1
            self.statements(s.body)
            self.loops -= 1
            self.coerce(s.cond, T.BOOL, "UNTIL condition")
        elif isinstance(s, (A.Exit, A.Continue)):
            if not self.loops:
                self.error(s.pos, f"{'EXIT' if isinstance(s, A.Exit) else 'CONTINUE'} outside a loop")
        elif isinstance(s, A.Return):
            pass
        elif isinstance(s, A.PragmaStmt) and is_c_pragma(s.text):
            self.error(s.pos, C_PRAGMA)
        elif isinstance(s, A.PragmaStmt):
            self.error(s.pos, "pragmas in a body (C code) are outside the supported subset")
        else:
            self.error(s.pos, "unsupported statement")

    def case(self, s: A.Case) -> None:
        sel = self.concrete(s.selector)
        sb = sel.base()
        if not (T.is_int(sb) or isinstance(sb, T.Enum)):
            self.error(s.selector.pos, f"the CASE selector must be an integer or enumerated value, not "
                                       f"{T.describe(sel)} (MatIEC; convert it, e.g. BYTE_TO_USINT)")
        for labels, body in s.elements:
            for lab in labels:
                try:
                    for v in (lab.lo, lab.hi):
                        if v is None:
                            continue
                        if isinstance(sb, T.Enum):
                            if lab.hi is not None:
                                self.error(lab.pos, "a range of enumerated values is not allowed")
                            self.enum_value_of(v, sb)
                        else:
                            if not (isinstance(v, A.Literal) and v.kind == "int"):
                                self.error(v.pos, "a CASE label must be an integer literal")
                            if "#" in v.text:
                                self.error(v.pos, "CASE labels must be decimal integers (MatIEC rejects 16#..)")
                            if v.type_name is not None:
                                self.error(v.pos, "typed CASE labels are outside the supported subset")
                            v.ty = sb
                    if lab.hi is not None and not isinstance(sb, T.Enum) and lab.lo.value > lab.hi.value:
                        self.error(lab.pos, f"empty CASE range {lab.lo.value}..{lab.hi.value}")
                except _Abort:
                    pass
            self.statements(body)
        if s.else_body is not None:
            self.statements(s.else_body)

    def for_loop(self, s: A.For) -> None:
        ty = self.lvalue(s.var, "FOR control variable")
        sym = s.var.sym
        if not T.is_int(ty):
            self.error(s.var.pos, f"the FOR control variable must be an integer, not {T.describe(ty)}")
        if sym.kind in ("VAR_EXTERNAL", "VAR_IN_OUT") or sym.location:
            self.error(s.var.pos, "the FOR control variable must be a local variable")
        self.coerce(s.start, ty, "FOR start value")
        self.coerce(s.end, ty, "FOR end value")
        if s.step is not None:
            self.coerce(s.step, ty, "FOR BY value")
            if isinstance(s.step, A.Literal) and s.step.value == 0 and not _leaves_loop(s.body):
                self.error(s.step.pos, "FOR ... BY 0 never ends: its body has no EXIT or RETURN")
        self.loops += 1
        self.for_vars.append(sym)
        try:
            self.statements(s.body)
        finally:
            self.for_vars.pop()
            self.loops -= 1

    # ------------------------------------------------------------------ calls as statements
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

    # ------------------------------------------------------------------ variables
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

    # ------------------------------------------------------------------ expressions
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

    def check_duration_units(self, e: A.Literal) -> None:
        if re.search(r"(?i)\d(us|ns)", e.text):
            self.error(e.pos, f"{e.text}: the units us and ns are outside the supported subset (MatIEC knows d, h, m, "
                              "s and ms: write T#0.25ms)")

    def infer_Literal(self, e: A.Literal) -> T.Type:
        tn = e.type_name
        if e.kind == "wstring":
            self.error(e.pos, "WSTRING literals are outside the supported subset")
        if e.kind == "time":
            self.check_duration_units(e)
        if e.kind == "string":
            self.check_string_escapes(e)
            self.check_string_ascii(e)
        if e.kind == "string" and tn is not None:
            self.error(e.pos, f"{tn}#{e.text}: a typed string literal is outside the supported subset (MatIEC's "
                              "grammar has no typed string literals and refuses it); write the string alone")
        if e.kind == "real" and outside_float_range(e.text):
            self.error(e.pos, f"the real literal {e.text} is outside the range MatIEC accepts for any real "
                              "literal, LREAL included (it reads them as 32-bit floats: 1.18E-38 to 3.40E38 in "
                              "magnitude, or 0)")
        if tn is None:
            if e.kind == "string":
                return self._string_lit(e)
            return {"int": T.LIT_INT, "real": T.LIT_REAL, "bool": T.BOOL,
                    "time": T.TIME, "date": T.DATE, "tod": T.TOD, "dt": T.DT}[e.kind]
        t = self.named_type_for_literal(tn, e.pos)
        tb = t.base()
        if e.kind == "int":
            if not isinstance(tb, T.Elem) or tb.kind not in ("sint", "uint", "bit", "bool"):
                self.error(e.pos, f"{tn}#{e.text}: an integer is not a {tn} literal")
            lo, hi = (t.lo, t.hi) if isinstance(t, T.Subrange) else (tb.lo, tb.hi)
            if not lo <= e.value <= hi:
                self.error(e.pos, f"the value {e.text} does not fit {tn} ({lo}..{hi})")
            return tb
        if e.kind == "real":
            if tb not in T.REALS:
                self.error(e.pos, f"{tn}#{e.text}: a real number is not a {tn} literal")
            return tb
        if e.kind == "bool":
            if tb is not T.BOOL:
                self.error(e.pos, f"{tn}#{e.text}: not a {tn} literal")
            return T.BOOL
        if e.kind == "string":
            if tb is not T.STRING:
                self.error(e.pos, f"{tn}#{e.text}: not a {tn} literal")
            return self._string_lit(e)
        self.error(e.pos, f"invalid typed literal {tn}#{e.text}")

    def check_string_escapes(self, e: A.Literal) -> None:
        """Escapes that MatIEC turns into C that does not compile or means something else."""
        raw = e.text[1:-1]
        i = 0
        while i < len(raw):
            if raw[i] == "$" and i + 1 < len(raw):
                nxt = raw[i + 1]
                if nxt in "Ll":
                    self.error(e.pos, "the escape $L is outside the supported subset (MatIEC writes a raw line "
                                      "break into the C); use $N")
                # MatIEC writes $N and $hh as C's \xHH, which swallows a hexadecimal digit that follows
                width = 1 if nxt in "Nn" else (2 if re.fullmatch(r"[0-9A-Fa-f]{2}", raw[i + 1:i + 3]) else 0)
                if width and re.match(r"[0-9A-Fa-f]", raw[i + 1 + width:i + 2 + width]):
                    self.error(e.pos, f"'${raw[i + 1:i + 1 + width]}' followed by a hexadecimal digit is outside the "
                                      "supported subset (MatIEC's C reads the digit as part of the escape)")
                i += 1 + max(width, 1)
                continue
            i += 1

    def check_string_ascii(self, e: A.Literal) -> None:
        """MatIEC's lexer takes only 7-bit characters in a string literal (a byte above 127 is no token)."""
        bad = next((ch for ch in e.text if ord(ch) > 127), None)
        if bad is not None:
            self.error(e.pos, f"the string literal contains the non-ASCII character {bad!r}, which MatIEC refuses "
                              "(its lexer knows 7-bit characters only in a string literal); write each byte as "
                              "$hh, e.g. $E9")

    def _string_lit(self, e: A.Literal) -> T.Type:
        if len(e.value) > T.STR_MAX_LEN:
            self.error(e.pos, f"string literal longer than {T.STR_MAX_LEN} characters")
        return T.STRING

    def named_type_for_literal(self, name: str, pos: A.Pos) -> T.Type:
        if name in T.ELEMENTARY:
            return T.ELEMENTARY[name]
        if name in T.ELEMENTARY_ALIASES:
            return T.ELEMENTARY_ALIASES[name]
        if name in self.types:
            return self.types[name]
        self.error(pos, f"unknown type '{name}' in typed literal")

    def infer_EnumLit(self, e: A.EnumLit) -> T.Type:
        t = self.types.get(e.type_name)
        if not isinstance(t, (T.Enum, T.Alias)) or not isinstance(t.base(), T.Enum):
            self.error(e.pos, f"'{e.type_name}' is not an enumerated type")
        en = t.base()
        if e.value.upper() not in en.values:
            self.error(e.pos, f"'{e.value}' is not a value of {en.name}")
        return en

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

    # ------------------------------------------------------------------ function calls
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
        if k in UNSUPPORTED_FUNCTIONS:
            self.error(e.pos, f"{UNSUPPORTED_FUNCTIONS[k]} is outside the supported subset (MatIEC)")
        self.error(e.pos, f"unknown function '{e.name}' (functions must be declared before they are used)")

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


def _leaves_loop(body: list[A.Node]) -> bool:
    """Whether a loop body has a way out: a RETURN anywhere, or an EXIT that is not inside an inner loop."""
    todo = [(s, False) for s in body]
    while todo:
        s, nested = todo.pop()
        if isinstance(s, A.Return) or (isinstance(s, A.Exit) and not nested):
            return True
        if isinstance(s, A.If):
            todo += [(x, nested) for _, b in s.branches for x in b] + [(x, nested) for x in s.else_body or []]
        elif isinstance(s, A.Case):
            todo += [(x, nested) for _, b in s.elements for x in b] + [(x, nested) for x in s.else_body or []]
        elif isinstance(s, (A.For, A.While, A.Repeat)):
            todo += [(x, True) for x in s.body]
    return False


def _date_field(t: T.Type, path: str = "") -> tuple[str, T.Type] | None:
    """The first DATE or DT inside a type (through fields and array elements), with its path."""
    tb = t.base()
    if tb is T.DATE or tb is T.DT:
        return path, tb
    if isinstance(tb, T.Struct):
        for f in tb.fields:
            found = _date_field(f.ty, f"{path}.{f.name}" if path else f.name)
            if found:
                return found
    if isinstance(tb, T.Array):
        return _date_field(tb.elem, path + "[]")
    return None


def _has_index(e: A.Node) -> bool:
    while isinstance(e, (A.Member, A.Index)):
        if isinstance(e, A.Index):
            return True
        e = e.base
    return False


def _shiftable(t) -> bool:
    return T.is_bit(t) and not T.same(t, T.BOOL)


def _selectable(t: T.Type) -> bool:
    tb = t.base()
    return isinstance(tb, T.Elem)


def _a(noun: str) -> str:
    return ("an " if noun[0] in "aeiou" else "a ") + noun


def _hint(found: T.Type, want: T.Type) -> str:
    fb, wb = found.base(), want.base()
    if isinstance(fb, T.Elem) and isinstance(wb, T.Elem):
        return f"; convert explicitly, e.g. {fb.name}_TO_{wb.name}(...)"
    return ""


def _bulk_fits(values: list[int], ty: T.Type) -> bool:
    """A long list of plain integer literals (bulkinit) that initialises an array of an integer or bit
    string type, every value in range and no more values than elements: what the item-by-item checks
    would accept."""
    if not isinstance(ty, T.Array) or len(values) > ty.count:
        return False
    elem = ty.elem.base()
    if not (isinstance(elem, T.Elem) and elem.kind in ("sint", "uint", "bit")) or isinstance(ty.elem, T.Subrange):
        return False
    return T.fits(min(values), elem) and T.fits(max(values), elem)
