"""P, PV and PVA streams ([MC] 4.3.38..44, 5.4; seed 004 5.2): the stream setpoint generator and the handlers
of the catalogue's kinds STREAM and STREAM_STOP. A part of the MC model (interpreter.py registers the handlers,
control.py calls `check` once per cycle while a stream runs).

What [MC] states: each setpoint is stamped with its receive time; the first two fix the nominal period; the
stream is replayed 1.5 periods late with a fine interpolation between setpoints; the "configured period"
variants take 14E6h instead of the measured stamps for the derivatives; errors 0082h..0085h. What it leaves
open is INFERRED (docs/emulator.md, "Streams"): the interpolation (cubic Hermite from P and V, quintic from P,
V and A, P alone with backward-difference velocities), the playback timeline (the stamps + 1.5 periods; with a
configured period, the first stamp + 1.5 periods + k periods), the buffer size (MotionSettings), the hold
before the first setpoint plays, and what 03Fxh does (the held setpoints play out, then the axis rests there).

The plan is known up to `end_ns`, the playback time of the newest setpoint: the fast path computes quiet cycles
only before it (fast_path.py stops an active run at the plan's end), so a setpoint arriving later changes no
cycle already computed; at `end_ns` without a newer setpoint the generic cycle finds the underflow.
"""

from __future__ import annotations

from bisect import bisect_right

from ....protocol import commands as C
from ....protocol import words as W
from ....protocol.commands import CommandDef
from ....protocol.upids import P_STREAM_PERIOD
from .units import ACC_RAW, VEL_RAW

NS = 1e-9
_KEEP = 16              # segments kept behind the newest (the MC only looks at the present)


class StreamPlan:
    """The demand of a stream: holds where the stream began until the first setpoint plays, then follows the
    segments between consecutive setpoints; after the last one (stopped stream, or underflow) it rests there."""

    kind = "stream"

    def __init__(self, origin_ns: int, p0: float, cid: int, configured_period_ns: int | None):
        self.origin_ns = origin_ns
        self.cid = cid
        self.configured_ns = configured_period_ns       # None: derivatives from the measured stamps
        self.points: list[tuple[int, float, float | None, float | None]] = []   # (stamp, p, v, a), newest last
        self.count = 0                                  # setpoints received
        self.period_ns: int | None = None               # the nominal period (first two stamps)
        self.delay_ns = 0
        self.stopped = False
        self.target = float(p0)                         # where it rests: the start, then the newest setpoint
        self.end_ns = origin_ns
        self._starts: list[int] = []                    # segment k: from _starts[k] to _ends[k]
        self._ends: list[int] = []
        self._coef: list[tuple[float, ...]] = []        # quintic in s = (t - start) / h, pu
        self._plays: list[int] = []                     # play times of the newest setpoints
        self._first_stamp = origin_ns
        self._before = self._hold = (float(p0), 0.0, 0.0)   # before the first setpoint plays; after the last
        self._last_v = 0.0
        self._end_v = 0.0

    # ---------------------------------------------------------------- setpoints in
    def add(self, stamp: int, p: float, v: float | None, a: float | None) -> None:
        self.count += 1
        pts = self.points
        if self.count == 2:
            self.period_ns = stamp - pts[-1][0]
            nominal = self.configured_ns or self.period_ns
            self.delay_ns = nominal * 3 // 2
        pts.append((stamp, p, v, a))
        if len(pts) > 3:
            del pts[0]
        self.target = p
        if self.count == 2:
            self._first_stamp = pts[-2][0]
            self._plays.append(self._play_time(0, pts[-2][0]))
        if self.count >= 2:
            self._plays.append(self._play_time(self.count - 1, stamp))
            if len(self._plays) > 2 * _KEEP:
                del self._plays[:_KEEP]
            self._segment()

    def _play_time(self, k: int, stamp: int) -> int:
        """When setpoint number k (0 = the first) plays."""
        if self.configured_ns:
            return self._first_stamp + self.delay_ns + k * self.configured_ns
        return stamp + self.delay_ns

    def _segment(self) -> None:
        """The segment from the previous setpoint to the newest."""
        (s0, p0, v0, a0), (s1, p1, v1, a1) = self.points[-2], self.points[-1]
        t0, t1 = self._plays[-2], self._plays[-1]
        h = max(t1 - t0, 1) * NS
        if v1 is None:
            # P stream: velocities by backward difference over the configured or the measured period
            dt = (self.configured_ns or (s1 - s0) or 1) * NS
            v0, v1 = self._last_v, (p1 - p0) / dt
        self._last_v = v1
        v0 = 0.0 if v0 is None else v0
        d = p1 - p0
        if a0 is None or a1 is None:        # cubic Hermite
            c = (p0, v0 * h, 3 * d - 2 * v0 * h - v1 * h, -2 * d + v0 * h + v1 * h, 0.0, 0.0)
        else:                               # quintic Hermite
            A0, A1 = a0 * h * h, a1 * h * h
            c = (p0, v0 * h, A0 / 2,
                 10 * d - 6 * v0 * h - 4 * v1 * h - 1.5 * A0 + 0.5 * A1,
                 -15 * d + 8 * v0 * h + 7 * v1 * h + 1.5 * A0 - A1,
                 6 * d - 3 * v0 * h - 3 * v1 * h - 0.5 * A0 + 0.5 * A1)
        self._starts.append(t0)
        self._ends.append(t1)
        self._coef.append(c)
        if len(self._starts) > 2 * _KEEP:
            del self._starts[:_KEEP], self._ends[:_KEEP], self._coef[:_KEEP]
        self.end_ns = t1
        self._hold = (p1, 0.0, 0.0)
        self._end_v = (c[1] + 2 * c[2] + 3 * c[3] + 4 * c[4] + 5 * c[5]) / h     # the velocity it ends with

    def pending(self, t: int) -> int:
        """Setpoints received that have not begun to play at t (all of them before the period is known)."""
        if self.period_ns is None:
            return self.count
        return sum(1 for tp in self._plays if tp > t)

    # ---------------------------------------------------------------- the demand
    def at(self, t_ns: int) -> tuple[float, float, float]:
        starts = self._starts
        if not starts:
            return self._hold
        if t_ns < starts[0]:
            return self._before
        if t_ns >= self.end_ns:
            if self.stopped:
                return self._hold
            # no newer setpoint (the cycle that finds the underflow): on at the last velocity, so that the
            # quick stop brakes from it
            v = self._end_v
            return self._hold[0] + v * (t_ns - self.end_ns) * NS, v, 0.0
        i = bisect_right(starts, t_ns) - 1
        return self._eval(i, t_ns)

    def _eval(self, i: int, t_ns: int) -> tuple[float, float, float]:
        c0, c1, c2, c3, c4, c5 = self._coef[i]
        t0 = self._starts[i]
        h = max(self._ends[i] - t0, 1) * NS
        s = (t_ns - t0) * NS / h
        p = c0 + s * (c1 + s * (c2 + s * (c3 + s * (c4 + s * c5))))
        dp = c1 + s * (2 * c2 + s * (3 * c3 + s * (4 * c4 + s * 5 * c5)))
        ddp = 2 * c2 + s * (6 * c3 + s * (12 * c4 + s * 20 * c5))
        return p, dp / h, ddp / (h * h)

    def done(self, t_ns: int) -> bool:
        return self.stopped and t_ns >= self.end_ns

    def demands(self, t_ns: int, step_ns: int):
        while True:
            p, v, _ = self.at(t_ns)
            yield p, v
            t_ns += step_ns


