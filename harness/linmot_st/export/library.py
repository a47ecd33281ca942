"""What an ST entry file declares, read with the builtin compiler's front end, plus what an export needs
beyond the syntax tree: the original text of every POU body (comments kept) and the comments that
document POUs, types, struct fields and variables.

The declarations come from the compiler's loader (includes expanded in order) and are checked by its
checker, so an export is only ever made of a library that compiles. Source spans come from the
compiler's own lexer run over each file with comments kept: a POU body is the text between the
`END_VAR` that closes its last declaration block and its `END_FUNCTION`/`END_FUNCTION_BLOCK`/
`END_PROGRAM`. Documentation is the comment on the line of a declaration's `;` (after it), or the
comments on the lines just above it; a POU's is the comments between its name and its first VAR block.
"""

from __future__ import annotations

import bisect
import textwrap
from dataclasses import dataclass, field
from pathlib import Path

from linmot_st import resources
from linmot_st.toolchain import sources as _sources
from linmot_st.toolchain.builtin import ast as A
from linmot_st.toolchain.builtin.checker import Checker
from linmot_st.toolchain.builtin.errors import BuiltinCompileError
from linmot_st.toolchain.builtin.loader import load, read_source
from linmot_st.toolchain.builtin.parser import tokens  # the compiler's own lexer

END_KEYWORDS = {"FUNCTION": "END_FUNCTION", "FUNCTION_BLOCK": "END_FUNCTION_BLOCK", "PROGRAM": "END_PROGRAM"}


class ExportError(Exception):
    """The library cannot be read or exported; the message says why (compiler diagnostics included)."""


@dataclass
class Documented:
    node: A.Node
    doc: str | None = None


@dataclass
class TypeEntry:
    decl: A.TypeDecl
    doc: str | None
    field_docs: dict[int, str] = field(default_factory=dict)   # id(StructField) -> comment


@dataclass
class PouEntry:
    pou: A.Pou
    body: str                      # the body's ST text as written (comments kept), dedented
    doc: str | None
    var_docs: dict[int, str] = field(default_factory=dict)     # id(VarDecl) -> comment
    declarations: str = ""         # the POU's header and declaration blocks as written (up to the last END_VAR)


@dataclass
class Library:
    entry: Path
    root: Path
    files: list[Path]              # read order: the entry first, then each include as reached
    names: list[str]               # the same, relative to the include root
    elements: list[A.Node]         # the compiler's declarations, includes expanded, in order
    types: list[TypeEntry]
    pous: list[PouEntry]
    configurations: list[A.Configuration]
    search: list[Path] = field(default_factory=list)    # folders searched for includes before the root

    @property
    def counts(self) -> dict[str, int]:
        kinds = [p.pou.kind for p in self.pous]
        return {"types": len(self.types), "functions": kinds.count("FUNCTION"),
                "function_blocks": kinds.count("FUNCTION_BLOCK"), "programs": kinds.count("PROGRAM"),
                "configurations": len(self.configurations)}


def default_entry(cwd: Path | None = None) -> Path:
    """st_lib/linmot.st of the nearest folder (cwd or an ancestor) that holds it, else the one this
    linmot-st comes with (linmot_st.resources)."""
    here = (cwd or Path.cwd()).resolve()
    for folder in [here, *here.parents]:
        if (folder / _sources.LIBRARY_MARKER).is_file():
            return folder / _sources.LIBRARY_MARKER
    try:
        return resources.library_tree() / _sources.LIBRARY_MARKER
    except resources.LibraryNotFound as exc:
        raise ExportError(str(exc)) from None


def read_library(entry: str | Path | None = None, check: bool = True) -> Library:
    """Load, check and index an ST entry file and its includes. Raises ExportError."""
    try:
        path = _sources.resolve_entry(entry if entry is not None else default_entry())
    except _sources.SourceError as exc:
        raise ExportError(str(exc)) from None
    root = _sources.include_root(path)
    search = _sources.library_search(root)
    try:
        elements, files, names = load(path, root, search)
        if check:
            Checker().check(elements, names)
    except BuiltinCompileError as exc:
        raise ExportError(f"{names_or(path, root)} does not compile:\n{exc}") from None

    texts = {name: _FileIndex(read_source(f)) for f, name in zip(files, names)}
    lib = Library(path, root, list(files), list(names), elements, [], [], [], search)
    for el in elements:
        if isinstance(el, A.TypeBlock):
            for decl in el.decls:
                ix = texts[decl.pos.file]
                entry_ = TypeEntry(decl, ix.doc_of(decl.pos))
                if isinstance(decl.spec, A.StructSpec):
                    _struct_docs(decl.spec, ix, entry_.field_docs)
                lib.types.append(entry_)
        elif isinstance(el, A.Pou):
            lib.pous.append(_pou_entry(el, texts[el.pos.file]))
        elif isinstance(el, A.Configuration):
            lib.configurations.append(el)
    return lib


