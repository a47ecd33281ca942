"""Which VAR_IN_OUT parameters of FUNCTION_BLOCKs the generated C passes by reference.

MatIEC's semantics, which the builtin backend keeps, is copy-in/copy-out: the instance holds a copy of its
in-out, copied in before the body and back after it. The copies dominate a scan that calls many FBs with
large in-outs (plc_project: the 1 KiB mailbox and the axis' structs, tens of KiB per axis and scan). A
pointer to the actual means the same wherever nothing can tell the two apart, which this module proves
for a parameter over the whole program, or leaves it a copy:

* the FB never reaches storage outside its instance and its in-outs: neither it nor anything it calls
  has a VAR_EXTERNAL, a located variable or a direct address (%IX0.0), so it cannot read the actual by
  another name while its copy would differ;
* every call binds the parameter, to a variable whose root is neither the instance itself, nor the root of
  another in-out or of an output (`=>`) of the same call (the copies' write-back order would matter), and
  whose indices read none of these and call nothing (the write-back would re-evaluate them);
* no code reads or writes the parameter from outside the FB (`Inst.Box`): the copy there would be stale.

A forced actual still gets a copy that is dropped (as a FUNCTION's in-out, codegen.fb_call). What remains
different, documented in docs/builtin-compiler.md: the FB's in-out member in the manifest is a pointer to
the actual (`ptr:T`) instead of a copy, and a scan that faults inside the body leaves the body's writes so
far in the actual (a copy would drop them; the PLC stops either way).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator

from . import ast as A
from . import types as T
from .symbols import PouSym, Program, Var


def by_reference(prog: Program) -> set[tuple[str, str]]:
    """(FB key, parameter key) of each VAR_IN_OUT the C passes as a pointer."""
    reaches = _reaches_globals(prog)
    refs = {(p.key, v.key) for p in prog.pous
            if p.kind == "FUNCTION_BLOCK" and not p.std and not reaches[p.key]
            for v in p.params if v.kind == "VAR_IN_OUT" and not v.is_fb_instance}
    for p in prog.pous:
        if p.ast is None:
            continue
        for node in _walk(p.ast.body):
            if isinstance(node, A.Call) and isinstance(node.target, tuple) and node.target[1] is not None:
                refs -= _unsafe(node)
            elif isinstance(node, A.Member) and isinstance(getattr(node.base, "ty", None), T.PouType):
                sym = getattr(node, "sym", None)
                if isinstance(sym, Var) and sym.kind == "VAR_IN_OUT":
                    refs.discard((node.base.ty.pou.key, sym.key))
    return refs


def _unsafe(call: A.Call) -> set[tuple[str, str]]:
    """The in-outs of the called FB that this call does not let pass by reference."""
    pou, inst, bound = call.target
    inouts = [(p, a) for p, a in bound if p.kind == "VAR_IN_OUT" and not p.is_fb_instance]
    out_roots = [_root(a.value) for p, a in bound if p.kind == "VAR_OUTPUT" and a.output]
    roots = [_root(a.value) for _, a in inouts]
    unsafe = {(pou.key, p.key) for p in pou.params if p.kind == "VAR_IN_OUT"} - {(pou.key, p.key) for p, _ in inouts}
    for (p, a), root in zip(inouts, roots):
        others = [r for r in roots if r is not root] + out_roots + [inst]
        clash = sum(1 for r in roots if r is root) > 1 or any(root is r for r in others)
        for sub in _index_exprs(a.value):
            for node in _walk([sub]):
                if isinstance(node, A.Call) or (isinstance(node, A.Name) and any(node.sym is r for r in others + [root])):
                    clash = True
        if clash:
            unsafe.add((pou.key, p.key))
    return unsafe


def _reaches_globals(prog: Program) -> dict[str, bool]:
    """Per POU: whether it, or a POU it calls, reads or writes a global, a located variable or an address."""
    own = {p.key: any(v.kind == "VAR_EXTERNAL" or v.location for v in p.vars.values())
           or (p.ast is not None and any(isinstance(n, A.DirectVar) for n in _walk(p.ast.body)))
           for p in prog.pous}
    memo: dict[str, bool] = {}

    def reaches(p: PouSym, seen: frozenset = frozenset()) -> bool:
        if p.key not in memo:
            memo[p.key] = own.get(p.key, True) or any(reaches(c, seen | {p.key}) for c in p.callees
                                                       if c.key not in seen)
        return memo[p.key]

    return {p.key: reaches(p) for p in prog.pous}


def _root(e: A.Node):
    """The variable an lvalue belongs to."""
    while isinstance(e, (A.Member, A.Index)):
        e = e.base
    return getattr(e, "sym", e)


def _index_exprs(e: A.Node) -> list[A.Node]:
    """The index expressions on the way from an lvalue to its root."""
    out = []
    while isinstance(e, (A.Member, A.Index)):
        if isinstance(e, A.Index):
            out.extend(e.indices)
        e = e.base
    return out


def _walk(nodes) -> Iterator[A.Node]:
    """Every AST node in and below `nodes` (statements or expressions)."""
    stack = list(nodes) if isinstance(nodes, list) else [nodes]
    while stack:
        n = stack.pop()
        if isinstance(n, (list, tuple)):
            stack.extend(n)
            continue
        if not isinstance(n, A.Node):
            continue
        yield n
        for f in dataclasses.fields(n):
            if f.name in ("target", "sym", "ty", "pos"):
                continue
            v = getattr(n, f.name)
            if isinstance(v, (A.Node, list, tuple)):
                stack.append(v)
