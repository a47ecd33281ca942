"""Small sans-I/O bus nodes for tests, examples and benchmarks (no CANopen logic)."""

from __future__ import annotations

from collections.abc import Callable, Iterable

from .frame import Frame


class ScriptedNode:
    """Sends given frames at given times and records what it receives.

    ``replies(frame, t)`` may return frames to answer a received frame with (ready time >= t).
    """

    def __init__(self, script: Iterable[tuple[int, Frame]] = (),
                 replies: Callable[[Frame, int], list[tuple[int, Frame]]] | None = None) -> None:
        self.script = sorted(script, key=lambda x: x[0])
        self.replies = replies
        self.received: list[tuple[int, Frame]] = []
        self.resets: list[int] = []

    def on_frame(self, frame: Frame, t_ns: int):
        self.received.append((t_ns, frame))
        return self.replies(frame, t_ns) if self.replies else ()

    def on_timer(self, t_ns: int):
        due = [(t, f) for t, f in self.script if t <= t_ns]
        self.script = self.script[len(due):]
        return [(t_ns, f) for _, f in due]

    def next_timer_ns(self):
        return self.script[0][0] if self.script else None

    def power_on(self, t_ns: int):
        self.resets.append(t_ns)
        return ()


class EchoNode:
    """Answers each frame with identifier ``request_id`` by one with ``reply_id`` and the same data."""

    def __init__(self, request_id: int = 0x601, reply_id: int = 0x581) -> None:
        self.request_id, self.reply_id = request_id, reply_id
        self.count = 0

    def on_frame(self, frame: Frame, t_ns: int):
        if frame.can_id != self.request_id:
            return ()
        self.count += 1
        return [(t_ns, Frame(self.reply_id, frame.data, frame.rtr, frame.rtr_dlc))]

    def on_timer(self, t_ns: int):
        return ()

    def next_timer_ns(self):
        return None
