"""Setpoint generation ([MC] chapter 5): the VA interpolator and the time-curve player.

A generator is planned once, when its command starts, and evaluated at any time after that: `at(t_ns)` gives
the demand position (pu), velocity (pu/s) and acceleration (pu/s^2). Plans are exact (piecewise constant
acceleration, or linear between curve setpoints); the MC samples them once per cycle, so a motion ends within
one cycle of its planned end. `demands(t_ns, step_ns)` yields the same (position, velocity) as `at` at t_ns,
t_ns + step_ns, ... without a call per sample (the quiet MC cycles take their demand from it).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

NS = 1e-9


@dataclass(frozen=True)
class _Seg:
    t: float        # start, s after the plan's origin
    p: float
    v: float
    a: float


class VaPlan:
    """VA interpolator from a start state to a target (INFERRED model, spec 3): trapezoid, or triangle when the
    distance is short; from a velocity above vmax it ramps down with dec; when the target cannot be reached
    without passing it (too fast, or moving away) it brakes with dec and comes back. Ends at rest on target."""

    kind = "vai"

    def __init__(self, origin_ns: int, p0: float, v0: float, target: float, vmax: float, acc: float, dec: float):
        self.origin_ns = origin_ns
        self.target = float(target)
        self.vmax, self.acc, self.dec = max(vmax, 1e-9), max(acc, 1e-9), max(dec, 1e-9)
        segs: list[_Seg] = []
        t = _plan(segs, 0.0, float(p0), float(v0), self.target, self.vmax, self.acc, self.dec)
        self._segs = segs
        self._rows = [(s.t, s.p, s.v, s.a) for s in segs]     # the segments as demands() walks them (made once)
        self._start = (float(p0), float(v0))
        self.end_s = t
        self.end_ns = origin_ns + math.ceil(t * 1e9)

    def at(self, t_ns: int) -> tuple[float, float, float]:
        t = (t_ns - self.origin_ns) * NS
        if t >= self.end_s or not self._segs:
            return self.target, 0.0, 0.0
        if t <= 0:
            return self._start[0], self._start[1], 0.0
        segs = self._segs
        i = len(segs) - 1
        while i > 0 and segs[i].t > t:
            i -= 1
        s = segs[i]
        dt = t - s.t
        return s.p + s.v * dt + 0.5 * s.a * dt * dt, s.v + s.a * dt, s.a

    def done(self, t_ns: int) -> bool:
        return t_ns >= self.end_ns

    def demands(self, t_ns: int, step_ns: int):
        """(position, velocity) at t_ns, t_ns + step_ns, ...: `at`'s arithmetic, term for term (so the values
        are bit-identical), with the segment found by walking forward as time only grows."""
        origin, end_s, ns = self.origin_ns, self.end_s, NS      # NS in a local: read once per cycle
        segs = self._rows
        inf = float("inf")
        i = 0
        if segs:
            st, sp, sv, sa = segs[0]
            next_t = segs[1][0] if len(segs) > 1 else inf
        while segs:
            t = (t_ns - origin) * ns
            if t >= end_s:
                break
            if t <= 0:
                yield self._start
            else:
                while t >= next_t:          # `at` takes the last segment that starts at or before t
                    i += 1
                    st, sp, sv, sa = segs[i]
                    next_t = segs[i + 1][0] if i + 1 < len(segs) else inf
                dt = t - st
                yield sp + sv * dt + 0.5 * sa * dt * dt, sv + sa * dt
            t_ns += step_ns
        rest = (self.target, 0.0)
        while True:
            yield rest


def _plan(segs: list[_Seg], t: float, p: float, v: float, target: float, vmax: float, acc: float,
          dec: float) -> float:
    """Appends the segments from (p, v) at time t to rest on target; returns the end time."""
    d = target - p
    if abs(d) < 1e-9 and abs(v) < 1e-9:
        return t
    s = 1.0 if (d > 0 or (d == 0 and v < 0)) else -1.0        # direction towards the target
    u, dist = s * v, abs(d)                                     # speed towards it, distance to it
    if u < 0 or u * u / (2 * dec) > dist + 1e-9:
        # moving away, or too fast to stop in time: brake to rest, then plan again from there
        tb = abs(u) / dec
        segs.append(_Seg(t, p, v, -math.copysign(dec, v)))
        p_stop = p + v * tb / 2
        return _plan(segs, t + tb, p_stop, 0.0, target, vmax, acc, dec)
    if u > vmax:
        # above the new vmax: ramp down to it with dec, cruise, brake
        t1 = (u - vmax) / dec
        x1 = (u * u - vmax * vmax) / (2 * dec)
        x3 = vmax * vmax / (2 * dec)
        t2 = max(dist - x1 - x3, 0.0) / vmax
        segs.append(_Seg(t, p, v, -s * dec))
        segs.append(_Seg(t + t1, p + s * x1, s * vmax, 0.0))
        segs.append(_Seg(t + t1 + t2, p + s * (dist - x3), s * vmax, -s * dec))
        return t + t1 + t2 + vmax / dec
    # peak speed of a triangle from u to 0 over dist
    vp = math.sqrt((dist + u * u / (2 * acc)) / (1 / (2 * acc) + 1 / (2 * dec)))
    if vp > vmax:
        vp = vmax
        x1 = (vp * vp - u * u) / (2 * acc)
        x3 = vp * vp / (2 * dec)
        t2 = max(dist - x1 - x3, 0.0) / vp
    else:
        x1 = (vp * vp - u * u) / (2 * acc)
        t2 = 0.0
    t1 = (vp - u) / acc
    x3 = dist - x1 - vp * t2
    if t1 > 0:
        segs.append(_Seg(t, p, v, s * acc))
    if t2 > 0:
        segs.append(_Seg(t + t1, p + s * x1, s * vp, 0.0))
    segs.append(_Seg(t + t1 + t2, p + s * (dist - x3), s * vp, -s * dec))
    return t + t1 + t2 + vp / dec


class StopPlan(VaPlan):
    """Brake from (p0, v0) to rest with dec (VAI stop, quick stop): the target is where it comes to rest."""

    kind = "stop"

    def __init__(self, origin_ns: int, p0: float, v0: float, dec: float):
        dec = max(dec, 1e-9)
        super().__init__(origin_ns, p0, v0, p0 + v0 * abs(v0) / (2 * dec), abs(v0) + 1.0, dec, dec)


class CurvePlan:
    """A time curve ([MC] 4.3.45..50, [CFG] 5.3): N setpoints equally spaced over the curve time, position =
    offset + amplitude x setpoint, linear between setpoints (INFERRED). The curve time is the info block's
    x-length (10 us) stretched by the time scale, or the command's own curve time."""

    kind = "curve"

    def __init__(self, origin_ns: int, curve_id: int, setpoints: list[int], duration_ns: int, offset: float,
                 amplitude: float):
        self.origin_ns = origin_ns
        self.curve_id = curve_id
        self.y = [float(v) for v in setpoints]
        self.duration_ns = max(int(duration_ns), 0)
        self.offset, self.amplitude = float(offset), float(amplitude)
        self.end_ns = origin_ns + self.duration_ns
        self.target = self.offset + self.amplitude * self.y[-1]
        self._step_s = self.duration_ns * NS / (len(self.y) - 1)

    def at(self, t_ns: int) -> tuple[float, float, float]:
        if t_ns >= self.end_ns or self._step_s <= 0:
            return self.target, 0.0, 0.0
        x = max(t_ns - self.origin_ns, 0) * NS / self._step_s
        i = int(x)
        f = x - i
        y0, y1 = self.y[i], self.y[i + 1]
        slope = (y1 - y0) / self._step_s
        return self.offset + self.amplitude * (y0 + f * (y1 - y0)), self.amplitude * slope, 0.0

    def done(self, t_ns: int) -> bool:
        return t_ns >= self.end_ns

    def demands(self, t_ns: int, step_ns: int):
        return _demands_by_at(self, t_ns, step_ns)


class Hold:
    """No setpoint generation: the demand rests at a position."""

    kind = "hold"

    def __init__(self, p: float):
        self.target = float(p)
        self.end_ns = 0

    def at(self, t_ns: int) -> tuple[float, float, float]:
        return self.target, 0.0, 0.0

    def done(self, t_ns: int) -> bool:
        return True

    def demands(self, t_ns: int, step_ns: int):
        rest = (self.target, 0.0)
        while True:
            yield rest


def _demands_by_at(plan, t_ns: int, step_ns: int):
    """`demands` through `at`, for a plan without a faster walk."""
    while True:
        p, v, _ = plan.at(t_ns)
        yield p, v
        t_ns += step_ns
