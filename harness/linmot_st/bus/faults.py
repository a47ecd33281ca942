"""Fault injection on the simulated bus: which frames a fault hits, and what it does to them.

Each fault has a predicate on the frame, an optional sender name and an optional number of
occurrences; `hits` records (t_ns, sender, frame) of every frame it acted on. The bus applies the
faults of a stage in the order they were added (docs/bus.md, "Fault hooks"):
  queued  -> delay            the frame becomes ready `delay_ns` later (the sender is slow); with `fifo`
                              the sender's frames queued behind it wait for it (it keeps its order)
  start   -> drop             the frame never reaches the bus (lost in the sender): no bus time
             corrupt          the frame is sent but destroyed by an error frame; the sender's controller
                              retransmits it automatically (real CAN: receivers never see a bad frame)
  end     -> mutate_payload   receivers get a changed frame, as if a corruption had escaped the CRC:
                              only for testing a receiver's robustness, it cannot happen on a sound bus
             duplicate        the frame is transmitted a second time right after the first
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

from .frame import Frame

Predicate = Callable[[Frame], bool]


@dataclass(eq=False)
class Fault:
    kind: str                                  # delay, drop, corrupt, mutate_payload, duplicate
    predicate: Predicate
    sender: str | None = None                  # only frames sent by this participant
    count: int | None = None                   # act on at most this many frames (None: every match)
    delay_ns: int = 0                          # delay
    fifo: bool = False                         # delay: the sender's later frames wait behind the delayed one
    mutate: Callable[[Frame], Frame] | None = None   # mutate_payload
    hits: list[tuple[int, str, Frame]] = field(default_factory=list)
    active: bool = True

    def matches(self, sender: str, frame: Frame) -> bool:
        return (self.active and (self.sender is None or self.sender == sender)
                and (self.count is None or len(self.hits) < self.count) and bool(self.predicate(frame)))

    def hit(self, t_ns: int, sender: str, frame: Frame) -> None:
        self.hits.append((t_ns, sender, frame))

    def cancel(self) -> None:
        self.active = False


STAGE = {"delay": "queued", "drop": "start", "corrupt": "start", "mutate_payload": "end", "duplicate": "end"}


def flip_bit(byte_index: int = 0, bit: int = 0) -> Callable[[Frame], Frame]:
    """A `mutate` function for mutate_payload: flips one data bit (nothing if the frame is shorter)."""

    def mutate(frame: Frame) -> Frame:
        if byte_index >= len(frame.data):
            return frame
        data = bytearray(frame.data)
        data[byte_index] ^= 1 << bit
        return Frame(frame.can_id, bytes(data), frame.rtr, frame.rtr_dlc)

    return mutate


def with_data(data: bytes) -> Callable[[Frame], Frame]:
    """A `mutate` function for mutate_payload: replaces the data (e.g. a short DLC)."""
    return lambda frame: Frame(frame.can_id, bytes(data), frame.rtr, frame.rtr_dlc)


def match_id(*can_ids: int) -> Predicate:
    """A predicate matching frames by identifier."""
    ids = frozenset(can_ids)
    return lambda frame: frame.can_id in ids
