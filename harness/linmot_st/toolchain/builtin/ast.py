"""The syntax tree of a Structured Text compilation unit, as the parser builds it.

Names are kept as written (`name`) and compared upper-cased (`key`). The checker annotates expression
nodes in place (`ty`, and `sym`/`call` where they resolve to something) for the code generator.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, NamedTuple


class Pos(NamedTuple):
    file: str
    line: int
    col: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.col}"


@dataclass(eq=False)
class Node:
    pos: Pos


# ------------------------------------------------------------------ type specifications

@dataclass(eq=False)
class NamedSpec(Node):
    name: str


@dataclass(eq=False)
class ArraySpec(Node):
    ranges: list[tuple[Any, Any]]          # (lo, hi): ints, or Name nodes (rejected by the checker)
    elem: Node
    star: bool = False                     # ARRAY[*]


@dataclass(eq=False)
class StructSpec(Node):
    fields: list[StructField]


@dataclass(eq=False)
class StructField(Node):
    name: str
    spec: Node
    init: Node | None


@dataclass(eq=False)
class EnumSpec(Node):
    values: list[tuple[str, Pos]]
    explicit: bool = False                 # (A := 1, ...): outside the subset


@dataclass(eq=False)
class SubrangeSpec(Node):
    base: str
    lo: int
    hi: int


@dataclass(eq=False)
class StringLenSpec(Node):
    base: str
    length: int


@dataclass(eq=False)
class UnsupportedSpec(Node):
    what: str                              # "POINTER TO", "REF_TO"


# ------------------------------------------------------------------ initial values

@dataclass(eq=False)
class ArrayInit(Node):
    items: list[tuple[int, Node | None]]   # (repeat count, value or None for the default)
    ints: Any = None                       # a bulkinit.BulkInts instead of items: a long list of plain literals

    def entries(self) -> list[tuple[int, Node | None]]:
        """`items`, or, for a list read by bulkinit, its literals as items (each at its own position)."""
        return self.items if self.ints is None else self.ints.items(self.pos.file)


@dataclass(eq=False)
class StructInit(Node):
    items: list[tuple[str, Pos, Node]]


# ------------------------------------------------------------------ declarations

@dataclass(eq=False)
class TypeDecl(Node):
    name: str
    spec: Node
    init: Node | None


@dataclass(eq=False)
class VarDecl(Node):
    names: list[tuple[str, Pos]]
    spec: Node
    init: Node | None
    location: str | None = None            # "%IX0.1"
    edge: str | None = None                # R_EDGE/F_EDGE: outside the subset


@dataclass(eq=False)
class VarBlock(Node):
    kind: str                              # VAR, VAR_INPUT, VAR_OUTPUT, VAR_IN_OUT, VAR_TEMP, VAR_GLOBAL, VAR_EXTERNAL, ...
    qualifier: str | None                  # CONSTANT, RETAIN, NON_RETAIN
    decls: list[VarDecl]


@dataclass(eq=False)
class Pou(Node):
    kind: str                              # FUNCTION, FUNCTION_BLOCK, PROGRAM
    name: str
    return_spec: Node | None
    blocks: list[VarBlock]
    body: list[Node]
    end_pos: Pos | None = None
    std: bool = False                      # part of the builtin standard library


@dataclass(eq=False)
class TaskDecl(Node):
    name: str
    params: list[tuple[str, Pos, Node]]


@dataclass(eq=False)
class ProgramConfig(Node):
    name: str
    task: str | None
    type_name: str
    type_pos: Pos
    bindings: list[tuple[str, Pos, str, Node]]   # (param, pos, ":=" or "=>", expression)


@dataclass(eq=False)
class Resource(Node):
    name: str
    on: str
    globals: list[VarBlock]
    tasks: list[TaskDecl]
    programs: list[ProgramConfig]
    implicit: bool = False     # tasks and programs written directly in the CONFIGURATION (no RESOURCE)


@dataclass(eq=False)
class Configuration(Node):
    name: str
    globals: list[VarBlock]
    resources: list[Resource]


@dataclass(eq=False)
class TypeBlock(Node):
    decls: list[TypeDecl]


@dataclass(eq=False)
class Pragma(Node):
    text: str


# ------------------------------------------------------------------ statements

@dataclass(eq=False)
class Assign(Node):
    target: Node
    value: Node


@dataclass(eq=False)
class CallStmt(Node):
    call: Call


@dataclass(eq=False)
class If(Node):
    branches: list[tuple[Node, list[Node]]]
    else_body: list[Node] | None


@dataclass(eq=False)
class CaseLabel(Node):
    lo: Node                               # a Literal or Name
    hi: Node | None                        # for a range


@dataclass(eq=False)
class Case(Node):
    selector: Node
    elements: list[tuple[list[CaseLabel], list[Node]]]
    else_body: list[Node] | None


@dataclass(eq=False)
class For(Node):
    var: Name
    start: Node
    end: Node
    step: Node | None
    body: list[Node]


@dataclass(eq=False)
class While(Node):
    cond: Node
    body: list[Node]


@dataclass(eq=False)
class Repeat(Node):
    body: list[Node]
    cond: Node


@dataclass(eq=False)
class Exit(Node):
    pass


@dataclass(eq=False)
class Continue(Node):
    pass


@dataclass(eq=False)
class Return(Node):
    pass


@dataclass(eq=False)
class PragmaStmt(Node):
    text: str


# ------------------------------------------------------------------ expressions

@dataclass(eq=False)
class Expr(Node):
    ty: Any = field(default=None, init=False, repr=False)       # set by the checker
    paren: int = field(default=0, init=False, repr=False)        # how many parentheses enclose it


@dataclass(eq=False)
class Literal(Expr):
    kind: str              # int, real, bool, string, wstring, time, date, tod, dt
    value: Any             # int, float (real text kept in `text`), bool, bytes, int (ns / s)
    type_name: str | None = None     # typed literal prefix (upper case), e.g. INT#5
    text: str = ""


@dataclass(eq=False)
class EnumLit(Expr):
    type_name: str | None  # E#RUN
    value: str


@dataclass(eq=False)
class Name(Expr):
    name: str
    sym: Any = field(default=None, init=False, repr=False)


@dataclass(eq=False)
class Member(Expr):
    base: Node
    name: str
    name_pos: Pos = None


@dataclass(eq=False)
class Index(Expr):
    base: Node
    indices: list[Node]


@dataclass(eq=False)
class BitAccess(Expr):
    base: Node
    bit: str


@dataclass(eq=False)
class Deref(Expr):
    base: Node


@dataclass(eq=False)
class DirectVar(Expr):
    location: str


@dataclass(eq=False)
class Arg(Node):
    name: str | None       # formal name, None for a positional argument
    value: Node            # expression, or a variable for an output
    output: bool = False   # =>
    negated: bool = False  # NOT x => y


@dataclass(eq=False)
class Call(Expr):
    name: str
    args: list[Arg]
    target: Any = field(default=None, init=False, repr=False)   # resolved callee (checker)


@dataclass(eq=False)
class BinOp(Expr):
    op: str                # OR XOR AND = <> < > <= >= + - * / MOD **
    left: Node
    right: Node


@dataclass(eq=False)
class UnOp(Expr):
    op: str                # NEG NOT
    operand: Node


def key(name: str) -> str:
    """Identifiers are case-insensitive: compare them upper-cased."""
    return name.upper()
