"""Statements: POU bodies, assignments, IF, CASE, loops."""

from __future__ import annotations

from .. import ast as A
from .. import nesting
from .. import types as T
from ..parser import C_PRAGMA, is_c_pragma
from ..symbols import PouSym
from .base import _Abort


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


class Statements:
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
