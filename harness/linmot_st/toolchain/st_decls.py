"""A scanner of ST *declarations* only, for what iec2c's output does not keep.

iec2c's C drops two facts the manifest needs: array lower bounds (`ARRAY[1..4] OF BYTE` becomes
`__ARRAY_OF_BYTE_4`, indexed `[i - 1]` at each use) and which ST type name a variable was declared with;
and it does not say where each POU starts in the ST files. This scanner reads TYPE blocks, the VAR
blocks of POUs, CONFIGURATION and RESOURCE globals, and POU headers. It skips POU bodies entirely and
checks nothing: the sources were already accepted by iec2c, which is the authority on their meaning.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path


@dataclass
class TypeSpec:
    kind: str                      # name | array | struct | enum | subrange | string
    name: str = ""                 # name: the referenced type (upper case); subrange: its base
    dims: list[tuple[int, int]] = field(default_factory=list)
    elem: TypeSpec | None = None
    fields: dict[str, TypeSpec] = field(default_factory=dict)
    values: list[str] = field(default_factory=list)


@dataclass
class Pou:
    kind: str                      # FUNCTION | FUNCTION_BLOCK | PROGRAM
    name: str
    file: str
    line: int
    vars: dict[str, TypeSpec] = field(default_factory=dict)


@dataclass
class Declarations:
    types: dict[str, TypeSpec] = field(default_factory=dict)
    pous: dict[str, Pou] = field(default_factory=dict)
    globals: dict[str, dict[str, TypeSpec]] = field(default_factory=dict)   # "CONFIG0" / "CONFIG0.RES0" -> vars

    def resolve(self, spec: TypeSpec | None, depth: int = 0) -> tuple[str, TypeSpec | None]:
        """Follow named aliases to the defining spec; returns (the last type name met, that spec)."""
        name = ""
        while spec is not None and spec.kind == "name" and spec.name in self.types and depth < 64:
            name, spec, depth = spec.name, self.types[spec.name], depth + 1
        return name, spec


_TOKEN = re.compile(r"""
    (?P<ws>\s+)
  | (?P<comment>\(\*)
  | (?P<pragma>\{)
  | (?P<string>'(?:\$.|[^'])*'|"(?:\$.|[^"])*")
  | (?P<loc>%[A-Za-z]*[0-9.]*)
  | (?P<num>[0-9][0-9_]*(?:\#[0-9A-Fa-f_]+)?(?:\.[0-9_]+)?(?:[eE][+-]?[0-9]+)?)
  | (?P<id>[A-Za-z_][A-Za-z0-9_]*(?:\#[A-Za-z0-9_.#:+-]+)?)
  | (?P<op>\.\.|:=|=>|[:;,\[\]().+\-*/<>=&^])
""", re.X)

VAR_KEYWORDS = {"VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_EXTERNAL", "VAR_GLOBAL", "VAR_TEMP",
                "VAR_ACCESS", "VAR_CONFIG"}
VAR_QUALIFIERS = {"CONSTANT", "RETAIN", "NON_RETAIN", "PERSISTENT"}
POU_END = {"FUNCTION": "END_FUNCTION", "FUNCTION_BLOCK": "END_FUNCTION_BLOCK", "PROGRAM": "END_PROGRAM"}


def tokenize(text: str) -> list[tuple[str, int]]:
    """(token, line) pairs; identifiers and keywords upper-cased; comments, pragmas and strings dropped
    (strings become the placeholder "'")."""
    out: list[tuple[str, int]] = []
    pos, line, n = 0, 1, len(text)
    while pos < n:
        m = _TOKEN.match(text, pos)
        if not m:
            pos += 1
            continue
        kind = m.lastgroup
        if kind == "comment":   # nested comments are counted (iec2c -n); plain ones end at the first *)
            depth, end = 1, m.end()
            while depth and end < n:
                if text.startswith("(*", end):
                    depth, end = depth + 1, end + 2
                elif text.startswith("*)", end):
                    depth, end = depth - 1, end + 2
                else:
                    end += 1
            line += text.count("\n", pos, end)
            pos = end
            continue
        if kind == "pragma":
            end = text.find("}", pos)
            end = n if end < 0 else end + 1
            line += text.count("\n", pos, end)
            pos = end
            continue
        tok = m.group()
        if kind != "ws":
            out.append(("'" if kind == "string" else tok.upper(), line))
        line += tok.count("\n")
        pos = m.end()
    return out


def _int(tok: str) -> int:
    tok = tok.replace("_", "")
    if "#" in tok:
        base, _, digits = tok.partition("#")
        return int(digits, int(base))
    return int(tok)


class _Parser:
    def __init__(self, tokens: list[tuple[str, int]], file: str, decls: Declarations):
        self.toks, self.i, self.file, self.decls = tokens, 0, file, decls

    def peek(self, k: int = 0) -> str:
        j = self.i + k
        return self.toks[j][0] if j < len(self.toks) else ""

    def next(self) -> str:
        tok = self.peek()
        self.i += 1
        return tok

    def skip_to(self, *stops: str) -> str:
        while self.i < len(self.toks) and self.peek() not in stops:
            self.i += 1
        return self.next()

    def run(self) -> None:
        while self.i < len(self.toks):
            tok, line = self.toks[self.i]
            self.i += 1
            if tok == "TYPE":
                self.type_block()
            elif tok in POU_END:
                self.pou(tok, line)
            elif tok == "CONFIGURATION":
                self.configuration()

    def type_block(self) -> None:
        while self.peek() and self.peek() != "END_TYPE":
            name = self.next()
            if self.next() != ":":
                self.skip_to(";", "END_TYPE")
                continue
            self.decls.types[name] = self.typespec()
            self.skip_to(";", "END_TYPE")
        self.next()

    def typespec(self) -> TypeSpec:
        tok = self.next()
        if tok == "ARRAY":
            dims = []
            if self.next() == "[":
                while True:
                    lo = self._signed()
                    self.next()   # ..
                    hi = self._signed()
                    dims.append((lo, hi))
                    if self.next() != ",":
                        break   # ]
            self.skip_to("OF")
            return TypeSpec("array", dims=dims, elem=self.typespec())
        if tok == "STRUCT":
            spec = TypeSpec("struct")
            while self.peek() and self.peek() != "END_STRUCT":
                names = [self.next()]
                while self.peek() == ",":
                    self.next()
                    names.append(self.next())
                if self.next() != ":":
                    self.skip_to(";", "END_STRUCT")
                    continue
                sub = self.typespec()
                for n in names:
                    spec.fields[n] = sub
                self.skip_to(";", "END_STRUCT")
            self.next()
            return spec
        if tok == "(":
            values = []
            while self.peek() and self.peek() != ")":
                t = self.next()
                if t != ",":
                    values.append(t)
            self.next()
            return TypeSpec("enum", values=values)
        if tok in ("STRING", "WSTRING"):
            if self.peek() in ("[", "("):
                self.skip_to("]", ")")
            return TypeSpec("string", name=tok)
        if self.peek() == "(":   # subrange INT(0..100)
            self.skip_to(")")
            return TypeSpec("subrange", name=tok)
        return TypeSpec("name", name=tok)

    def _signed(self) -> int:
        sign = 1
        while self.peek() in ("-", "+"):
            sign = -sign if self.next() == "-" else sign
        tok = self.next()
        try:
            return sign * _int(tok)
        except ValueError:
            return 0   # a non-literal bound: iec2c rejects those, so this is never reached on valid input

    def var_blocks(self, target: dict[str, TypeSpec], end: str) -> None:
        """Parse VAR blocks until `end`; everything else (the body) is skipped."""
        while self.peek() and self.peek() != end:
            if self.next() in VAR_KEYWORDS:
                self.var_block_body(target, end)
        self.next()

    def var_block_body(self, target: dict[str, TypeSpec], end: str) -> None:
        """The declarations after a VAR keyword, through its END_VAR."""
        while self.peek() in VAR_QUALIFIERS:
            self.next()
        while self.peek() and self.peek() not in ("END_VAR", end):
            names = [self.next()]
            while self.peek() == ",":
                self.next()
                names.append(self.next())
            if self.peek() == "AT":
                self.next()
                self.next()   # the location
            if self.next() != ":":
                self.skip_to(";", "END_VAR")
                continue
            spec = self.typespec()
            for n in names:
                target[n] = spec
            self.skip_to(";", "END_VAR")
        if self.peek() == "END_VAR":
            self.next()

    def pou(self, kind: str, line: int) -> None:
        name = self.next()
        pou = Pou(kind, name, self.file, line)
        self.decls.pous[name] = pou
        self.var_blocks(pou.vars, POU_END[kind])

    def configuration(self) -> None:
        config = self.next()
        scope = config
        while self.peek() and self.peek() != "END_CONFIGURATION":
            tok = self.next()
            if tok == "VAR_GLOBAL":
                self.var_block_body(self.decls.globals.setdefault(scope, {}), "END_CONFIGURATION")
            elif tok == "RESOURCE":
                scope = f"{config}.{self.next()}"
            elif tok == "END_RESOURCE":
                scope = config
        self.next()


def scan(files: list[tuple[str, str]]) -> Declarations:
    """Declarations of the given (name, text) sources, in order."""
    decls = Declarations()
    for name, text in files:
        _Parser(tokenize(text), name, decls).run()
    return decls


def scan_paths(paths: list[Path], root: Path) -> Declarations:
    from .sources import rel_name
    return scan([(rel_name(p, root), p.read_text(encoding="latin-1")) for p in paths])
