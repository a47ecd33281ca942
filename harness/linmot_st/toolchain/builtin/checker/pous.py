"""POU interfaces: FUNCTION, FUNCTION_BLOCK and PROGRAM declarations, their VAR blocks, the standard FBs."""

from __future__ import annotations

from .. import ast as A
from .. import stdfb
from .. import types as T
from ..symbols import PouSym, Var
from .base import _Abort


class PouInterfaces:
    def std_fb(self, key: str, pos: A.Pos) -> PouSym:
        if key in self.pous:
            return self.pous[key]
        if self._std_ast is None:
            from ..parser import parse
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
