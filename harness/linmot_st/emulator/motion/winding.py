"""Encoder winding (300xh..311xh; [MC] 4.3.213..216 give only headers, the seed's 5.4 only a TOC line): a
traverse that lays thread on a spool turned by the master encoder. INFERRED model: the slider moves between
the left (1540h) and right (1541h) positions, advancing by the pitch (1542h, pu per master revolution, counts
per revolution 1291h), reversing at each; 301h/311h start after a number of revolutions (the traverse stands at
the left position until then). Curve winding (310h/311h) shapes each stroke with a curve's setpoints (first to
last setpoint = left to right, mirrored on the way back). The traverse is a pure function of the counter, so it
follows the spool at any speed and direction. Adaptation of the reversal positions and the "disturbance"
(304h/305h) need a sensor the emulator does not have: the commands are accepted and switch a flag only.
"""

from __future__ import annotations

from ...protocol import commands as C
from ...protocol import words as W
from ...protocol.commands import CommandDef
from ...protocol.upids import P_WINDING_LEFT, P_WINDING_PITCH, P_WINDING_RIGHT
from .drive_series import on_series
from .setpoints import _demands_by_at

NEVER = 1 << 62


class WindingFollower:
    kind = "winding"

    def __init__(self, mc, t: int, start_revs: float, shape: list[float] | None):
        self.origin_ns = t
        self.encoder = mc.encoder
        self.left, self.right = float(mc.par(P_WINDING_LEFT)), float(mc.par(P_WINDING_RIGHT, 100_000))
        self.pitch = float(mc.par(P_WINDING_PITCH, 10_000))
        self.start_count = mc.encoder.counts(t) + start_revs * mc.encoder.counts_per_rev()
        self.cpr = mc.encoder.counts_per_rev()
        self.shape = shape
        self.target = self.left
        self.end_ns = NEVER

    def stroke(self, count: int) -> tuple[int, float]:
        """(stroke number, 0..1 progress in it) at the counter value."""
        span = abs(self.right - self.left)
        travel = max(count - self.start_count, 0) / self.cpr * self.pitch
        if span <= 0:
            return 0, 0.0
        n = int(travel // span)
        return n, travel / span - n

    def position(self, u: float, forwards: bool) -> float:
        if self.shape is not None:
            y = self.shape
            k = len(y) - 1
            x = u * k
            i = min(int(x), k - 1)
            v = y[i] + (x - i) * (y[i + 1] - y[i])
            u = (v - y[0]) / (y[-1] - y[0]) if y[-1] != y[0] else u
        if not forwards:
            u = 1.0 - u
        return self.left + (self.right - self.left) * u

    def at(self, t_ns: int) -> tuple[float, float, float]:
        c = self.encoder.counts(t_ns)
        n, u = self.stroke(c)
        p = self.position(u, n % 2 == 0)
        n2, u2 = self.stroke(c + 1)        # the slope per count, for the velocity (feedforward)
        slope = self.position(u2, n2 % 2 == 0) - p if n2 == n else 0.0
        rate = self.encoder.rate(t_ns) if c >= self.start_count else 0.0
        return p, slope * rate, 0.0

    def done(self, t_ns: int) -> bool:
        return False

    def demands(self, t_ns: int, step_ns: int):
        return _demands_by_at(self, t_ns, step_ns)


def _winding(mc, c: CommandDef, f: dict, t: int) -> bool:
    if c.cid in (C.WINDING_STOP_ADAPTATION, C.WINDING_RESTART_ADAPTATION):
        mc.winding_adaptation = c.cid == C.WINDING_RESTART_ADAPTATION
        return True
    shape = None
    if "curve_id" in f:
        curve = mc.curves.ram.get(f["curve_id"])
        if curve is None:
            return mc._fail(W.ERR_CURVE_NOT_DEFINED, t)
        shape = [float(v) for v in curve.setpoints]
    mc._start(WindingFollower(mc, t, f.get("revolutions", 0), shape))
    return True


HANDLERS = {C.Kind.WINDING: on_series(_winding)}
