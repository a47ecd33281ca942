"""The master encoder input of the emulated drive ([MC] 7.3): an external RS422 encoder (a conveyor, a winder's
spindle) whose counts the cam, position-indexing and winding motions follow.

The encoder itself is a *signal*: a function of virtual time giving the quadrature edges counted at 4x decoding
(`counts(t_ns)`) and their rate (`rate(t_ns)`, edges/s). A test or `linmot-st emulate` drives it with one of the
signals below (constant speed, a speed profile, a recorded list, any function of time). The drive's counter is
that signal through the encoder parameters: decoding 128Fh (1x/2x/4x: edges / 4, 2, 1; 4x on a step/dir encoder
counts as 2x, [MC] 7.3), direction 1290h (1 = negative), plus the offset Encoder Cam Set Value (104xh) sets.
The speed variable is averaged over the speed filter time 1293h.

Units: counts are increments of the master encoder ([MC] 4.3.153 "1 Incr"), times ns.
"""

from __future__ import annotations

import bisect
import csv
import math
from collections.abc import Callable, Sequence
from typing import Protocol

from ...protocol.upids import (
    P_MASTER_ENCODER_COUNTS_PER_REV,
    P_MASTER_ENCODER_DECODING,
    P_MASTER_ENCODER_DIRECTION,
    P_MASTER_ENCODER_SOURCE,
    P_MASTER_ENCODER_SPEED_FILTER,
    P_MASTER_ENCODER_TYPE,
)

NS = 1e-9
_STEP_DIR = (4, 5)                       # encoder types step/dir (SD), step/dir/zero (SDZ): [MC] 7.3
_EDGES_PER_COUNT = {0: 4, 1: 2, 2: 1}    # decoding 1x, 2x, 4x on the 4x edges of the signal


class Signal(Protocol):
    def counts(self, t_ns: int) -> float: ...       # 4x edges since the signal's origin
    def rate(self, t_ns: int) -> float: ...         # edges/s


class Standstill:
    """No encoder turning (also: no signal connected)."""

    def counts(self, t_ns: int) -> float:
        return 0.0

    def rate(self, t_ns: int) -> float:
        return 0.0


class ConstantSpeed:
    """`speed` edges/s from `start` edges at t0_ns (negative speed: turning backwards)."""

    def __init__(self, speed: float, start: float = 0.0, t0_ns: int = 0):
        self.speed, self.start, self.t0_ns = float(speed), float(start), t0_ns

    def counts(self, t_ns: int) -> float:
        return self.start + self.speed * ((t_ns - self.t0_ns) / 1e9)

    def rate(self, t_ns: int) -> float:
        return self.speed


class SpeedProfile:
    """Piecewise constant speed: `steps` = [(t_ns, edges/s), ...] in increasing time, each speed holding until
    the next step; before the first step the encoder stands at `start`."""

    def __init__(self, steps: Sequence[tuple[int, float]], start: float = 0.0):
        self.times = [int(t) for t, _ in steps]
        self.speeds = [float(v) for _, v in steps]
        if self.times != sorted(self.times):
            raise ValueError("speed profile steps must be in increasing time")
        self.base = [float(start)]
        for i in range(1, len(self.times)):
            self.base.append(self.base[-1] + self.speeds[i - 1] * ((self.times[i] - self.times[i - 1]) / 1e9))

    def _seg(self, t_ns: int) -> int:
        return bisect.bisect_right(self.times, t_ns) - 1

    def counts(self, t_ns: int) -> float:
        i = self._seg(t_ns)
        if i < 0:
            return self.base[0]
        return self.base[i] + self.speeds[i] * ((t_ns - self.times[i]) / 1e9)

    def rate(self, t_ns: int) -> float:
        i = self._seg(t_ns)
        return self.speeds[i] if i >= 0 else 0.0


