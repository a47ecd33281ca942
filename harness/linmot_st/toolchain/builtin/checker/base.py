"""The checker's state (what it has declared so far, where it is) and its diagnostics, shared by its parts."""

from __future__ import annotations

from .. import ast as A
from .. import constfold
from .. import types as T
from ..errors import Diagnostic
from ..symbols import ConfigSym, LocatedCell, PouSym, Var


class _Abort(Exception):
    """Stops checking the current statement or declaration after an error was recorded."""


class CheckerState:
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
