"""The compiler backends by name, in the order `auto` tries them (MatIEC where iec2c is found)."""

from __future__ import annotations

from .backend import Backend
from .builtin.backend import BuiltinBackend
from .matiec.backend import MatiecBackend

BACKENDS: dict[str, Backend] = {b.name: b for b in (MatiecBackend(), BuiltinBackend())}
AUTO = "auto"
CHOICES = (AUTO, *BACKENDS)      # what --backend accepts


def choose(name: str = AUTO) -> Backend:
    """The backend of that name; `auto`: the first one that can run (the last one when none can, so the
    build reports why it cannot)."""
    if name == AUTO:
        return next((b for b in BACKENDS.values() if b.available()), list(BACKENDS.values())[-1])
    if name not in BACKENDS:
        raise ValueError(f"unknown backend {name!r}: choose one of {', '.join((AUTO, *BACKENDS))}")
    return BACKENDS[name]


def auto_note(chosen: Backend) -> str:
    """Why `auto` chose this backend: the ones before it that cannot run, else that it can."""
    order = list(BACKENDS.values())
    passed = [b.missing_note for b in order[:order.index(chosen)] if not b.available()]
    return ", ".join(passed) if passed else chosen.found_note


def matiec_available() -> bool:
    return BACKENDS["matiec"].available()


def builtin_available() -> bool:
    return BACKENDS["builtin"].available()
