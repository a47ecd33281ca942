"""The bus node protocol (docs/architecture.md section 3): what the simulated bus and NodeServer require of a
sans-I/O node, written and checked here once.

A node may also have `rx_filter`: the CAN-IDs its `on_frame` reacts to from now on (None: every frame), as a
CAN controller's acceptance filter. Both transports read it again after each call into the node: the simulated
bus then offers the node no other frame, NodeServer makes it the python-can bus's receive filters.
"""

from __future__ import annotations

from collections.abc import Iterable
from collections.abc import Set as AbstractSet
from typing import Protocol

from .frame import Frame

Sent = Iterable[tuple[int, Frame]]     # frames to send, each with its ready time (>= the call's time)


class BusNode(Protocol):
    def on_frame(self, frame: Frame, t_ns: int) -> Sent | None:
        """A frame ended on the bus at t_ns."""

    def on_timer(self, t_ns: int) -> Sent | None:
        """Time reached next_timer_ns(); the node must move its timer past t_ns."""

    def next_timer_ns(self) -> int | None:
        """When on_timer is due next (None: no timed work)."""


class FilteredBusNode(BusNode, Protocol):
    rx_filter: AbstractSet[int] | None


_REQUIRED = ("on_frame", "on_timer", "next_timer_ns")


def check_node(node: object) -> None:
    """TypeError unless `node` has the methods of BusNode (the one check both transports make)."""
    for method in _REQUIRED:
        if not callable(getattr(node, method, None)):
            raise TypeError(f"{type(node).__name__} is not a bus node: it has no {method}() method")


def is_filtered(node: object) -> bool:
    """Whether the node states an acceptance filter (has `rx_filter`, even if it is None now)."""
    return hasattr(node, "rx_filter")