class Recorded:
    """A recorded list [(t_ns, edges), ...]: linear between the samples, held before the first and after the
    last."""

    def __init__(self, samples: Sequence[tuple[int, float]]):
        self.times = [int(t) for t, _ in samples]
        self.values = [float(c) for _, c in samples]
        if not self.times or self.times != sorted(self.times):
            raise ValueError("a recorded signal needs samples in increasing time")

    def _seg(self, t_ns: int) -> int:
        return min(max(bisect.bisect_right(self.times, t_ns) - 1, 0), len(self.times) - 2)

    def counts(self, t_ns: int) -> float:
        if len(self.times) == 1 or t_ns <= self.times[0]:
            return self.values[0]
        if t_ns >= self.times[-1]:
            return self.values[-1]
        i = self._seg(t_ns)
        f = (t_ns - self.times[i]) / (self.times[i + 1] - self.times[i])
        return self.values[i] + f * (self.values[i + 1] - self.values[i])

    def rate(self, t_ns: int) -> float:
        if len(self.times) == 1 or not self.times[0] <= t_ns < self.times[-1]:
            return 0.0
        i = self._seg(t_ns)
        return (self.values[i + 1] - self.values[i]) / ((self.times[i + 1] - self.times[i]) * NS)


class Function:
    """Edges as any function of virtual time in seconds; its rate by a central difference unless given."""

    def __init__(self, fn: Callable[[float], float], rate: Callable[[float], float] | None = None):
        self.fn, self._rate = fn, rate

    def counts(self, t_ns: int) -> float:
        return float(self.fn(t_ns * NS))

    def rate(self, t_ns: int) -> float:
        t = t_ns * NS
        if self._rate is not None:
            return float(self._rate(t))
        h = 1e-6
        return (self.fn(t + h) - self.fn(t - h)) / (2 * h)


