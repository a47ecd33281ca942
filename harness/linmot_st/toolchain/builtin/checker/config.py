"""The configuration: resources, tasks, program instances, globals and the VAR_EXTERNALs that use them."""

from __future__ import annotations

from .. import ast as A
from .. import types as T
from ..symbols import ConfigSym, PouSym, ProgInst, ResourceSym, TaskSym, Var
from .base import _Abort


class Configuration:
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
