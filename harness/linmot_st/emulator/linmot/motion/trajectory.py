"""The trajectory record of one drive: what the axis did, for assertions and plots.

One sample per MC cycle while anything moves, and one at each event (a command, a state change), so a
standing axis costs nothing. Positions in pu (0.1 um), velocities in pu/s. Beside the samples, `io` holds every
change of the drive's I/O (emulator/linmot/io.py's IoChange: time, pin or "trigger", level or volts), and
`master_counts(t)` the master encoder's counter at any time of the record.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple


class Sample(NamedTuple):
    t_ns: int
    demand: float
    actual: float
    demand_velocity: float
    actual_velocity: float
    state_var: int
    status_word: int

    @property
    def state(self) -> int:
        return self.state_var >> 8

    @property
    def following_error(self) -> float:
        return self.demand - self.actual


@dataclass
class Trajectory:
    samples: list[Sample]

    def __init__(self) -> None:
        self.samples = []
        self.io: list = []           # IoChange records, in time order (the drive's DriveIO appends them)
        self.master_encoder = None   # the MC's master encoder (its counter's history: master_counts)

    def add(self, sample: Sample) -> None:
        s = self.samples
        if s and s[-1].t_ns == sample.t_ns:
            s[-1] = sample          # an event and a cycle at the same instant: keep the later state
        else:
            s.append(sample)

    def extend(self, samples: list[Sample]) -> None:
        """Samples in strictly increasing time (a run of MC cycles), the first one as `add` takes it."""
        if samples:
            self.add(samples[0])
            self.samples.extend(samples[1:] if len(samples) > 1 else ())

    def clear(self) -> None:
        self.samples.clear()
        self.io.clear()

    def io_at(self, name: str, t_ns: int):
        """The level (volts for X4.4) of an I/O pin, or of "trigger", at t_ns; None before its first change."""
        found = None
        for c in self.io:
            if c.t_ns > t_ns:
                break
            if c.name == name:
                found = c.value
        return found

    def __len__(self) -> int:
        return len(self.samples)

    def between(self, t0_ns: int, t1_ns: int | None = None) -> list[Sample]:
        return [s for s in self.samples if s.t_ns >= t0_ns and (t1_ns is None or s.t_ns <= t1_ns)]

    def at(self, t_ns: int) -> Sample | None:
        """The last sample at or before t_ns."""
        found = None
        for s in self.samples:
            if s.t_ns > t_ns:
                break
            found = s
        return found

    def master_counts(self, t_ns: int) -> int:
        """The master encoder's counter at t_ns (emulator/linmot/master_encoder.py keeps its history)."""
        return self.master_encoder.counts(t_ns) if self.master_encoder is not None else 0

    def columns(self) -> dict[str, list]:
        """The samples as columns (for plots and numpy); with a master encoder that was driven, its counter
        at each sample as `master_counts`."""
        cols = {name: [getattr(s, name) for s in self.samples] for name in Sample._fields}
        enc = self.master_encoder
        if enc is not None and enc.driven:
            cols["master_counts"] = [enc.counts(s.t_ns) for s in self.samples]
        return cols
