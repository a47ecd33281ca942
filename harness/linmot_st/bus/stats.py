"""Bus statistics from a trace: busy time, load, frames per sender, and the stuffing-free lower bound.

Busy time counts each transmission from SOF to the end of its interframe space (3 bits), error
frames included: that is the time no other frame could use. The lower bound is the bus time the same
successful frames would need with no stuff bits and no errors (111 bits per 8-byte frame): the
commissioning report divides its actual bus time by it.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

from .bits import IFS_BITS, unstuffed_bus_bits


@dataclass
class BusStats:
    t0_ns: int
    t1_ns: int
    busy_ns: int                    # bus time in [t0, t1), transmissions clipped to the interval
    frames: int                     # successful frames that started in [t0, t1)
    errors: int                     # transmissions destroyed by an error frame that started in [t0, t1)
    frames_by_sender: dict[str, int] = field(default_factory=dict)
    lower_bound_ns: int = 0         # the same successful frames without stuff bits, back to back

    @property
    def load(self) -> float:
        """Busy fraction of the interval, 0..1 (multiply by 100 for %)."""
        span = self.t1_ns - self.t0_ns
        return self.busy_ns / span if span > 0 else 0.0

    @property
    def stuffing_ratio(self) -> float:
        """Busy time over its stuffing-free lower bound (>= 1 without errors)."""
        return self.busy_ns / self.lower_bound_ns if self.lower_bound_ns else 0.0


def bus_stats(trace: Iterable, bit_ns: int, t0_ns: int, t1_ns: int) -> BusStats:
    if t1_ns < t0_ns:
        raise ValueError(f"empty interval [{t0_ns}, {t1_ns})")
    ifs = IFS_BITS * bit_ns
    st = BusStats(t0_ns, t1_ns, 0, 0, 0)
    for entry in trace:
        start, end = entry.start_ns, entry.end_ns + ifs
        if end > t0_ns and start < t1_ns:
            st.busy_ns += min(end, t1_ns) - max(start, t0_ns)
        if not t0_ns <= start < t1_ns:
            continue
        if entry.status == "error":
            st.errors += 1
            continue
        st.frames += 1
        st.frames_by_sender[entry.sender] = st.frames_by_sender.get(entry.sender, 0) + 1
        st.lower_bound_ns += unstuffed_bus_bits(entry.frame.dlc, entry.frame.rtr) * bit_ns
    return st


def busy_per_window(trace: Iterable, bit_ns: int, t0_ns: int, t1_ns: int, window_ns: int) -> list[tuple[int, int, int]]:
    """(start, end, busy ns) of each window [t, min(t + window_ns, t1)) from t0 on: the busy_ns bus_stats gives each
    window (the same clipping), in one sweep of the trace instead of one per window (the motion job's busiest 100
    ms: a whole trace per window was 86 sweeps of the 2-axis demo; tests/bus/test_bus_stats.py compares the two)."""
    if window_ns <= 0:
        raise ValueError(f"window {window_ns} ns: must be > 0")
    if t1_ns <= t0_ns:
        return []
    n = (t1_ns - t0_ns + window_ns - 1) // window_ns
    busy = [0] * n
    ifs = IFS_BITS * bit_ns
    for entry in trace:
        start, end = entry.start_ns, entry.end_ns + ifs
        if end <= t0_ns or start >= t1_ns:
            continue
        if start < t0_ns:
            start = t0_ns
        if end > t1_ns:
            end = t1_ns
        k = (start - t0_ns) // window_ns
        while start < end:                    # the part of the transmission in each window it overlaps
            w_end = t0_ns + (k + 1) * window_ns
            cut = end if end < w_end else w_end
            busy[k] += cut - start
            start, k = cut, k + 1
    return [(t0_ns + k * window_ns, min(t0_ns + (k + 1) * window_ns, t1_ns), b) for k, b in enumerate(busy)]