class MasterEncoder:
    """The drive's master encoder counter. `par(upid, default)` reads the encoder parameters' RAM values;
    `before_change(t)` is called before the signal or the counter changes (the MC syncs its cycles to t, so
    nothing it computed ahead used the old signal).

    The counter's history is kept: `segments` = [(from t_ns, signal, offset)], one per drive_with / set_value,
    so `counts(t)` is the counter at any time, past ones included (the trajectory record reads it for its
    samples: Trajectory.master_counts). The encoder parameters are read as they are now."""

    def __init__(self, par: Callable[[int, int], int], before_change: Callable[[int], None] | None = None):
        self._par = par
        self._before_change = before_change or (lambda t: None)
        self.segments: list[tuple[int, Signal, int]] = [(-(1 << 62), Standstill(), 0)]
        self._starts = [-(1 << 62)]

    @property
    def signal(self) -> Signal:
        return self.segments[-1][1]

    @property
    def driven(self) -> bool:
        """A signal or a counter value was ever given."""
        return len(self.segments) > 1

    def _segment(self, t_ns: int) -> tuple[int, Signal, int]:
        return self.segments[bisect.bisect_right(self._starts, t_ns) - 1]

    def _new_segment(self, t_ns: int, signal: Signal, offset: int) -> None:
        if self._starts[-1] == t_ns and len(self.segments) > 1:
            self.segments[-1] = (t_ns, signal, offset)
        else:
            self.segments.append((t_ns, signal, offset))
            self._starts.append(t_ns)

    # ---- driving it (tests, `linmot-st emulate`) ----
    def drive_with(self, signal: Signal, t_ns: int) -> None:
        """From t_ns the encoder follows `signal` (its counter continues from where it is: the offset absorbs
        the jump, as a counter does when a cable is plugged)."""
        self._before_change(t_ns)
        before = self.counts(t_ns)
        self._new_segment(t_ns, signal, before - self._raw(signal, t_ns))

    def set_value(self, value: int, t_ns: int) -> None:
        """104xh: the counter reads `value` now."""
        self._before_change(t_ns)
        signal = self._segment(t_ns)[1]
        self._new_segment(t_ns, signal, int(value) - self._raw(signal, t_ns))

    # ---- what the drive reads ----
    @property
    def connected(self) -> bool:
        return self._par(P_MASTER_ENCODER_SOURCE, 1) != 0 and self._par(P_MASTER_ENCODER_TYPE, 1) != 0

    def _scale(self) -> float:
        decoding = self._par(P_MASTER_ENCODER_DECODING, 2)
        if self._par(P_MASTER_ENCODER_TYPE, 1) in _STEP_DIR and decoding == 2:
            decoding = 1                                # [MC] 7.3: 4x falls back to 2x without error
        sign = -1.0 if self._par(P_MASTER_ENCODER_DIRECTION, 0) else 1.0
        return sign / _EDGES_PER_COUNT.get(decoding, 1)

    def _raw(self, signal: Signal, t_ns: int) -> int:
        """The signal's counts through decoding and direction (whole increments; the 1e-6 absorbs the float
        rounding of a signal that lands exactly on an edge)."""
        if not self.connected:
            return 0
        return math.floor(signal.counts(t_ns) * self._scale() + 1e-6)

    def counts(self, t_ns: int) -> int:
        """The counter at t_ns (whole increments)."""
        _, signal, offset = self._segment(t_ns)
        return self._raw(signal, t_ns) + offset

    def rate(self, t_ns: int) -> float:
        """Counts/s at t_ns (unfiltered: the slope the cam's feedforward uses)."""
        return self._segment(t_ns)[1].rate(t_ns) * self._scale() if self.connected else 0.0

    def sample(self, t_ns: int) -> tuple[int, float]:
        """(counts, rate) at t_ns: what the followers read once per MC cycle, the parameters read once."""
        _, signal, offset = self._segment(t_ns)
        if not self.connected:
            return offset, 0.0
        scale = self._scale()
        return math.floor(signal.counts(t_ns) * scale + 1e-6) + offset, signal.rate(t_ns) * scale

    def speed(self, t_ns: int) -> float:
        """Counts/s averaged over the speed filter time 1293h (in 0.1 ms: INFERRED unit)."""
        window_ns = max(self._par(P_MASTER_ENCODER_SPEED_FILTER, 10), 1) * 100_000
        return (self.counts(t_ns) - self.counts(t_ns - window_ns)) / (window_ns * NS)

    def counts_per_rev(self) -> int:
        return max(self._par(P_MASTER_ENCODER_COUNTS_PER_REV, 8000), 1)

    def revolutions(self, t_ns: int) -> float:
        return self.counts(t_ns) / self.counts_per_rev()


def parse_signal(spec: str) -> Signal:
    """A signal from a command-line spec (`linmot-st emulate --master-encoder`):
    `speed:EDGES_PER_S` (constant speed from time 0), `profile:T=EDGES_PER_S,T=EDGES_PER_S,...` (T in seconds of
    the drive's clock, each speed holding until the next), `recorded:FILE` (a CSV of `seconds,edges` lines,
    linear between). Raises ValueError with what is wrong."""
    kind, _, rest = spec.partition(":")
    try:
        if kind == "speed":
            return ConstantSpeed(float(rest))
        if kind == "profile":
            steps = []
            for item in rest.split(","):
                t, _, v = item.partition("=")
                steps.append((round(float(t) * 1e9), float(v)))
            return SpeedProfile(steps)
        if kind == "recorded":
            with open(rest, newline="") as f:
                rows = [r for r in csv.reader(f) if r and not r[0].lstrip().startswith("#")]
            return Recorded([(round(float(t) * 1e9), float(c)) for t, c in rows])
    except OSError as exc:
        raise ValueError(f"{rest}: {exc.strerror or exc}") from None
    except (TypeError, ValueError) as exc:
        raise ValueError(f"master encoder signal {spec!r}: {exc}") from None
    raise ValueError(f"master encoder signal {spec!r}: expected speed:N, profile:T=N,... or recorded:FILE")
