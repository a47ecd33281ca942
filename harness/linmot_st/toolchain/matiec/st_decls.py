"""The ST *declarations* the MatIEC backend needs beyond iec2c's output, read with the builtin parser.

iec2c's C drops two facts the manifest needs: array lower bounds (`ARRAY[1..4] OF BYTE` becomes
`__ARRAY_OF_BYTE_4`, indexed `[i - 1]` at each use) and which ST type name a variable was declared with;
and it does not say where each POU starts in the ST files. These come from the builtin compiler's parser
(syntax only: its checker is not run, so iec2c stays the authority on what the sources mean) and are
reduced here to the few facts the manifest needs: TYPE declarations, the variables of each POU, the
CONFIGURATION and RESOURCE globals, and where each POU starts.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from ..builtin import ast as A


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


def _spec(node) -> TypeSpec:
    """The manifest-relevant shape of a type specification node of the builtin AST."""
    if isinstance(node, A.NamedSpec):
        name = node.name.upper()
        return TypeSpec("string", name=name) if name in ("STRING", "WSTRING") else TypeSpec("name", name=name)
    if isinstance(node, A.StringLenSpec):
        return TypeSpec("string", name=node.base.upper())
    if isinstance(node, A.ArraySpec):
        # a non-literal bound is rejected by iec2c, so it never reaches the manifest
        dims = [(lo if isinstance(lo, int) else 0, hi if isinstance(hi, int) else 0) for lo, hi in node.ranges]
        return TypeSpec("array", dims=dims, elem=_spec(node.elem))
    if isinstance(node, A.StructSpec):
        return TypeSpec("struct", fields={f.name.upper(): _spec(f.spec) for f in node.fields})
    if isinstance(node, A.EnumSpec):
        return TypeSpec("enum", values=[v.upper() for v, _ in node.values])
    if isinstance(node, A.SubrangeSpec):
        return TypeSpec("subrange", name=node.base.upper())
    return TypeSpec("name", name=getattr(node, "what", "").upper())


def _vars(blocks, target: dict[str, TypeSpec]) -> None:
    for block in blocks:
        for decl in block.decls:
            spec = _spec(decl.spec)
            for name, _pos in decl.names:
                target[name.upper()] = spec


def scan(files: list[tuple[str, str]]) -> Declarations:
    """Declarations of the given (name, text) sources, in order (included files are given separately)."""
    from ..builtin.parser import parse  # lark loads on first use: `linmot-st --help` imports this module

    decls = Declarations()
    for name, text in files:
        for node in parse(text, name):
            if isinstance(node, A.TypeBlock):
                for t in node.decls:
                    decls.types[t.name.upper()] = _spec(t.spec)
            elif isinstance(node, A.Pou):
                pou = Pou(node.kind, node.name.upper(), name, node.pos.line)
                _vars(node.blocks, pou.vars)
                decls.pous[pou.name] = pou
            elif isinstance(node, A.Configuration):
                config = node.name.upper()
                _vars(node.globals, decls.globals.setdefault(config, {}))
                for res in node.resources:
                    _vars(res.globals, decls.globals.setdefault(f"{config}.{res.name.upper()}", {}))
    return decls


def scan_paths(paths: list[Path], root: Path, search: list[Path] = ()) -> Declarations:
    from ..builtin.loader import display_name, read_source  # (the parser: lark, on first use)
    return scan([(display_name(p, root, search), read_source(p)) for p in paths])