def names_or(path: Path, root: Path) -> str:
    return _sources.rel_name(path, root)


def _struct_docs(spec: A.StructSpec, ix: _FileIndex, out: dict[int, str]) -> None:
    for f in spec.fields:
        doc = ix.doc_of(f.pos)
        if doc:
            out[id(f)] = doc
        if isinstance(f.spec, A.StructSpec):
            _struct_docs(f.spec, ix, out)


def _pou_entry(pou: A.Pou, ix: _FileIndex) -> PouEntry:
    i = ix.at(pou.pos)                      # the POU's name
    toks = ix.tokens
    end_kw = END_KEYWORDS[pou.kind]
    # the header ends with the END_VAR of the last declaration block (or with the name / return type)
    head_end = i
    if pou.blocks:
        left = len(pou.blocks)
        j = i
        while left:
            j += 1
            if toks[j].type == "END_VAR":
                left -= 1
        head_end = j
    elif isinstance(pou.return_spec, A.NamedSpec):
        head_end = ix.at(pou.return_spec.pos)
    j = head_end + 1
    while toks[j].type != end_kw:
        j += 1
    body = ix.text[toks[head_end].end_pos:toks[j].start_pos]
    body = _strip_blank_edges(body)

    # documentation: the comments between the name (or return type) and the first declaration block
    first_block = ix.at(pou.blocks[0].pos) if pou.blocks else head_end + 1
    start = ix.at(pou.return_spec.pos) if isinstance(pou.return_spec, A.NamedSpec) else i
    docs = [ix.comment_text(t) for t in toks[start + 1:first_block] if t.type == "COMMENT"]
    keyword = i - 1
    var_docs = {}
    for block in pou.blocks:
        for decl in block.decls:
            d = ix.doc_of(decl.pos)
            if d:
                var_docs[id(decl)] = d
    declarations = ix.text[toks[keyword].start_pos:toks[head_end].end_pos]
    return PouEntry(pou, body, "\n".join(docs) or None, var_docs, declarations)


def _strip_blank_edges(text: str) -> str:
    lines = text.split("\n")
    while lines and not lines[0].strip():
        lines.pop(0)
    while lines and not lines[-1].strip():
        lines.pop()
    return textwrap.dedent("\n".join(line.rstrip() for line in lines)) + "\n" if lines else ""


class _FileIndex:
    """One source file's tokens (the compiler's lexer, comments kept), addressable by line and column."""

    def __init__(self, text: str):
        self.text = text
        self.tokens = tokens(text)
        self._starts = [(t.line, t.column) for t in self.tokens]

    def at(self, pos: A.Pos) -> int:
        k = bisect.bisect_left(self._starts, (pos.line, pos.col))
        if k >= len(self.tokens) or self._starts[k] != (pos.line, pos.col):
            raise ExportError(f"{pos}: no token starts here (the lexer and the parser disagree)")
        return k

    def comment_text(self, tok) -> str:
        first, *rest = str(tok)[2:-2].split("\n")
        rest = textwrap.dedent("\n".join(rest)).rstrip()
        return "\n".join(x for x in (first.strip(), rest) if x).strip()

    def _decl_end(self, k: int) -> int:
        """Index of the `;` that ends the declaration starting at token k."""
        depth = 0
        toks = self.tokens
        while k < len(toks):
            t = toks[k].type
            if t in ("LPAR", "LSQB", "STRUCT"):
                depth += 1
            elif t in ("RPAR", "RSQB", "END_STRUCT"):
                depth -= 1
            elif t == "SEMICOLON" and depth == 0:
                return k
            k += 1
        return k - 1

    def doc_of(self, pos: A.Pos) -> str | None:
        toks = self.tokens
        k = self.at(pos)
        parts = []
        # comments on their own lines just above the declaration
        above = []
        j = k - 1
        while j >= 0 and toks[j].type == "COMMENT" and (j == 0 or toks[j - 1].end_line < toks[j].line) \
                and toks[j].end_line >= toks[j + 1].line - 1:
            above.insert(0, self.comment_text(toks[j]))
            j -= 1
        parts += above
        # the comment after the `;` on the same line
        end = self._decl_end(k)
        if end + 1 < len(toks) and toks[end + 1].type == "COMMENT" and toks[end + 1].line == toks[end].end_line:
            parts.append(self.comment_text(toks[end + 1]))
        parts = [p for p in parts if p]
        return "\n".join(parts) or None
