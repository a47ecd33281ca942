"""A direct link to one sans-I/O node in virtual time, for tests and quick experiments: no bus in between,
frames are delivered at their ready time and take no bus time.

    link = DirectLink(E1100Drive(1))          # powers the drive on and waits for its boot-up message
    link.sdo("40 00 10 00 00 00 00 00")       # -> the 8 response bytes, or None after the timeout
"""

from __future__ import annotations

import heapq
import itertools

from ..bus.frame import Frame

S = 1_000_000_000


def hexbytes(data: bytes | str) -> bytes:
    return bytes.fromhex(data) if isinstance(data, str) else bytes(data)


class DirectLink:
    def __init__(self, node, t_ns: int = 0, *, power_on: bool = True, boot_timeout_ns: int = 60 * S):
        self.node = node
        self.t = t_ns
        self.received: list[tuple[int, Frame]] = []      # every frame the node sent, with its time
        self._pending: list[tuple[int, int, Frame]] = []
        self._seq = itertools.count()
        if power_on:
            node.power_on(t_ns)
            if self.wait_for(lambda f: f.can_id == 0x700 + node.node_id, boot_timeout_ns) is None:
                raise RuntimeError("the node sent no boot-up message")

    def _push(self, frames) -> None:
        for ready, frame in frames or ():
            heapq.heappush(self._pending, (ready, next(self._seq), frame))

    def _step(self, t_end: int) -> bool:
        """Process the next event at or before t_end; False when there is none."""
        timer = self.node.next_timer_ns()
        nxt = self._pending[0][0] if self._pending else None
        if timer is not None and timer <= t_end and (nxt is None or timer <= nxt):
            self.t = max(self.t, timer)
            self._push(self.node.on_timer(self.t))
            return True
        if nxt is not None and nxt <= t_end:
            ready, _, frame = heapq.heappop(self._pending)
            self.t = max(self.t, ready)
            self.received.append((self.t, frame))
            return True
        return False

    def run_until(self, t_ns: int) -> list[tuple[int, Frame]]:
        """Advance to t_ns; returns the frames the node sent meanwhile."""
        start = len(self.received)
        while self._step(t_ns):
            pass
        self.t = max(self.t, t_ns)
        return self.received[start:]

    def advance(self, dt_ns: int) -> list[tuple[int, Frame]]:
        return self.run_until(self.t + dt_ns)

    def send(self, frame: Frame, dt_ns: int = 0) -> None:
        """Deliver `frame` to the node dt_ns from now."""
        self.run_until(self.t + dt_ns)
        self._push(self.node.on_frame(frame, self.t))

    def wait_for(self, predicate, timeout_ns: int) -> Frame | None:
        """Run until the node sends a frame matching `predicate` (returned) or timeout_ns passes (None)."""
        t_end = self.t + timeout_ns
        start = len(self.received)
        while True:
            for _, frame in self.received[start:]:
                if predicate(frame):
                    return frame
            start = len(self.received)
            if not self._step(t_end):
                self.t = max(self.t, t_end)
                return None

    def sdo(self, request: bytes | str, timeout_ns: int = 10 * S, node_id: int | None = None) -> bytes | None:
        """Send an SDO request (8 bytes, or hex text) and return the response bytes (None: no answer)."""
        nid = self.node.node_id if node_id is None else node_id
        self.send(Frame(0x600 + nid, hexbytes(request)))
        frame = self.wait_for(lambda f: f.can_id == 0x580 + nid, timeout_ns)
        return None if frame is None else frame.data

    def nmt(self, command: int, node_id: int | None = None) -> None:
        self.send(Frame(0x000, bytes([command, self.node.node_id if node_id is None else node_id])))
