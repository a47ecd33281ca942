"""Conditions in IEC text, as `rig.step_until`, `inject_fault(when=)` and the scope's triggers take them.

    MAIN.DONE OR MAIN.FAILED
    NOT (MAIN.STATION.STATE = ST_READY) AND MAIN.N * 2 >= MAIN.LIMIT - 1
    (MAIN.STATUS AND 16#0008) <> 0 XOR MAIN.FORCED

The grammar is IEC 61131-3's expression grammar (table 71 of edition 3, strongest first): parentheses,
`**`, unary `-` and `NOT`, `*` `/` `MOD`, `+` `-`, `<` `>` `<=` `>=`, `=` `<>`, `AND` (`&`), `XOR`, `OR`;
operators of equal precedence apply left to right. Operands: variables by IEC path (a unique suffix is
enough, as everywhere in the rig), literals (`5`, `-1.5E3`, `16#FF`, `2#1010`, `TRUE`, `T#1s500ms`,
`INT#7`, `'text'`) and enum values (bare, `ST_READY`, or typed, `E_STATE#ST_READY`) compared with an enum.
`==` and `!=` are accepted for `=` and `<>`.

A condition is parsed (lark, LALR) and type-checked when it is made, so a typo or an unknown variable
fails before any scan, with the column; it is then compiled to closures over the PLC's bound accessors
(`plc.var`), so evaluating it each scan does no lookup. Arithmetic is exact (Python integers, IEC `/` and
`MOD` truncating toward zero on integers), not wrapped to the variables' widths.
"""

from __future__ import annotations

import inspect
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache, partial
from typing import TYPE_CHECKING, Any

from lark import Lark, Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

if TYPE_CHECKING:
    from linmot_st.plc import Plc

GRAMMAR = r"""
?start: disj
?disj: xor_ | disj OR xor_            -> binop
?xor_: conj | xor_ XOR conj           -> binop
?conj: equality | conj AND equality   -> binop
?equality: compare | equality EQ compare  -> binop
?compare: sum | compare CMP sum       -> binop
?sum: product | sum ADD product       -> binop
?product: unary | product MUL unary   -> binop
?unary: power | NOT unary             -> unop
      | ADD unary                     -> unop
?power: atom | power POW atom         -> binop
?atom: PATH | INT | REAL | BASED | DURATION | TYPED | STRING | TRUE | FALSE
     | "(" disj ")"

OR: "OR"i
XOR: "XOR"i
AND: "AND"i | "&"
NOT: "NOT"i
TRUE: "TRUE"i
FALSE: "FALSE"i
EQ.2: "<>" | "==" | "!=" | "="           // .2: before CMP's "<" (lark tries terminals in order)
CMP: "<=" | ">=" | "<" | ">"
ADD: "+" | "-"
MUL: "*" | "/" | "MOD"i
POW.2: "**"                                // .2: before MUL's "*"
REAL.3: /\d[\d_]*\.\d[\d_]*([eE][+-]?\d+)?|\d[\d_]*[eE][+-]?\d+/
BASED.3: /(2|8|16)#[0-9A-Fa-f_]+/
DURATION.3: /(T|TIME|LT|LTIME)#-?[0-9_.a-zA-Z]+/i
TYPED.2: /[A-Za-z_]\w*#[\w.+\-#]+/
INT: /\d[\d_]*/
STRING: /'(\$.|[^'$])*'|"[^"]*"/
PATH: /%[IQM][XBWDL]?\d+(\.\d+)*/
    | /[A-Za-z_]\w*(\s*\[[^\]]*\])?(\s*\.\s*[A-Za-z_]\w*(\s*\[[^\]]*\])?)*/
%ignore /\s+/
"""

# what the parser's terminals mean, for "expected ..." in an error message
_TERMINALS = {"OR": "OR", "XOR": "XOR", "AND": "AND", "NOT": "NOT", "EQ": "= or <>", "CMP": "a comparison",
              "ADD": "+ or -", "MUL": "*, / or MOD", "POW": "**", "LPAR": "(", "RPAR": ")", "$END": "the end"}
_OPERANDS = {"PATH", "INT", "REAL", "BASED", "DURATION", "TYPED", "STRING", "TRUE", "FALSE"}
_TIME_UNITS = {"d": 86_400_000_000_000, "h": 3_600_000_000_000, "m": 60_000_000_000, "s": 1_000_000_000,
               "ms": 1_000_000, "us": 1_000, "ns": 1}
_TIME_PART = re.compile(r"(\d+(?:\.\d+)?)(ms|us|ns|d|h|m|s)", re.I)
_INTEGER_TYPES = {"SINT", "INT", "DINT", "LINT", "USINT", "UINT", "UDINT", "ULINT", "BYTE", "WORD", "DWORD",
                  "LWORD", "TIME", "DATE", "TOD", "DT"}      # TIME and the dates read as integer nanoseconds
