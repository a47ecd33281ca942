"""The builtin compiler as the build driver sees it (toolchain/backend.py's protocol)."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

from .. import (
    builtin,  # its compile_to_c looked up at each call (tests replace it)
    cc,
)
from ..backend import Generated, Rejected
from ..sources import Sources
from . import PACKAGE_DIR, backend_version
from .errors import BuiltinCompileError

GENERATOR_SUFFIXES = (".py", ".lark", ".c", ".h", ".json")
NEEDS = ("lark",)       # the parser's one package outside the standard library


class BuiltinBackend:
    name = "builtin"
    found_note = "builtin compiler found"
    missing_note = "builtin compiler not available"

    def missing(self) -> str | None:
        absent = [m for m in NEEDS if importlib.util.find_spec(m) is None]
        if absent:
            return f"the builtin compiler is not available: No module named {absent[0]!r}"
        return None

    def available(self) -> bool:
        return self.missing() is None

    def version(self) -> str:
        return backend_version()

    def generator_files(self) -> list[Path]:
        return [p for p in PACKAGE_DIR.rglob("*") if p.suffix in GENERATOR_SUFFIXES]

    def flags(self) -> list[str]:
        return list(cc.BUILTIN_FLAGS)

    def generate(self, src: Sources, c_dir: Path, version: str, coverage: bool = False) -> Generated:
        try:
            # a coverage build's C names the ST lines (#line), as iec2c's always does
            extra = {"line_directives": True} if coverage else {}
            out = builtin.compile_to_c(src.entry, src.root, c_dir, search=src.search, **extra)
        except BuiltinCompileError as exc:
            raise Rejected([str(d) for d in exc.diagnostics] or str(exc).splitlines()) from None
        units = list(out.c_files)
        return Generated(json.loads(out.manifest.read_text()), units, {u: self.flags() for u in units},
                         [c_dir], units, list(out.sources))      # one program cut into units

    def explain_c_errors(self, diagnostics: list[str]) -> list[str]:
        return diagnostics
