"""Variable declarations: names, types, initial values, located variables (AT %IX...)."""

from __future__ import annotations

import re

from .. import ast as A
from .. import types as T
from ..symbols import LocatedCell, PouSym, Var
from .base import _Abort

LOCATION_RE = re.compile(r"%([IQM])([XBWDL]?)(\d+(?:\.\d+)*)$")


SIZE_BITS = {"X": 1, "B": 8, "W": 16, "D": 32, "L": 64}


class Variables:
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
