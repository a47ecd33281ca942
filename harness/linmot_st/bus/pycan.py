"""Adapters to real python-can buses: serve a sans-I/O node in real time, open a bus from a short spec.

`NodeServer` runs a node (the bus node protocol of docs/architecture.md section 3: `on_frame`,
`on_timer`, `next_timer_ns`) on any python-can `Bus` from one background thread. The node's clock is
the wall clock (monotonic), in ns since the server started, so a node written for virtual time runs
unchanged. Every call into the node happens on the server thread while holding `server.lock`; other
threads that inspect or change the node take the same lock (or use `server.call`).

A node with an `rx_filter` (bus/node.py: the CAN-IDs it reacts to, the same attribute the simulated bus reads)
gets it as the bus's receive filters, kept up to date as it changes: on SocketCAN the kernel then wakes the
server only for those frames, so a node's answers are not queued behind the rest of a busy bus.
"""

from __future__ import annotations

import heapq
import logging
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable
from typing import Any

from .frame import Frame
from .node import check_node, is_filtered

log = logging.getLogger(__name__)

# Longest a recv() blocks, so that stop() and newly due frames are served promptly.
_POLL_S = 0.02
_UNSET = object()       # no filter given to the bus yet (None is a filter: every frame)


class NodeServer:
    """Serve a sans-I/O node on a python-can Bus from a background thread, in real time.

    ``on_start(t_ns)`` (for example the drive's ``power_on``) runs on the server thread at t = 0,
    before any frame is received; frames it returns are sent like any other.
    """

    def __init__(self, node: Any, bus: Any, *, on_start: Callable[[int], Any] | None = None,
                 name: str | None = None) -> None:
        check_node(node)
        self.node = node
        self.bus = bus
        self.name = name or type(node).__name__
        self.lock = threading.RLock()
        self._on_start = on_start
        self._stop = threading.Event()
        self._thread: threading.Thread | None = None
        self._t0 = 0
        self._out: list[tuple[int, int, Frame]] = []   # heap of (ready_ns, seq, frame)
        self._seq = 0
        self.error: BaseException | None = None        # first exception raised by the node
        self.frames_received = 0
        self.frames_sent = 0
        self.send_errors = 0
        self._has_filter = is_filtered(node)
        self._filtered: object = _UNSET

    # -- life cycle -------------------------------------------------------------------------
    def start(self) -> NodeServer:
        if self._thread is not None:
            raise RuntimeError(f"{self.name}: server already started")
        self._t0 = time.monotonic_ns()
        self._stop.clear()
        self._thread = threading.Thread(target=self._run, name=f"NodeServer[{self.name}]", daemon=True)
        self._thread.start()
        return self

    def stop(self, timeout: float = 2.0) -> None:
        """Stop serving and join the thread; re-raises the first exception the node raised."""
        thread, self._thread = self._thread, None
        if thread is not None:
            self._stop.set()
            thread.join(timeout)
            if thread.is_alive():
                raise RuntimeError(f"{self.name}: server thread did not stop within {timeout} s")
        if self.error is not None:
            err, self.error = self.error, None
            raise RuntimeError(f"{self.name}: the node raised {err!r}") from err

    @property
    def running(self) -> bool:
        return self._thread is not None and self._thread.is_alive()

    def __enter__(self) -> NodeServer:
        return self.start() if self._thread is None else self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    # -- clock and access -------------------------------------------------------------------
    def now_ns(self) -> int:
        """The node's time: wall-clock ns since start()."""
        return time.monotonic_ns() - self._t0

    def call(self, fn: Callable[..., Any], *args: Any) -> Any:
        """Call ``fn(*args)`` under the node lock; a list of (ready_ns, Frame) it returns is sent."""
        with self.lock:
            result = fn(*args)
            if isinstance(result, (list, tuple)) and all(
                    isinstance(x, tuple) and len(x) == 2 and isinstance(x[1], Frame) for x in result):
                self._queue(result)
        return result

    # -- the thread -------------------------------------------------------------------------
    def _queue(self, frames: Iterable[tuple[int, Frame]] | None) -> None:
        for ready, frame in frames or ():
            self._seq += 1
            heapq.heappush(self._out, (ready, self._seq, frame))

    def _fail(self, exc: BaseException) -> None:
        log.exception("%s: node raised", self.name)
        if self.error is None:
            self.error = exc

    def _filter(self) -> None:
        """Give the bus the node's rx_filter when it changed (called under the lock); None: every frame."""
        accepts = self.node.rx_filter
        if accepts != self._filtered:
            self._filtered = accepts
            self.bus.set_filters(None if accepts is None else
                                 [{"can_id": i, "can_mask": 0x7FF, "extended": False} for i in sorted(accepts)])

    def _run(self) -> None:
        node, bus, out = self.node, self.bus, self._out
        if self._on_start is not None:
            try:
                with self.lock:
                    self._queue(self._on_start(0))
            except Exception as exc:  # noqa: BLE001 - reported by stop()
                self._fail(exc)
        while not self._stop.is_set():
            now = self.now_ns()
            try:
                with self.lock:
                    if self._has_filter:
                        self._filter()
                    due = node.next_timer_ns()
                    if due is not None and due <= now:
                        self._queue(node.on_timer(now))
                        due = node.next_timer_ns()
            except Exception as exc:  # noqa: BLE001
                self._fail(exc)
                due = None
            while out and out[0][0] <= now:
                frame = heapq.heappop(out)[2]
                try:
                    bus.send(frame.to_message(timestamp=time.time()))
                    self.frames_sent += 1
                except Exception as exc:  # noqa: BLE001 - a full Tx queue must not kill the server
                    self.send_errors += 1
                    log.warning("%s: send %s failed: %s", self.name, frame, exc)
            wake = min(x for x in (due, out[0][0] if out else None, now + int(_POLL_S * 1e9)) if x is not None)
            msg = bus.recv(timeout=max(0.0, (wake - self.now_ns()) / 1e9))
            if msg is None or msg.is_error_frame or msg.is_extended_id or getattr(msg, "is_fd", False):
                continue
            self.frames_received += 1
            try:
                frame = Frame.from_message(msg)
                with self.lock:
                    self._queue(node.on_frame(frame, self.now_ns()))
            except Exception as exc:  # noqa: BLE001
                self._fail(exc)


