"""Where a program's FOR loops behave differently under the installed iec2c's FOR semantics.

The sources are read with the builtin parser (syntax only, as st_decls does); each FOR is judged against
the traits for_semantics.probe measured (spec/matiec.md 7.1):
  * loops that should run once run zero times: a FOR whose bounds can give exactly one iteration
    (constant bounds: exactly; otherwise: it can);
  * the control variable ends at its last value: a FOR whose control variable is read anywhere in the
    POU outside the loops it controls (the next statement, or the next scan of a PROGRAM or FB);
  * a loop whose end is the type's maximum never ends: a FOR whose last step can pass the control
    variable's type limit (constant end and step: exactly; otherwise: it can). Under HEAD only a FOR with
    BY on a 32- or 64-bit control variable does (its test adds the step in the C type).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

from ..builtin import ast as A
from ..builtin.errors import BuiltinCompileError
from ..builtin.loader import display_name, read_source
from ..builtin.parser import parse
from .for_semantics import ForSemantics

RANGES = {"SINT": (-2 ** 7, 2 ** 7 - 1), "INT": (-2 ** 15, 2 ** 15 - 1), "DINT": (-2 ** 31, 2 ** 31 - 1),
          "LINT": (-2 ** 63, 2 ** 63 - 1), "USINT": (0, 2 ** 8 - 1), "UINT": (0, 2 ** 16 - 1),
          "UDINT": (0, 2 ** 32 - 1), "ULINT": (0, 2 ** 64 - 1)}
NOT_PROMOTED = {"DINT", "LINT", "UDINT", "ULINT"}     # C adds in the type itself, not in int


def warnings(paths: list[Path], root: Path, search: list[Path], sem: ForSemantics) -> list[str]:
    """`file:line:col: warning: ...` for each FOR that this iec2c's semantics changes."""
    if sem.iec:
        return []
    out = []
    for path in paths:
        name = display_name(path, root, search)
        try:
            nodes = parse(read_source(path), name)
        except (OSError, BuiltinCompileError):
            continue            # iec2c has its say on what does not parse
        for pou in (n for n in nodes if isinstance(n, A.Pou)):
            out += _pou_warnings(pou, sem, A)
    return out


def _pou_warnings(pou, sem: ForSemantics, A) -> list[str]:
    types = {}
    for block in pou.blocks:
        for decl in block.decls:
            if isinstance(decl.spec, A.NamedSpec):
                for var, _pos in decl.names:
                    types[var.upper()] = decl.spec.name.upper()
    loops = [n for n in _walk(pou.body) if isinstance(n, A.For)]
    out = []
    for loop in loops:
        var = loop.var.name.upper()
        where = f"{loop.pos.file}:{loop.pos.line}:{loop.pos.col}: warning: FOR {loop.var.name}"
        under = f"under this iec2c ({sem.name} FOR semantics, spec/matiec.md 7.1)"
        start, end = _const(loop.start, A), _const(loop.end, A)
        step = 1 if loop.step is None else _const(loop.step, A)
        count = _iterations(start, end, step)
        if not sem.once and (count is None or count == 1):
            how = "runs exactly once" if count == 1 else "can run exactly once"
            out.append(f"{where}: {how}, and then runs zero times {under}; use WHILE or REPEAT")
        if not sem.past_end and _read_outside(pou, var, loops, A):
            out.append(f"{where}: {loop.var.name} is read outside the loop: after it, it holds its last value "
                       f"in the loop {under}, not the value one step past the end")
        ctype = types.get(var)
        can_spin = sem.spins or (sem.spins_by and loop.step is not None and (ctype is None or ctype in NOT_PROMOTED))
        passes = _passes_limit(start, end, step, ctype) if can_spin else False
        if passes is not False:
            how = "steps past" if passes else "can step past"
            out.append(f"{where}: its last step {how} the limit of {ctype or 'its type'}, and then the loop "
                       f"never ends {under}")
    return out


def _walk(node):
    """Every node below node (a node or a list of them), statements and expressions alike."""
    if isinstance(node, (list, tuple)):
        for item in node:
            yield from _walk(item)
    elif dataclasses.is_dataclass(node) and not isinstance(node, type):
        yield node
        for f in dataclasses.fields(node):
            if f.name not in ("pos", "sym", "target", "name_pos"):
                yield from _walk(getattr(node, f.name))


def _read_outside(pou, var: str, loops, A) -> bool:
    inside = set()
    for loop in loops:
        if loop.var.name.upper() == var:
            inside.add(id(loop.var))
            inside.update(id(n) for n in _walk(loop.body))
    return any(isinstance(n, A.Name) and n.name.upper() == var and id(n) not in inside for n in _walk(pou.body))


def _const(node, A) -> int | None:
    if isinstance(node, A.Literal) and node.kind == "int":
        return node.value
    if isinstance(node, A.UnOp) and node.op == "NEG":
        inner = _const(node.operand, A)
        return None if inner is None else -inner
    return None


def _iterations(start, end, step) -> int | None:
    if start is None or end is None or step is None or step == 0:
        return None
    if step > 0:
        return max(0, (end - start) // step + 1)
    return max(0, (start - end) // -step + 1)


def _passes_limit(start, end, step, ctype) -> bool | None:
    """Whether the step after the last iteration leaves the control variable's range (None: can't tell)."""
    if end is None or step is None or step == 0 or ctype not in RANGES:
        return None
    lo, hi = RANGES[ctype]
    count = _iterations(start, end, step)
    if count == 0:
        return False
    if count is not None:
        after = start + count * step
        return after > hi if step > 0 else after < lo
    # the start is not known: the last value is somewhere up to the end
    return None if (end + step > hi if step > 0 else end + step < lo) else False
