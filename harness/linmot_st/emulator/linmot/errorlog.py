"""The drive's error log (spec 2.2 error log objects 70h..74h+n): entries with error code and the operating
time they occurred at (hours, and milliseconds within the hour). Kept across resets, like the real log."""

from __future__ import annotations

from dataclasses import dataclass

NS_PER_MS = 1_000_000
MS_PER_HOUR = 3_600_000


@dataclass(frozen=True)
class ErrorEntry:
    code: int
    time_ms: int     # 72h "time low": milliseconds within the hour
    time_h: int      # 73h "time high": operating hours


class ErrorLog:
    """Entries oldest first (entry 0 = oldest, INFERRED); at most `capacity` kept, the oldest dropped."""

    def __init__(self, capacity: int = 21, entries: list[ErrorEntry] | None = None, occurred: int | None = None):
        self.capacity = capacity
        self.entries: list[ErrorEntry] = list(entries or [])[-capacity:]
        self.occurred = occurred if occurred is not None else len(self.entries)

    def log(self, code: int, operating_ms: int) -> None:
        self.entries.append(ErrorEntry(code, operating_ms % MS_PER_HOUR, operating_ms // MS_PER_HOUR))
        del self.entries[:-self.capacity]
        self.occurred += 1

    def entry(self, n: int) -> ErrorEntry | None:
        return self.entries[n] if 0 <= n < len(self.entries) else None