class OwnFrames:
    """Tells a socket's own frames, returned by a bus opened with receive_own_messages=True, from the others.

    python-can's `is_rx` is not enough: on SocketCAN it is False for every frame sent from this host
    (MSG_DONTROUTE), whichever socket sent it, so a drive served by another process on the same vcan0 looks
    like an echo. A socket's own frames come back in the order it sent them: a message with is_rx False that
    equals the oldest frame sent and not yet seen back is one of ours; any other is another node's.
    """

    LIMIT = 4096            # sent frames remembered (a bus that never returns them must not grow without end)

    def __init__(self) -> None:
        self._sent: deque = deque()

    @staticmethod
    def _key(msg: Any) -> tuple:
        return msg.arbitration_id, bool(msg.is_remote_frame), bytes(msg.data or b"")

    def sent(self, msg: Any) -> None:
        self._sent.append(self._key(msg))
        if len(self._sent) > self.LIMIT:
            self._sent.popleft()

    def is_own(self, msg: Any) -> bool:
        if getattr(msg, "is_rx", True):
            return False
        key, sent = self._key(msg), self._sent
        if key not in sent:
            return False
        while sent.popleft() != key:        # frames sent before it that never came back (a lost echo)
            pass
        return True


DEFAULT_VIRTUAL_CHANNEL = "linmot-st"


def parse_bus_spec(spec: str, *, where: str | None = None,
                   forms: str = "virtual[:CHANNEL] or INTERFACE:CHANNEL") -> tuple[str, str]:
    """Check a bus spec without opening anything and return (interface, channel).

    ``virtual`` or ``virtual:CHANNEL`` (default channel "linmot-st"), ``socketcan:CHANNEL``, or
    ``INTERFACE:CHANNEL`` for any interface python-can knows, except ``udp_multicast`` (its traffic
    leaves the machine). Raises ValueError whose message reads ``<where>: <problem>`` (`where`
    defaults to ``bus spec '<spec>'``); `forms` names the accepted forms in that message (a caller
    may accept more, such as ``sim``).
    """
    interface, _, channel = spec.partition(":")
    interface, channel = interface.strip().lower(), channel.strip()
    where = where or f"bus spec {spec!r}"
    if not interface or (interface != "virtual" and not channel):
        raise ValueError(f"{where}: expected {forms} such as socketcan:can0 "
                         f"(an interface other than virtual needs a channel)")
    if interface == "udp_multicast":
        raise ValueError(f"{where}: the udp_multicast interface is not supported: its traffic leaves the machine")
    from can.interfaces import VALID_INTERFACES

    if interface not in VALID_INTERFACES:
        known = sorted(set(VALID_INTERFACES) - {"udp_multicast"})
        raise ValueError(f"{where}: python-can has no interface {interface!r} (it has {', '.join(known)})")
    return interface, channel or DEFAULT_VIRTUAL_CHANNEL


def open_bus(spec: str, *, bitrate: int = 500_000, **kwargs: Any):
    """Open a python-can Bus from a short spec (parse_bus_spec): ``virtual``, ``virtual:CHANNEL``,
    ``socketcan:CHANNEL``, or ``INTERFACE:CHANNEL``. ValueError for a bad spec; opening may raise
    can.CanError or OSError (no such adapter or interface). The bit rate of a SocketCAN interface is
    set with `ip link`, so `bitrate` is not passed to it."""
    import can

    interface, channel = parse_bus_spec(spec)
    if interface in ("virtual", "socketcan"):
        return can.Bus(interface=interface, channel=channel, **kwargs)
    return can.Bus(interface=interface, channel=channel, bitrate=bitrate, **kwargs)
