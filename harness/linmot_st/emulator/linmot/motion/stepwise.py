"""A setpoint generator computed cycle by cycle, for motions that react to a signal the plan cannot know ahead
(a force sensor, a tracking limiter): `step` advances the demand by one MC cycle. It has the plans' interface
(setpoints.py); `stepwise = True` keeps the MC's quiet cycles (fast_path.py) from computing it ahead, since a
step may depend on the axis as it is then. Between steps the demand is extrapolated with its velocity.
"""

from __future__ import annotations

from .setpoints import _demands_by_at

NS = 1e-9
NEVER = 1 << 62


class StepwisePlan:
    stepwise = True
    kind = "stepwise"

    def __init__(self, origin_ns: int, p0: float, v0: float, cycle_ns: int):
        self.origin_ns = origin_ns
        self.cycle_ns = cycle_ns
        self._t, self._p, self._v = origin_ns, float(p0), float(v0)
        self.target = float(p0)
        self.end_ns = NEVER

    def step(self, t_ns: int, p: float, v: float, dt: float) -> tuple[float, float]:
        """The demand (position, velocity) at t_ns, one cycle of dt seconds after (p, v)."""
        raise NotImplementedError

    def at(self, t_ns: int) -> tuple[float, float, float]:
        cyc = self.cycle_ns
        while self._t + cyc <= t_ns:
            self._t += cyc
            self._p, self._v = self.step(self._t, self._p, self._v, cyc * NS)
        return self._p + self._v * max(t_ns - self._t, 0) * NS, self._v, 0.0

    def done(self, t_ns: int) -> bool:
        return False

    def demands(self, t_ns: int, step_ns: int):
        return _demands_by_at(self, t_ns, step_ns)


def track(p: float, v: float, x: float, vx: float, dt: float, vmax: float, acc: float, dec: float):
    """One cycle of a VA-limited follower of a moving target (x = the target at the end of the cycle, vx its
    velocity): the speed relative to the target that can still brake onto it with dec in whole cycles (and
    does not pass it within this one), limited to vmax, reached with acc (speeding up) or dec (slowing down).
    INFERRED: the drive's tracking interpolator is not documented."""
    e = x - p
    d = abs(e)
    brake = dec * dt * ((0.25 + 2 * d / (dec * dt * dt)) ** 0.5 - 0.5)
    rel = min(brake, d / dt)
    want = min(max(vx + (rel if e > 0 else -rel), -vmax), vmax)
    rate = acc if abs(want) > abs(v) and want * v >= 0 else dec
    v1 = v + min(max(want - v, -rate * dt), rate * dt)
    p1 = p + v1 * dt
    if abs(x - p1) < 0.5 and abs(v1 - vx) <= rate * dt:       # on the target: lock onto it
        return x, vx
    return p1, v1
