"""What the build driver asks of an ST -> C compiler backend, and what a backend gives back.

A backend is one object of the table in backends.py. The driver (toolchain/__init__.py) knows only this
protocol: it asks whether the backend can run, what keys the cache (version, generator files, flags),
and then for the C of the sources (`generate`), which it compiles, links and caches the same way for
every backend.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Protocol, runtime_checkable

from .sources import Sources


class Rejected(Exception):
    """The backend rejected the sources: `diagnostics` are `file:line:col: error: message` lines. Any
    other exception of `generate` is an internal compiler error."""

    def __init__(self, diagnostics: list[str]):
        super().__init__("\n".join(diagnostics))
        self.diagnostics = list(diagnostics)


@dataclass
class Generated:
    """The C of one build, ready for cc.compile_shared."""
    manifest: dict                        # docs/architecture.md 1.1
    units: list[Path]                     # every C unit to compile
    unit_flags: dict[Path, list[str]]     # the C compiler flags of each unit
    include_dirs: list[Path]
    one_program: list[Path]               # units that are one program cut in pieces (sized together)
    sources_read: list[Path]              # the ST files the backend read (the cache entry's record)


@runtime_checkable
class Backend(Protocol):
    name: str
    found_note: str       # why `auto` chose it ("iec2c found")
    missing_note: str     # why `auto` passed it over ("iec2c not found")

    def missing(self) -> str | None:
        """None when the backend can run; else why not, as the sentence of an error message."""

    def available(self) -> bool:
        """missing() is None."""

    def version(self) -> str:
        """The compiler's identity, for the cache key and the manifest."""

    def generator_files(self) -> list[Path]:
        """The files of this project whose content shapes the generated C (they key the cache)."""

    def flags(self) -> list[str]:
        """The flags that shape the output (the compiler's own and the C units'): they key the cache."""

    def generate(self, src: Sources, c_dir: Path, version: str, coverage: bool = False) -> Generated:
        """The C (and manifest) of `src` in `c_dir`; raises Rejected on sources the compiler refuses.
        `coverage`: a coverage build (docs/coverage.md), whose C must map to ST lines with `#line`; the
        driver passes it only when true."""

    def explain_c_errors(self, diagnostics: list[str]) -> list[str]:
        """The C compiler's diagnostics on this backend's C, with notes on known causes added."""
