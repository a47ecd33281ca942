"""Read the entry file and the files it `{#include "path"}`s, in order, into one list of declarations.

Include paths resolve against the include root (docs/architecture.md 1), as iec2c resolves them
against its working directory. An include is allowed only between declarations (MatIEC's rule),
nests up to 16 deep like MatIEC's, and keeps its own file name and line numbers in diagnostics.
"""

from __future__ import annotations

from pathlib import Path

from ..sources import INCLUDE_PRAGMA, resolve_include
from . import ast as A
from .errors import BuiltinCompileError, Diagnostic
from .parser import parse

MAX_DEPTH = 16


def display_name(path: Path, root: Path, search: list[Path] = ()) -> str:
    """The path relative to the include root, else to the search folder it was found in (as iec2c names
    an included file by its include path), else absolute."""
    for folder in (root, *search):
        try:
            return path.resolve().relative_to(Path(folder).resolve()).as_posix()
        except ValueError:
            continue
    return str(path)


def read_source(path: Path) -> str:
    data = path.read_bytes()
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def load(entry: Path, root: Path, search: list[Path] = ()) -> tuple[list[A.Node], list[Path], list[str]]:
    """(declarations in order, files read, their display names). Includes are looked up in `search`
    first, then under `root` (sources.resolve_include). Raises BuiltinCompileError."""
    elements: list[A.Node] = []
    files: list[Path] = []
    names: list[str] = []
    diags: list[Diagnostic] = []

    def visit(path: Path, stack: list[Path], where: A.Pos | None) -> None:
        name = display_name(path, root, search)
        try:
            text = read_source(path)
        except OSError as exc:
            pos = where or A.Pos(name, 0, 0)
            diags.append(Diagnostic(pos.file, pos.line, pos.col, f"cannot read {name}: {exc.strerror or exc}"))
            return
        files.append(path)
        names.append(name)
        try:
            items = parse(text, name)
        except BuiltinCompileError as exc:
            diags.extend(exc.diagnostics)
            return
        for el in items:
            if isinstance(el, A.Pragma):
                m = INCLUDE_PRAGMA.fullmatch(el.text.strip())
                if m:
                    target = resolve_include(m.group(1), root, list(search))
                    if target is None:
                        diags.append(Diagnostic(el.pos.file, el.pos.line, el.pos.col,
                                                f'cannot find included file "{m.group(1)}" under {root}'))
                        continue
                    rt = target.resolve()
                    if rt in stack:
                        diags.append(Diagnostic(el.pos.file, el.pos.line, el.pos.col,
                                                f'"{m.group(1)}" includes itself (include cycle)'))
                        continue
                    if len(stack) >= MAX_DEPTH:
                        diags.append(Diagnostic(el.pos.file, el.pos.line, el.pos.col,
                                                f"includes nested more than {MAX_DEPTH} deep"))
                        continue
                    visit(target, stack + [rt], el.pos)
                    continue
            elements.append(el)

    visit(Path(entry), [Path(entry).resolve()], None)
    if diags:
        raise BuiltinCompileError(diags)
    return elements, files, names