_REAL_TYPES = {"REAL", "LREAL"}


class ConditionError(ValueError):
    """A condition that cannot be parsed, names an unknown variable or mixes types; says where."""

    def __init__(self, text: str, column: int, message: str):
        self.text, self.column, self.message = text, column, message
        super().__init__(f"condition {text!r}, column {column}: {message}\n    {text}\n    {' ' * (column - 1)}^")


@dataclass
class Condition:
    test: Callable[[], bool]
    text: str
    paths: list[str] = field(default_factory=list)      # IEC paths it reads (shown on failure)


@dataclass
class _Typed:
    """A compiled sub-expression: its evaluator and its IEC type class (BOOL, INT, REAL, ENUM, STRING or ANY)."""
    fn: Callable[[], Any]
    kind: str
    names: tuple = ()                                   # ENUM: the type's value names
    bare: str | None = None                             # a lone identifier: maybe an enum value


@lru_cache(maxsize=1)
def _parser() -> Lark:
    return Lark(GRAMMAR, parser="lalr", propagate_positions=True, maybe_placeholders=False)


def parse(text: str) -> Tree | Token:
    """The syntax tree of a condition; ConditionError (with the column) when it is not one."""
    try:
        return _parser().parse(text)
    except UnexpectedInput as exc:
        raise ConditionError(text, *_describe(text, exc)) from None


def _describe(text: str, exc: UnexpectedInput) -> tuple[int, str]:
    if isinstance(exc, UnexpectedEOF) or (isinstance(exc, UnexpectedToken) and exc.token.type == "$END"):
        expected = getattr(exc, "expected", None) or getattr(exc, "accepts", None) or ()
        return len(text.rstrip()) + 1, f"the condition ends too early (expected {_expected(expected)})"
    if isinstance(exc, UnexpectedCharacters):
        return exc.column, f"unexpected character {text[exc.pos_in_stream]!r}"
    tok = exc.token
    return tok.column, f"unexpected {tok.value!r} (expected {_expected(exc.accepts or exc.expected)})"


def _expected(names) -> str:
    names = set(names)
    out = ["an operand"] if names & _OPERANDS else []
    out += sorted({_TERMINALS.get(n, n) for n in names - _OPERANDS})
    return ", ".join(out) or "nothing"


def condition(plc: Plc, cond: str | Callable[[], Any], what: str | None = None) -> Condition:
    """A condition from IEC text (module docstring) or a callable; the text is checked against the PLC's
    variables now, so an error shows before any scan."""
    if callable(cond):
        return Condition(lambda: bool(cond()), what or _source_of(cond))
    text = cond.strip()
    comp = _Compiler(plc, text)
    top = comp.compile(parse(text))
    if top.kind not in ("BOOL", "ANY"):
        raise ConditionError(text, 1, f"the condition is {top.kind}, not BOOL (compare it, e.g. ... <> 0)")
    fn = top.fn                       # a BOOL expression's evaluator returns a bool already
    return Condition(fn if top.kind == "BOOL" else (lambda: bool(fn())), what or text, comp.paths)


# ---- the compiler: syntax tree -> typed closures ---------------------------------------------------------

def _trunc_div(a: int, b: int) -> int:
    q = abs(a) // abs(b)
    return q if (a < 0) == (b < 0) else -q


_ARITH = {"+": lambda a, b: a + b, "-": lambda a, b: a - b, "*": lambda a, b: a * b, "**": lambda a, b: a ** b}
_COMPARE = {"=": lambda a, b: a == b, "==": lambda a, b: a == b, "<>": lambda a, b: a != b,
            "!=": lambda a, b: a != b, "<": lambda a, b: a < b, ">": lambda a, b: a > b,
            "<=": lambda a, b: a <= b, ">=": lambda a, b: a >= b}
_LOGIC = {"AND": lambda a, b: a & b, "&": lambda a, b: a & b, "OR": lambda a, b: a | b,
          "XOR": lambda a, b: a ^ b}
_NUMERIC = ("INT", "REAL", "ANY")


