"""iec2c's `#line` directives made exact for coverage builds (docs/coverage.md, "MatIEC").

iec2c (`-O l`) writes one `#line N "file"` before the C of each ST statement (generate_c_st.cc,
print_line_directive in the statement list). Two things then count on the wrong ST line in gcov:
- the C lines after the first of a statement are numbered N+1, N+2 ... (a directive numbers the line after
  it, and the ones after that count on), ST lines that may hold other code or none;
- `} else if (cond) {` has no directive of its own: the ELSIF's test counts on the line of the last
  statement of the arm before it.
- the C after the body (the rest of the function, the next functions of the file) counts on the lines
  after the last statement's.
`exact_lines` repeats the directive before each C line that starts a statement (the line before it ends
a statement or a block: `;`, `{`, `}`; never inside a macro call, an expression or a macro's definition),
puts the ELSIF's own line before each `} else if (`: the first ELSIF of that file after the line in
effect (the arm before it ends there, so no other ELSIF lies between), gives the lines of no statement (a
block's closing brace, CASE's `else if` tests and `else {`) the C file's own numbering, as the builtin backend
counts them on no ST line, and returns to the C file's own numbering after each function.
"""

from __future__ import annotations

import re
from pathlib import Path

from ..builtin import ast as A
from ..builtin.errors import BuiltinCompileError

_DIRECTIVE = re.compile(r'^\s*#line\s+(\d+)\s+"((?:[^"\\]|\\.)*)"\s*$')
_ELSE_IF = re.compile(r"^\s*\}\s*else\s+if\s*\(")
# a line of no statement: a block's end (`}`, `};`, a function's `} // F_body__()`) or CASE's next test
# (`else if ((__case_expression == 2) ||` on a line of its own, then its `else {`): iec2c numbers them with
# the previous statement's line, where they would count every pass; the builtin backend counts them nowhere
_NO_STATEMENT = re.compile(r"^\s*(\}\s*;?\s*(//.*)?|else\b.*)$")


def exact_lines(text: str, elsif_lines, c_name: str) -> str:
    """The C text with directives repeated and ELSIF lines set. `elsif_lines(file) -> sorted list[int]`:
    the lines of the ELSIF keywords' tests in that ST file (as the #line names it); `c_name`: the C file's
    name, for the C after a function."""
    lines = text.split("\n")
    tail = _body_tails(lines)
    out: list[str] = []
    current: tuple[int, str] | None = None      # (ST line, file as written) in effect
    boundary = True                             # the previous C line ended a statement or a block
    continued = False                           # the previous line ended in a backslash (a macro's body)
    for i, line in enumerate(lines):
        if continued:
            continued = line.rstrip().endswith("\\")
            out.append(line)
            continue
        continued = line.rstrip().endswith("\\")
        m = _DIRECTIVE.match(line)
        if m:
            current = (int(m[1]), m[2])
            out.append(line)
            boundary = False            # the next line has this directive already
            continue
        stripped = line.strip()
        if current is not None and stripped and not stripped.startswith("#"):
            if _ELSE_IF.match(line):
                later = [n for n in elsif_lines(current[1]) if n > current[0]]
                if later:
                    current = (later[0], current[1])
                out.append(f'#line {current[0]} "{current[1]}"')
            elif _NO_STATEMENT.match(line) or i in tail:
                out.append(f'#line {len(out) + 2} "{c_name}"')          # counted on no ST line
            elif boundary:
                out.append(f'#line {current[0]} "{current[1]}"')
        out.append(line)
        if stripped and not stripped.startswith("#"):
            boundary = stripped.endswith((";", "{", "}")) and not stripped.endswith("\\")
        if current is not None and line.startswith("}"):
            # a function ends (iec2c writes its closing brace at column 0): the C after it is no ST line's;
            # back to the C file's own numbering (the directive numbers the line after it)
            out.append(f'#line {len(out) + 2} "{c_name}"')
            current = None
    return "\n".join(out)


def _body_tails(lines: list[str]) -> set[int]:
    """The indices of each body's tail, which iec2c numbers with the last statement's line: the `goto __end;`
    right before the `__end:` label, the label and the `return;` after it (an ST RETURN's own `goto __end;`
    comes earlier, with its own directive)."""
    tails: set[int] = set()
    code = [i for i, line in enumerate(lines) if line.strip() and not _DIRECTIVE.match(line)]
    for k, i in enumerate(code):
        if lines[i].strip() == "__end:":
            tails.add(i)
            if k > 0 and lines[code[k - 1]].strip() == "goto __end;":
                tails.add(code[k - 1])
            if k + 1 < len(code) and lines[code[k + 1]].strip() == "return;":
                tails.add(code[k + 1])
    return tails


def decisions(stmts: list) -> list:
    """Every IF and CASE statement in these statements, nested ones included, in source order."""
    out = []
    for s in stmts:
        if isinstance(s, A.If):
            out.append(s)
            for _, body in s.branches:
                out += decisions(body)
            out += decisions(s.else_body or [])
        elif isinstance(s, A.Case):
            out.append(s)
            for _, body in s.elements:
                out += decisions(body)
            out += decisions(s.else_body or [])
        elif isinstance(s, (A.For, A.While, A.Repeat)):
            out += decisions(s.body)
    return out


def elsif_lines(path: Path) -> list[int]:
    """The lines of the tests of every ELSIF in an ST file, sorted (read with the builtin parser)."""
    from ..builtin.parser import parse  # lark loads on first use: `linmot-st --help` imports this module
    try:
        elements = parse(Path(path).read_text(errors="replace"), str(path))
    except (BuiltinCompileError, OSError, RecursionError):
        return []
    return sorted({cond.pos.line for e in elements if isinstance(e, A.Pou)
                   for s in decisions(e.body) if isinstance(s, A.If) for cond, _ in s.branches[1:]})


def elsif_table(root: Path, sources: list[Path]):
    """elsif_lines for exact_lines by the name a `#line` gives: looked up among the build's sources (by
    its tail: an included file is named by its include path), else against the root."""
    cache: dict[str, list[int]] = {}

    def lookup(name: str) -> list[int]:
        if name not in cache:
            p = Path(name)
            path = p if p.is_absolute() else next(
                (s for s in sources if Path(s).parts[-len(p.parts):] == p.parts), root / p)
            cache[name] = elsif_lines(Path(path))
        return cache[name]
    return lookup
