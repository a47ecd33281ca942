"""The project's own IEC 61131-3 Structured Text -> C compiler ("builtin" backend).

Entry point for the build driver (linmot_st.toolchain):

    from linmot_st.toolchain.builtin import compile_to_c, BuiltinCompileError, backend_version

    out = compile_to_c(entry_file: Path, include_root: Path, out_dir: Path) -> BuiltinOutput
        out.c_files   list[Path]  the translation units to compile (plc_builtin.c, plc_builtin1.c, ...: one
                                  or more by size, units.py); each #includes plc_builtin.h, which
                                  #includes out.header; both sit next to them in out_dir (no -I needed)
        out.header    Path        builtin_rt.h, copied into out_dir
        out.manifest  Path        out_dir/manifest.json (docs/architecture.md 1.1)
        out.sources   list[Path]  every ST file read: the entry file first, then the {#include}d files
    raises BuiltinCompileError(diagnostics) on rejected sources: `.diagnostics` is a list of Diagnostic,
    each `str()`s as `file:line:col: error: message`; `str(exc)` is all of them, one per line.
    File names in diagnostics are relative to include_root where the file lies under it.

    backend_version() -> str      changes whenever this package's sources change (for the build cache)

The generated C provides config_init__, config_run__, common_ticktime__, greatest_tick_count__,
plc_root_addr and plc_type_size; it needs __CURRENT_TIME and plc_raise_fault from the glue, and -lm.

Pipeline: loader (files, includes) -> parser (lark, AST) -> checker (types, rules) -> codegen (C, manifest).
See docs/builtin-compiler.md.
"""

from __future__ import annotations

import functools
import hashlib
import json
import shutil
from dataclasses import dataclass
from pathlib import Path

from .errors import BuiltinCompileError, Diagnostic

__all__ = ["compile_to_c", "compile_text", "BuiltinCompileError", "BuiltinOutput", "Diagnostic", "backend_version"]

PACKAGE_DIR = Path(__file__).parent
RUNTIME_HEADER = PACKAGE_DIR / "builtin_rt.h"
C_FILE_NAME = "plc_builtin.c"      # the first unit; the others are plc_builtin1.c, plc_builtin2.c, ...


@dataclass
class BuiltinOutput:
    c_files: list[Path]
    header: Path
    manifest: Path
    sources: list[Path]


@functools.lru_cache(maxsize=1)
def backend_version() -> str:
    h = hashlib.sha256()
    for p in sorted(PACKAGE_DIR.rglob("*")):        # (the checker is a package of its own: checker/)
        if p.suffix in (".py", ".lark", ".h", ".json"):
            h.update(p.relative_to(PACKAGE_DIR).as_posix().encode())
            h.update(p.read_bytes())
    return "builtin-" + h.hexdigest()[:12]


def compile_to_c(entry_file: Path, include_root: Path, out_dir: Path, search: list[Path] = (),
                 line_directives: bool = False) -> BuiltinOutput:
    """Compile an ST entry file (and its includes) to C + manifest in out_dir; includes are looked up in
    `search`, then under include_root (iec2c's -I folder, then its working directory). `line_directives`:
    `#line` before each statement, as iec2c's `-O l` (coverage builds)."""
    from .loader import load
    entry_file, include_root, out_dir = Path(entry_file), Path(include_root), Path(out_dir)
    elements, sources, names = load(entry_file, include_root, search)
    header, units, manifest = _translate(elements, names, line_directives)
    return _write(header, units, manifest, out_dir, sources)


def compile_text(text: str, out_dir: Path, name: str = "input.st", line_directives: bool = False) -> BuiltinOutput:
    """Compile ST source given as text (tests, tools); `name` is the file name diagnostics use."""
    from .parser import parse
    elements = parse(text, name)
    header, units, manifest = _translate(elements, [name], line_directives)
    return _write(header, units, manifest, Path(out_dir), [])


def check_text(text: str, name: str = "input.st"):
    """Parse and check only; returns the checked Program (raises BuiltinCompileError)."""
    from .checker import Checker
    from .parser import parse
    return Checker().check(parse(text, name), [name])


def _translate(elements, names, line_directives: bool = False) -> tuple[str, list[str], dict]:
    from .checker import Checker
    from .codegen import CodeGen
    prog = Checker().check(elements, names)
    return CodeGen(prog, backend_version(), line_directives).generate_units()


def _write(header_text: str, units: list[str], manifest: dict, out_dir: Path, sources: list[Path]) -> BuiltinOutput:
    from .units import HEADER_NAME
    out_dir.mkdir(parents=True, exist_ok=True)
    (out_dir / HEADER_NAME).write_text(header_text)
    c_files = []
    for k, text in enumerate(units):
        c_files.append(out_dir / (C_FILE_NAME if k == 0 else C_FILE_NAME.replace(".c", f"{k}.c")))
        c_files[-1].write_text(text)
    header = out_dir / RUNTIME_HEADER.name
    shutil.copyfile(RUNTIME_HEADER, header)
    mpath = out_dir / "manifest.json"
    mpath.write_text(json.dumps(manifest, indent=1))
    return BuiltinOutput(c_files, header, mpath, sources)
