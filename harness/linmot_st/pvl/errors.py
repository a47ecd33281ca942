"""PvlError: everything wrong with a PVL file (or model), one `file:line: message` per problem."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, order=True)
class Diagnostic:
    line: int | None          # 1-based file line; None for a model that was not read from a file
    message: str

    def format(self, filename: str) -> str:
        return f"{filename}:{self.line}: {self.message}" if self.line is not None else f"{filename}: {self.message}"


class PvlError(ValueError):
    """Raised by the parser and the writer. `diagnostics` holds every problem found, in line order;
    `str(err)` is one `file:line: message` line per problem."""

    def __init__(self, filename: str, diagnostics: list[Diagnostic]):
        self.filename = filename
        self.diagnostics = sorted(diagnostics, key=lambda d: (d.line is None, d.line or 0))
        super().__init__("\n".join(self.messages))

    @property
    def messages(self) -> list[str]:
        return [d.format(self.filename) for d in self.diagnostics]
