"""Encoder winding (300xh..311xh; [MC] 4.3.213..216 give only headers, the seed's 5.4 only a TOC line): a
traverse that lays thread on a spool turned by the master encoder. INFERRED model: the slider moves between
the left (1540h) and right (1541h) positions, advancing by the pitch (1542h, pu per master revolution, counts
per revolution 1291h), reversing at each; 301h/311h start after a number of revolutions (the traverse stands at
the left position until then). Curve winding (310h/311h) shapes each stroke with a curve's setpoints (first to
last setpoint = left to right, mirrored on the way back). The traverse is a pure function of the counter, so it
follows the spool at any speed and direction. Adaptation and disturbance (304h stops, 305h restarts them):
the reversal positions move inwards stroke by stroke, as a winder keeps the flanks of a growing spool from
building up and varies the reversal points against ribbon patterns (WindingFollower; the amounts are
MotionSettings, 0 by default: the sources give none).
"""

from __future__ import annotations

import bisect

from ....protocol import commands as C
from ....protocol import words as W
from ....protocol.commands import CommandDef
from ....protocol.upids import P_WINDING_LEFT, P_WINDING_PITCH, P_WINDING_RIGHT
from .setpoints import _demands_by_at

NEVER = 1 << 62


GOLDEN = 0.6180339887498949        # the disturbance sequence: frac(k x golden ratio), low discrepancy (INFERRED)


class WindingFollower:
    """The traverse: stroke k runs from where stroke k - 1 reversed to its own reversal position (stroke 0 from
    the left position to the right one), the strokes' travel summing the pitch per master revolution. With
    adaptation on, stroke k's reversal position is moved inwards by winding_adaptation_pu_per_stroke x the
    strokes adapted before it plus winding_disturbance_pu x frac(k x golden ratio); 304h freezes both from
    the next stroke on, 305h lets them go on (INFERRED model, MotionSettings)."""

    kind = "winding"

    def __init__(self, mc, t: int, start_revs: float, shape: list[float] | None):
        self.origin_ns = t
        self.encoder = mc.encoder
        self.left, self.right = float(mc.par(P_WINDING_LEFT)), float(mc.par(P_WINDING_RIGHT, 100_000))
        self.pitch = float(mc.par(P_WINDING_PITCH, 10_000))
        self.start_count = mc.encoder.counts(t) + start_revs * mc.encoder.counts_per_rev()
        self.cpr = mc.encoder.counts_per_rev()
        self.shape = shape
        self.adapt, self.disturb = mc.s.winding_adaptation_pu_per_stroke, mc.s.winding_disturbance_pu
        self.toggles: list[tuple[int, bool]] = [(0, getattr(mc, "winding_adaptation", True))]
        self._bounds = [0.0]                  # travel (pu) at which stroke k starts
        self._ends = [self.left]              # stroke k - 1's reversal position = stroke k's start
        self.target = self.left
        self.end_ns = NEVER

    # ---- the strokes ----
    def _adapted_before(self, k: int) -> int:
        """How many strokes before k had adaptation on (toggles: (first stroke, on) in stroke order)."""
        n = 0
        for i, (first, on) in enumerate(self.toggles):
            last = self.toggles[i + 1][0] if i + 1 < len(self.toggles) else k
            if on:
                n += max(min(last, k) - first, 0)
        return n

    def reversal(self, k: int) -> float:
        """Where stroke k reverses: the right position for even k, the left one for odd k, moved inwards."""
        a = self._adapted_before(k)
        inward = self.adapt * a + self.disturb * ((a * GOLDEN) % 1.0)
        return self.right - inward if k % 2 == 0 else self.left + inward

    def _grow(self, travel: float) -> None:
        while self._bounds[-1] <= travel:
            k = len(self._bounds) - 1
            end = self.reversal(k)
            self._bounds.append(self._bounds[-1] + max(abs(end - self._ends[-1]), 1.0))
            self._ends.append(end)

    def stroke(self, count: int) -> tuple[int, float]:
        """(stroke number, 0..1 progress in it) at the counter value."""
        if self.right == self.left:
            return 0, 0.0
        travel = max(count - self.start_count, 0) / self.cpr * self.pitch
        self._grow(travel)
        k = bisect.bisect_right(self._bounds, travel) - 1
        return k, (travel - self._bounds[k]) / (self._bounds[k + 1] - self._bounds[k])

    def position(self, k: int, u: float) -> float:
        if self.shape is not None:
            y = self.shape
            n = len(y) - 1
            x = u * n
            i = min(int(x), n - 1)
            v = y[i] + (x - i) * (y[i + 1] - y[i])
            u = (v - y[0]) / (y[-1] - y[0]) if y[-1] != y[0] else u
        self._grow(self._bounds[k])
        start, end = self._ends[k], self._ends[k + 1]
        return start + (end - start) * u

    def change_adaptation(self, on: bool, t_ns: int) -> None:
        """304h/305h: from the stroke after the present one."""
        k, _ = self.stroke(self.encoder.counts(t_ns))
        del self._bounds[k + 2:], self._ends[k + 2:]          # the strokes after the next are planned again
        self.toggles.append((k + 1, on))

    def at(self, t_ns: int) -> tuple[float, float, float]:
        c = self.encoder.counts(t_ns)
        k, u = self.stroke(c)
        p = self.position(k, u)
        k2, u2 = self.stroke(c + 1)        # the slope per count, for the velocity (feedforward)
        slope = self.position(k2, u2) - p if k2 == k else 0.0
        rate = self.encoder.rate(t_ns) if c >= self.start_count else 0.0
        return p, slope * rate, 0.0

    def done(self, t_ns: int) -> bool:
        return False

    def demands(self, t_ns: int, step_ns: int):
        return _demands_by_at(self, t_ns, step_ns)


def _winding(mc, c: CommandDef, f: dict, t: int) -> bool:
    if c.cid in (C.WINDING_STOP_ADAPTATION, C.WINDING_RESTART_ADAPTATION):
        mc.winding_adaptation = on = c.cid == C.WINDING_RESTART_ADAPTATION
        if isinstance(mc.gen, WindingFollower):
            mc.gen.change_adaptation(on, t)
        return True
    shape = None
    if "curve_id" in f:
        curve = mc.curves.ram.get(f["curve_id"])
        if curve is None:
            return mc._fail(W.ERR_CURVE_NOT_DEFINED, t)
        shape = [float(v) for v in curve.setpoints]
    mc._start(WindingFollower(mc, t, f.get("revolutions", 0), shape))
    return True


HANDLERS = {C.Kind.WINDING: _winding}
