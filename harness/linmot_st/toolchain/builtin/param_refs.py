"""Which parameters of FUNCTION_BLOCKs the generated C passes by reference: VAR_IN_OUTs, and inputs of a
STRUCT or ARRAY type that the FB only reads.

MatIEC's semantics, which the builtin backend keeps, is copy-in (and for an in-out copy-out): the instance
holds a copy of its input and in-out, copied in before the body and an in-out back after it. The copies
dominate a scan that calls many FBs with large parameters (plc_project: the 1 KiB mailbox and the axis'
structs in and out, the 2.3 KiB motion steps in, tens of KiB per axis and scan). A pointer to the actual
means the same wherever nothing can tell the two apart, which this module proves for a parameter over the
whole program, or leaves it a copy:

* the FB never reaches storage outside its instance and its parameters: neither it nor anything it calls
  has a VAR_EXTERNAL, a located variable or a direct address (%IX0.0), so it cannot see or change the
  actual by another name while its copy would differ;
* every call binds the parameter to a variable whose root is neither the instance itself nor the root of
  another in-out, nor of an output (`=>`) of the same call (the body, or the copies' write-back order,
  would tell them apart), and whose indices read none of these and call nothing (a write-back evaluates
  them again);
* no FUNCTION called in the call's arguments writes the parameter's root or a variable its indices read
  (through the FUNCTION's in-outs), nor reaches a located variable or an address: MatIEC copies the
  parameters in one by one in the FB's declaration order, so such a write may come after the copy;
* an in-out's root is read by no index of another in-out's actual or an output's target of the same call:
  MatIEC evaluates those again after the body, before or after this in-out's copy-out as the FB declares
  them, where a pointer has changed the variable already;
* no code reads or writes the parameter from outside the FB (`Inst.Box`): the copy there would be stale;
* an input: the FB's body never writes it, nor passes it as an in-out or an output target.

A forced actual of an in-out still gets a copy that is dropped (codegen.fb_call). What remains different,
documented in docs/builtin-compiler.md: the instance's member in the manifest is a pointer to the actual
(`ptr:T`) instead of a copy, so Python reads the actual as it is now (and forcing that member forces the
actual); and a scan that faults inside the body leaves the body's writes so far in an in-out's actual (a
copy would drop them; the PLC stops either way).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterator

from . import ast as A
from . import types as T
from .symbols import PouSym, Program, Var


def by_reference(prog: Program) -> set[tuple[str, str]]:
    """(FB key, parameter key) of each parameter the C passes as a pointer."""
    reaches = _reaches_globals(prog)
    refs = {(p.key, v.key) for p in prog.pous
            if p.kind == "FUNCTION_BLOCK" and not p.std and not reaches[p.key]
            for v in p.params if _candidate(p, v)}
    for p in prog.pous:
        if p.ast is None:
            continue
        for node in _walk(p.ast.body):
            if isinstance(node, A.Call) and isinstance(node.target, tuple) and node.target[1] is not None:
                refs -= _unsafe(node, refs, reaches)
            elif isinstance(node, A.Member) and isinstance(getattr(node.base, "ty", None), T.PouType):
                sym = getattr(node, "sym", None)
                if isinstance(sym, Var) and sym.kind in ("VAR_IN_OUT", "VAR_INPUT"):
                    refs.discard((node.base.ty.pou.key, sym.key))
    return refs


def _candidate(pou: PouSym, v: Var) -> bool:
    if v.is_fb_instance or v.implicit:
        return False
    if v.kind == "VAR_IN_OUT":
        return True
    return (v.kind == "VAR_INPUT" and isinstance(v.ty.base(), (T.Array, T.Struct))
            and v not in _written(pou))


def _written(pou: PouSym) -> set:
    """The variables of a POU its body may write: assignment and FOR targets, outputs' targets, in-out
    actuals (of FBs and FUNCTIONs), by their roots."""
    out: set = set()
    if pou.ast is None:
        return out
    for node in _walk(pou.ast.body):
        if isinstance(node, A.Assign):
            out.add(_root(node.target))
        elif isinstance(node, A.For):
            out.add(_root(node.var))
        elif isinstance(node, A.Call) and isinstance(node.target, tuple):
            for param, arg in node.target[2]:
                if param.kind in ("VAR_IN_OUT", "VAR_OUTPUT") and (param.kind == "VAR_IN_OUT" or arg.output):
                    out.add(_root(arg.value))
    return out


def _unsafe(call: A.Call, refs: set[tuple[str, str]], reaches: dict[str, bool]) -> set[tuple[str, str]]:
    """The candidates among the called FB's parameters that this call does not let pass by reference."""
    pou, inst, bound = call.target
    everything = {(pou.key, p.key) for p in pou.params}
    mine = [(p, a) for p, a in bound if (pou.key, p.key) in refs]
    unsafe = everything - {(pou.key, p.key) for p, _ in mine}     # left unbound
    # the places the copy-out evaluates again after the body (outputs' targets, in-outs' actuals): an index
    # there that reads an in-out's variable reads it before or after that in-out's own copy-out, as the FB
    # declares them, where a pointer has written it already
    after = [(p, a.value) for p, a in bound if p.kind == "VAR_IN_OUT" or (p.kind == "VAR_OUTPUT" and a.output)]
    # what the call writes, by their roots: its in-outs during the body (by reference, or by the copy-out after
    # it) and its outputs after it; an input's copy is taken before the body, so its pointer must see none of them
    written = [(p, _root(v)) for p, v in after]
    # what the arguments' FUNCTIONs write through their in-outs: MatIEC copies the parameters in one by one
    # (in the FB's declaration order), so such a write may come after a parameter's copy
    effects, opaque = _side_effects([a.value for _, a in bound], reaches)
    if opaque:
        return everything
    for p, a in mine:
        root = _root(a.value) if _is_place(a.value) else None
        others = [r for q, r in written if q is not p]
        clash = root is None or root is inst or any(r is root for r in [*others, *effects])
        indices = list(_walk(_index_exprs(a.value)))
        if any(isinstance(n, A.Name) and any(n.sym is r for r in effects) for n in indices):
            clash = True
        if p.kind == "VAR_IN_OUT":      # a copy-out evaluates the indices again, after the body
            for node in indices:
                if isinstance(node, A.Call) or (isinstance(node, A.Name)
                                                and any(node.sym is r for r in [*others, root, inst])):
                    clash = True
            for q, target in after:
                if q is not p and any(isinstance(n, A.Name) and n.sym is root
                                      for n in _walk(_index_exprs(target))):
                    clash = True
        if clash:
            unsafe.add((pou.key, p.key))
    return unsafe


def _side_effects(exprs: list[A.Node], reaches: dict[str, bool]) -> tuple[list, bool]:
    """The roots the FUNCTIONs called in `exprs` (at any depth) may write through their in-outs, and whether
    one of them reaches a located variable or an address (then what it writes is not known by name)."""
    roots, opaque = [], False
    for node in _walk(exprs):
        if isinstance(node, A.Call) and isinstance(node.target, tuple) and node.target[1] is None:
            fn = node.target[0]
            opaque = opaque or reaches.get(fn.key, True)
            roots.extend(_root(a.value) for q, a in node.target[2] if q.kind == "VAR_IN_OUT")
    return roots, opaque


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


def _is_place(e: A.Node) -> bool:
    """A variable, a member or an element of one (what a pointer can point to)."""
    while isinstance(e, (A.Member, A.Index)):
        e = e.base
    return isinstance(e, A.Name) and isinstance(e.sym, Var) and e.paren == 0


def _root(e: A.Node):
    """The variable an lvalue belongs to."""
    while isinstance(e, (A.Member, A.Index, A.BitAccess)):
        e = e.base
    return getattr(e, "sym", None)


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