# ---------------------------------------------------------------- the handlers

def stream_setpoint(mc, c: CommandDef, f: dict, t: int) -> bool:
    """030xh..035xh: the first setpoint starts a stream (the demand holds where it is until the setpoint plays),
    each further one extends it."""
    gen = mc.gen
    if not (isinstance(gen, StreamPlan) and not gen.stopped):
        configured = None
        if c.cid in C.STREAM_CONFIGURED_PERIOD:
            configured = mc.par(P_STREAM_PERIOD, 2000) * 1000       # 14E6h in us (INFERRED unit)
        p0 = mc.gen.at(t)[0]
        gen = StreamPlan(t, p0, c.cid, configured)
        mc._start(gen)
    v = f["velocity"] * VEL_RAW if "velocity" in f else None
    a = f["acceleration"] * ACC_RAW if "acceleration" in f else None
    gen.add(t, float(f["position"]), v, a)
    if gen.count == 2:
        lo, hi = C.STREAM_PERIOD_RANGE_NS[gen.cid]
        if gen.period_ns < lo:
            return mc._fail(W.ERR_PVT_MASTER_TOO_FAST, t)
        if gen.period_ns > hi:
            return mc._fail(W.ERR_PVT_MASTER_TOO_SLOW, t)
    if gen.pending(t) > mc.s.stream_buffer_points:
        return mc._fail(W.ERR_PVT_BUFFER_OVERFLOW, t)
    return True


def stop_streaming(mc, c: CommandDef, f: dict, t: int) -> bool:
    """03Fxh: the setpoints held play out, then the axis rests on the last one (INFERRED); outside a stream
    nothing happens."""
    gen = mc.gen
    if isinstance(gen, StreamPlan) and not gen.stopped:
        gen.stopped = True
        if gen.count < 2:           # nothing to play: rest where the stream began
            gen.end_ns = t
            gen.target = gen._before[0]
    return True


def check(mc, t: int) -> None:
    """Once per MC cycle while a stream runs: a second setpoint that does not come (0085h), a setpoint that
    is not there when the previous one has played (0083h)."""
    gen = mc.gen
    if gen.stopped or mc.state == W.ERROR_QUICK_STOP:
        return
    if gen.count < 2:
        if gen.count == 1 and t - gen.points[-1][0] > C.STREAM_PERIOD_RANGE_NS[gen.cid][1]:
            mc._fail(W.ERR_PVT_MASTER_TOO_SLOW, t)
        return
    if t >= gen.end_ns:
        mc._fail(W.ERR_PVT_BUFFER_UNDERFLOW, t)
