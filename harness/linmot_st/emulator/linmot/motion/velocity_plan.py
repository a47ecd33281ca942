"""Infinite motion ([MC] 4.3.36/37, 02Exh/02Fxh): a setpoint generator without a target. From the start state it
ramps to the commanded velocity (speeding up with acc, slowing down or reversing with dec; INFERRED, as the VA
interpolator does) and keeps that velocity until another command replaces it. It never ends: Motion Active
stays set, In Target Position clear (spec/linmot-motion-commands.md 2.5; docs/emulator.md)."""

from __future__ import annotations

from .setpoints import NS, _demands_by_at

NEVER_NS = 1 << 62          # the plan's end: beyond any simulated time


class VelocityPlan:
    kind = "velocity"

    def __init__(self, origin_ns: int, p0: float, v0: float, velocity: float, acc: float, dec: float):
        self.origin_ns = origin_ns
        self.velocity = float(velocity)
        self.end_ns = NEVER_NS
        # the target an increment on the "last target" adds to: INFERRED the position where the motion started
        self.target = float(p0)
        acc, dec = max(acc, 1e-9), max(dec, 1e-9)
        segs: list[tuple[float, float, float, float]] = []    # (start s, p, v, a)
        t, p, v = 0.0, float(p0), float(v0)
        if v * self.velocity < 0:                              # moving the other way: brake to rest first
            tb = abs(v) / dec
            segs.append((t, p, v, -dec if v > 0 else dec))
            t, p, v = tb, p + v * tb / 2, 0.0
        if v != self.velocity:
            a = acc if abs(self.velocity) > abs(v) else dec
            a = a if self.velocity > v else -a
            tr = (self.velocity - v) / a
            segs.append((t, p, v, a))
            t, p, v = t + tr, p + (v + self.velocity) * tr / 2, self.velocity
        segs.append((t, p, v, 0.0))
        self._segs = segs

    def at(self, t_ns: int) -> tuple[float, float, float]:
        t = max(t_ns - self.origin_ns, 0) * NS
        segs = self._segs
        i = len(segs) - 1
        while i > 0 and segs[i][0] > t:
            i -= 1
        t0, p, v, a = segs[i]
        dt = t - t0
        return p + v * dt + 0.5 * a * dt * dt, v + a * dt, a

    def done(self, t_ns: int) -> bool:
        return False

    def demands(self, t_ns: int, step_ns: int):
        return _demands_by_at(self, t_ns, step_ns)
