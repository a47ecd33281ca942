"""The branches of ST code as a PLC engineer counts them: the arms of each IF (THEN, each ELSIF, the ELSE
written or not) and of each CASE (each list of labels, the ELSE written or not); and the POUs' line spans.

Read with the builtin compiler's parser (syntax only, no types), so the same for both backends. gcc's
own branch counts are no measure of these: the C of one ST assignment already branches (the force flags
of linmot-st's variables, the bounds checks), and a condition with AND/OR branches per operand.

An arm's count is the count of the line of its first statement (gcov's line count: how often the line
was entered). An arm without a statement of its own line (the ELSE not written, an empty arm, an arm
whose first statement shares a line with the decision or with another arm) gets the remainder: the
decision's count less the counted arms'; with more than one such arm in a decision they are left out
(counts unknown), see docs/coverage.md.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from linmot_st.toolchain.builtin import ast as A
from linmot_st.toolchain.builtin.errors import BuiltinCompileError
from linmot_st.toolchain.builtin.parser import parse
from linmot_st.toolchain.matiec.line_map import decisions


@dataclass(frozen=True)
class Arm:
    label: str              # THEN, ELSIF, ELSE, "ELSE (none written)", "CASE 1, 2" ...
    line: int | None        # the line of its first statement; None: no line of its own


@dataclass(frozen=True)
class Decision:
    kind: str               # IF or CASE
    line: int               # the line of the IF / CASE keyword (its first test's code)
    pou: str
    arms: tuple[Arm, ...]

    def counts(self, line_counts: dict[int, int]) -> list[int | None]:
        """How often each arm was taken, from gcov's line counts; None: not known (module docstring)."""
        entries = line_counts.get(self.line, 0)
        own = [a.line for a in self.arms]
        shared = {ln for ln in own if ln is not None and (ln == self.line or own.count(ln) > 1)}
        out: list[int | None] = [None if a.line is None or a.line in shared else line_counts.get(a.line, 0)
                                 for a in self.arms]
        unknown = [k for k, c in enumerate(out) if c is None]
        if len(unknown) == 1:
            out[unknown[0]] = max(0, entries - sum(c for c in out if c is not None))
        return out


@dataclass(frozen=True)
class Pou:
    kind: str
    name: str
    first_line: int
    last_line: int


@dataclass
class StFile:
    path: Path
    pous: list[Pou]
    decisions: list[Decision]

    def pou_at(self, line: int) -> str | None:
        for p in self.pous:
            if p.first_line <= line <= p.last_line:
                return p.name
        return None


def read(path: Path) -> StFile:
    """The POUs and decisions of one ST file. A file the parser cannot read (not the subset) has none:
    its lines are still reported, its branches are not."""
    path = Path(path)
    try:
        elements = parse(path.read_text(errors="replace"), str(path))
    except (BuiltinCompileError, OSError, RecursionError):
        return StFile(path, [], [])
    found = [e for e in elements if isinstance(e, A.Pou) and not e.std]
    pous, decisions = [], []
    for k, e in enumerate(found):
        # a POU ends at its END_ keyword where the parser kept it, else before the next POU
        end = e.end_pos.line if e.end_pos else (found[k + 1].pos.line - 1 if k + 1 < len(found) else 10**9)
        pous.append(Pou(e.kind, e.name, e.pos.line, end))
        _walk(e.body, e.name, decisions)
    return StFile(path, pous, sorted(decisions, key=lambda d: d.line))


def _first_line(body: list[A.Node]) -> int | None:
    return body[0].pos.line if body else None


def _walk(stmts: list[A.Node], pou: str, out: list[Decision]) -> None:
    for s in decisions(stmts):
        if isinstance(s, A.If):
            arms = [Arm("THEN" if k == 0 else "ELSIF", _first_line(body)) for k, (_, body) in enumerate(s.branches)]
        else:
            arms = [Arm("CASE " + ", ".join(_label(lab) for lab in labels), _first_line(body))
                    for labels, body in s.elements]
        arms.append(Arm("ELSE", _first_line(s.else_body)) if s.else_body is not None
                    else Arm("ELSE (none written)", None))
        out.append(Decision("IF" if isinstance(s, A.If) else "CASE", s.pos.line, pou, tuple(arms)))


def _label(lab: A.CaseLabel) -> str:
    def text(n: A.Node) -> str:
        return str(getattr(n, "value", None) if getattr(n, "value", None) is not None else getattr(n, "name", "?"))
    return text(lab.lo) + (f"..{text(lab.hi)}" if lab.hi is not None else "")

