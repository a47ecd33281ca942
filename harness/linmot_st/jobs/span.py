"""What a job's phase (commissioning) and step (motion) records share: a span of PLC time and scans."""

from __future__ import annotations


class Span:
    """A mixin of a record dataclass with fields t0_ns / scan0 (its first scan) and t1_ns / scan1 (the first scan
    after it)."""

    t0_ns: int
    t1_ns: int
    scan0: int
    scan1: int

    @property
    def scans(self) -> int:
        return self.scan1 - self.scan0

    @property
    def duration_ns(self) -> int:
        return self.t1_ns - self.t0_ns