class _Compiler:
    def __init__(self, plc: Plc, text: str):
        self.plc, self.text = plc, text
        self.paths: list[str] = []

    def fail(self, column: int, message: str):
        raise ConditionError(self.text, column, message)

    def compile(self, node: Tree | Token) -> _Typed:
        if isinstance(node, Token):
            return self.operand(node)
        if node.data == "unop":
            return self.unop(node.children[0], self.compile(node.children[1]))
        left, op, right = node.children
        a, b = self.compile_pair(left, right, op)
        return self.binop(op, a, b)

    def compile_pair(self, left, right, op: Token) -> tuple[_Typed, _Typed]:
        """Both operands; in a comparison, a lone identifier beside an enum is that enum's value if it names one."""
        if op.type not in ("EQ", "CMP"):
            return self.compile(left), self.compile(right)
        bare_l, bare_r = _is_bare(left), _is_bare(right)
        if bare_l and not bare_r:
            b = self.compile(right)
            return self.enum_or_operand(left, b), b
        a = self.compile(left)
        return a, (self.enum_or_operand(right, a) if bare_r else self.compile(right))

    def enum_or_operand(self, tok: Token, other: _Typed) -> _Typed:
        name = str(tok).upper()
        if other.kind == "ENUM" and name in {n.upper() for n in other.names}:
            value = next(n for n in other.names if n.upper() == name)
            return _Typed(lambda: value, "ENUM", other.names)
        try:
            return self.operand(tok)
        except ConditionError as exc:
            if other.kind != "ENUM":
                raise
            self.fail(exc.column, f"{tok} is neither a variable nor a value of the enum ({_names(other)})")

    # -- operands --------------------------------------------------------------------------------------------
    def operand(self, tok: Token) -> _Typed:
        kind, s = tok.type, str(tok)
        if kind in ("TRUE", "FALSE"):
            v = kind == "TRUE"
            return _Typed(lambda: v, "BOOL")
        if kind == "INT":
            v = int(s.replace("_", ""))
            return _Typed(lambda: v, "INT")
        if kind == "REAL":
            f = float(s.replace("_", ""))
            return _Typed(lambda: f, "REAL")
        if kind == "BASED":
            base, digits = s.split("#", 1)
            v = int(digits.replace("_", ""), int(base))
            return _Typed(lambda: v, "INT")
        if kind == "DURATION":
            ns = self.duration(tok)
            return _Typed(lambda: ns, "INT")
        if kind == "STRING":
            v = s[1:-1] if s[0] == '"' else re.sub(r"\$(.)", r"\1", s[1:-1])
            return _Typed(lambda: v, "STRING")
        if kind == "TYPED":
            return self.typed(tok)
        return self.variable(tok)

    def duration(self, tok: Token) -> int:
        body = str(tok).split("#", 1)[1].replace("_", "")
        sign = -1 if body.startswith("-") else 1
        body = body.lstrip("-")
        parts = _TIME_PART.findall(body)
        if not parts or "".join(n + u for n, u in parts).lower() != body.lower():
            self.fail(tok.column, f"{tok}: not a duration (e.g. T#1s500ms, T#20ms)")
        return sign * round(sum(float(n) * _TIME_UNITS[u.lower()] for n, u in parts))

    def typed(self, tok: Token) -> _Typed:
        type_name, value = str(tok).split("#", 1)
        t = type_name.upper()
        if t == "BOOL" and value.upper() in ("TRUE", "FALSE", "0", "1"):
            v = value.upper() in ("TRUE", "1")
            return _Typed(lambda: v, "BOOL")
        if t in _INTEGER_TYPES or t in _REAL_TYPES:
            sign = -1 if value.startswith("-") else 1                  # INT#-5
            try:
                inner = _parser().parse(value.lstrip("+-"))
            except UnexpectedInput:
                inner = None
            if not (isinstance(inner, Token) and inner.type in ("INT", "REAL", "BASED")):
                self.fail(tok.column, f"{tok}: not a {t} literal")
            v = sign * self.operand(inner).fn()
            return _Typed(lambda: v, "REAL" if t in _REAL_TYPES else "INT")
        return _Typed(lambda: value, "ENUM", (value,))       # an enum value; the other side checks its type

    def variable(self, tok: Token) -> _Typed:
        path = re.sub(r"\s+", "", str(tok))
        try:
            var = self.plc.var(path)
        except Exception as exc:  # noqa: BLE001 - the resolver's own message, placed in the condition
            raise ConditionError(self.text, tok.column, f"{exc.args[0] if exc.args else exc}") from None
        if path not in self.paths:
            self.paths.append(path)
        getter = getattr(type(var), "value", None)
        fn = (partial(getter.fget, var) if isinstance(getter, property)       # the bound accessor's getter,
              else lambda: var.value)                                           # called from C: no lookup
        vtype = str(getattr(var, "type", "")).upper()
        names = tuple(getattr(var, "_names", ()) or getattr(getattr(var, "_info", None), "values", None) or ())
        bare = path if "." not in path and "[" not in path else None
        if names:
            return _Typed(fn, "ENUM", names, bare)
        if vtype == "BOOL":
            return _Typed(fn, "BOOL", bare=bare)
        if vtype in _INTEGER_TYPES:
            return _Typed(fn, "INT", bare=bare)
        if vtype in _REAL_TYPES:
            return _Typed(fn, "REAL", bare=bare)
        if vtype == "STRING":
            return _Typed(fn, "STRING", bare=bare)
        return _Typed(fn, "ANY", bare=bare)

    # -- operators ---------------------------------------------------------------------------------------
    def unop(self, op: Token, a: _Typed) -> _Typed:
        f = a.fn
        if op.type == "NOT":
            if a.kind not in ("BOOL", "ANY"):
                self.fail(op.column, f"NOT takes a BOOL, not {a.kind} (NOT binds before comparisons: "
                                     "write NOT (A = B))")
            return _Typed(lambda: not f(), "BOOL")
        if a.kind not in _NUMERIC:
            self.fail(op.column, f"unary {op} takes a number, not {a.kind}")
        return _Typed((lambda: -f()) if str(op) == "-" else f, a.kind)

    def binop(self, op: Token, a: _Typed, b: _Typed) -> _Typed:
        fa, fb, o, col = a.fn, b.fn, str(op).upper(), op.column
        kinds = {a.kind, b.kind} - {"ANY"}
        if op.type in ("OR", "XOR", "AND"):
            if kinds <= {"BOOL"}:
                g = _LOGIC[o]
                return _Typed(lambda: bool(g(bool(fa()), bool(fb()))), "BOOL")
            if kinds <= {"INT"}:                                  # bit-wise on ANY_BIT / integers
                g = _LOGIC[o]
                return _Typed(lambda: g(fa(), fb()), "INT")
            self.fail(col, f"{o} takes two BOOLs or two integers, not {a.kind} and {b.kind}")
        if op.type in ("EQ", "CMP"):
            self.check_comparable(op, a, b)
            g = _COMPARE[o]
            return _Typed(lambda: g(fa(), fb()), "BOOL")
        if not kinds <= {"INT", "REAL"}:
            self.fail(col, f"{o} takes numbers, not {a.kind} and {b.kind}")
        kind = "REAL" if "REAL" in kinds else ("INT" if kinds == {"INT"} else "ANY")
        if o == "/":
            return _Typed(lambda: self.divide(fa(), fb(), col), kind)
        if o == "MOD":
            if "REAL" in kinds:
                self.fail(col, "MOD takes integers")
            return _Typed(lambda: self.modulo(fa(), fb(), col), kind)
        g = _ARITH[o]
        return _Typed(lambda: g(fa(), fb()), kind)

    def check_comparable(self, op: Token, a: _Typed, b: _Typed) -> None:
        kinds = {a.kind, b.kind} - {"ANY"}
        if len(kinds) <= 1 or kinds <= {"INT", "REAL"} or kinds <= {"ENUM", "STRING"}:
            if "ENUM" in kinds and op.type == "CMP":
                self.fail(op.column, f"{op}: enum values compare with = and <> only")
            if kinds == {"ENUM"} and a.names and b.names and not set(a.names) & set(b.names):
                self.fail(op.column, f"{op}: enum values of different types ({_names(a)} vs {_names(b)})")
            return
        hint = ""
        for side, other in ((a, b), (b, a)):
            if side.bare and other.kind == "ENUM":
                hint = f" ({side.bare} is not a value of the enum: {_names(other)})"
        self.fail(op.column, f"{op} compares {a.kind} with {b.kind}{hint}")

    def divide(self, x, y, col):
        if y == 0:
            raise ZeroDivisionError(f"condition {self.text!r}, column {col}: division by zero")
        if isinstance(x, int) and isinstance(y, int):          # IEC: integer / truncates toward zero
            return _trunc_div(x, y)
        return x / y

    def modulo(self, x, y, col):
        if y == 0:
            raise ZeroDivisionError(f"condition {self.text!r}, column {col}: MOD by zero")
        return x - y * _trunc_div(x, y)


def _is_bare(node) -> bool:
    return isinstance(node, Token) and node.type == "PATH" and re.fullmatch(r"[A-Za-z_]\w*", str(node)) is not None


def _names(t: _Typed) -> str:
    return ", ".join(t.names[:8]) + (", ..." if len(t.names) > 8 else "")


def _source_of(fn: Callable) -> str:
    try:
        text = inspect.getsource(fn).strip()
    except (OSError, TypeError):
        return getattr(fn, "__qualname__", repr(fn))
    m = re.search(r"lambda\s*:\s*", text)
    if not m:
        return " ".join(text.split())
    body, depth, quote = [], 0, ""
    for ch in text[m.end():]:                              # the lambda's body: up to a top-level , or )
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch in "([{":
            depth += 1
        elif ch in ")]}":
            if depth == 0:
                break
            depth -= 1
        elif ch == "," and depth == 0:
            break
        body.append(ch)
    return " ".join("".join(body).split())
