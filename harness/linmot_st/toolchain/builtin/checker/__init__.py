"""Semantic checks and typing: accepts exactly what the builtin backend compiles, rejects the rest.

The rules are MatIEC's (docs/builtin-compiler.md lists them): strict typing with no implicit
conversion, untyped literals that take the type of their context (and must fit it), ANY_BIT types
without arithmetic, array types compared by name, declaration before use, no recursion. Constructs
outside the subset are rejected with a message that says so. Errors are collected, one per
statement or declaration at most, and raised together as a BuiltinCompileError.

The checker annotates the AST in place (`Expr.ty`, `Name.sym`, `Call.target`) for codegen.py.

`Checker` is put together from one class per concern (as rusty's `validation/` is split), each in its
module: names (identifiers), datatypes (TYPE declarations), initial_values, pous (POU interfaces), variables,
config (configuration, resources, tasks, globals), statements, calls (FB and FUNCTION calls), std_calls
(standard functions: the typing rule of their row in stdfuncs/table.py), coercion (the typing core), literals
and expressions; base holds the state they share and the diagnostics. The parts call one another through `self`.
"""

from __future__ import annotations

import re

from .. import ast as A
from .. import types as T
from ..errors import BuiltinCompileError
from ..parser import C_PRAGMA, is_c_pragma
from ..symbols import Program
from .base import CheckerState, _Abort
from .calls import Calls
from .coercion import Coercion
from .config import Configuration
from .datatypes import DataTypes
from .expressions import Expressions
from .initial_values import InitialValues
from .literals import Literals
from .names import KEYWORDS, MATIEC_IDENTIFIERS, NameRules, matiec_library_names
from .pous import PouInterfaces
from .statements import Statements
from .std_calls import StdCalls
from .variables import Variables

__all__ = ["Checker", "KEYWORDS", "MATIEC_IDENTIFIERS", "matiec_library_names"]

# MatIEC's pragmas that turn the generation of C off and on for the POUs between them (types are still
# generated): matched as its lexer does, case-insensitively and exactly as spelled
DISABLE_CODE = re.compile(r"(?i)\{disable code generation\}")
ENABLE_CODE = re.compile(r"(?i)\{enable code generation\}")


class Checker(CheckerState, NameRules, DataTypes, InitialValues, PouInterfaces, Variables, Configuration, Statements,
              Calls, StdCalls, Coercion, Literals, Expressions):
    """The checker: `Checker().check(elements, files)` -> Program, or raises BuiltinCompileError."""

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

