"""Progress while the PLC commissions: one readable line per finished phase of each axis, and on a
terminal a status line (phase, items done / total, a bar per axis) redrawn at most 10 times a second."""

from __future__ import annotations

import sys
import time

BAR = 12
LABELS = {"start": "start", "check": "compatibility check", "compare": "compare", "params": "parameters", "curves": "curves",
          "ct": "command table", "flash": "flash save", "reset": "reset", "verify": "verify"}
UNITS = {"check": "layers", "compare": "items", "params": "parameters", "curves": "curves", "ct": "entries",
         "flash": "services", "reset": "resets", "verify": "items"}
SINGULAR = {"layers": "layer", "parameters": "parameter", "curves": "curve", "entries": "entry",
            "services": "service", "resets": "reset", "items": "item"}


def _n(k: int, word: str) -> str:
    return f"{k} {word}{'' if k == 1 else 's'}"


def _ms(ns: int) -> str:
    return f"{ns / 1e6:9.1f} ms"


class Progress:
    def __init__(self, out=None, tty: bool | None = None, interval_s: float = 0.1) -> None:
        self.out = out or sys.stderr
        self.tty = self.out.isatty() if tty is None else tty
        self.interval_s = interval_s
        self._next_draw = 0.0
        self._drawn = False

    # --- events from the sampler -----------------------------------------------------------------
    def phase_done(self, ax, rec, t_ns: int) -> None:
        if rec.phase == "start":
            return
        unit = UNITS.get(rec.phase, "items")
        if rec.items_total == 1:
            unit = SINGULAR.get(unit, unit)
        self._line(f"{_ms(t_ns)}  node {ax.node_id:<3} {LABELS.get(rec.phase, rec.phase):<19} done: "
                   f"{rec.items_total} {unit}, {_n(rec.exchanges, 'exchange')}, {_n(rec.scans, 'scan')}")

    def axis_finished(self, ax, rec, t_ns: int) -> None:
        if ax.done:
            self.phase_done(ax, rec, t_ns)
            self._line(f"{_ms(t_ns)}  node {ax.node_id:<3} commissioned")
        else:
            self._line(f"{_ms(t_ns)}  node {ax.node_id:<3} FAILED in {LABELS.get(rec.phase, rec.phase)}")

    def tick(self, sampler, t_ns: int) -> None:
        if not self.tty:
            return
        now = time.monotonic()
        if now < self._next_draw:
            return
        self._next_draw = now + self.interval_s
        parts = []
        for k, ax in enumerate(sampler.axes):
            phase, done, total = sampler.live(k)
            if ax.finished:
                parts.append(f"node {ax.node_id}: {'done' if ax.done else 'FAILED'}")
                continue
            if phase in ("idle",):
                parts.append(f"node {ax.node_id}: waiting for boot-up")
                continue
            frac = min(done / total, 1.0) if total else 0.0
            bar = "#" * int(frac * BAR) + "-" * (BAR - int(frac * BAR))
            parts.append(f"node {ax.node_id}: {phase:<6} [{bar}] {done}/{total}")
        self._draw(f"{t_ns / 1e9:7.3f} s  " + "  |  ".join(parts))

    def close(self) -> None:
        if self._drawn:
            self.out.write("\r\x1b[2K")
            self.out.flush()
            self._drawn = False

    # --- output ---------------------------------------------------------------------------------
    def _line(self, text: str) -> None:
        if self._drawn:
            self.out.write("\r\x1b[2K")
            self._drawn = False
        self.out.write(text + "\n")
        self.out.flush()
        self._next_draw = 0.0

    def _draw(self, text: str) -> None:
        self.out.write("\r\x1b[2K" + text[:200])
        self.out.flush()
        self._drawn = True
