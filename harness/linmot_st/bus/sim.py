"""The deterministic simulated CAN bus: a discrete-event model in virtual time (ns).

Participants are sans-I/O nodes (docs/architecture.md section 3) and endpoints (the PLC). Each has one
transmit queue served in order of ready time (FIFO among equal times), like a CAN controller with one
transmit buffer fed by a driver queue. Only the head of each queue competes for the bus. A node with
`tx_by_priority` has one buffer per CAN-ID instead (its ready frame of lowest CAN-ID competes; a frame of a
CAN-ID whose earlier frame is still unsent when it becomes ready replaces it). A node with `rx_filter` (bus/node.py: a set of CAN-IDs) is
offered only those frames, as by a CAN controller's acceptance filter.

Timing. A frame started at s ends at e = s + frame_length_bits * bit time (SOF..EOF, stuff bits
included); receivers get it at e, the bus is free again at e + 3 bit times (interframe space).
Arbitration at time T takes every queue head ready at or before T, the lowest identifier wins; equal
identifiers from different participants go in attach order (on a real bus they would collide). The
frames a node returns get its latency added to their ready times.

Order of events at one instant: frame end (delivery), scheduled actions, node timers, then
arbitration, so a frame made ready by any of the first three at T still competes at T.
`run_until(t)` processes everything up to t except a transmission start at exactly t: that one is
decided when time moves on, so frames an endpoint sends at t (the PLC's scan time) join it. It first
asks every node for its next_timer_ns() again, so a node changed from outside between two calls (a
drive powered on after it was attached) is served from that call on.
"""

from __future__ import annotations

import heapq
from bisect import insort
from collections.abc import Callable, Iterable
from typing import Any, NamedTuple

from .bits import ERROR_FRAME_BITS, IFS_BITS, frame_length_bits
from .faults import STAGE, Fault, Predicate
from .frame import Frame
from .node import check_node, is_filtered
from .stats import bus_stats
from .trace import write_trace

STANDARD_BITRATES = (125_000, 250_000, 500_000, 1_000_000)
_new_tuple = tuple.__new__
TEC_BUS_OFF = 256   # transmit error counter: +8 per transmit error, -1 per success (CAN 2.0 fault confinement)
# "no timer" / "empty queue" in the bus's per-participant lists of timers and queue heads: later than any time, so
# that the earliest of each is one min() in C rather than a loop over the participants per event
NEVER = 1 << 256


class TraceEntry(NamedTuple):
    start_ns: int
    end_ns: int          # end of EOF (of the error frame for status "error"); the bus is idle 3 bits later
    sender: str
    frame: Frame         # as the receivers saw it (after mutate_payload)
    status: str          # "ok", "mutated" (mutate_payload) or "error" (destroyed by an error frame)


class _Part:
    """A participant's state on the bus."""

    __slots__ = ("name", "node", "latency", "queue", "index", "order", "tec", "bus_off", "sent", "discarded",
                 "has_timer", "observe", "hold_until", "by_priority", "accepts", "filtered", "overwritten")

    def __init__(self, name: str, node: Any, latency: int, order: int) -> None:
        self.name, self.node, self.latency, self.order = name, node, latency, order
        self.has_timer = not isinstance(node, Endpoint)   # an endpoint never has a timer
        # a node that computes ahead of the bus (the emulated drive) brings its inspectable state to the
        # bus time after each run_until
        self.observe = getattr(node, "observe", None)
        self.queue: list[tuple[int, int, Frame]] = []    # (ready_ns, seq, frame), sorted
        self.index = 0           # its place in SimBus._parts, and so in SimBus._timers and SimBus._heads
        self.tec = 0
        self.bus_off = False
        self.sent = 0
        self.discarded = 0
        self.hold_until = 0      # a FIFO delay holds the frames queued behind the delayed one until then
        # a node with several transmit buffers sends its ready frame of highest priority first (the node says
        # so: `tx_by_priority`); the others (the PLC's mailbox) send in the order they queued
        self.by_priority = bool(getattr(node, "tx_by_priority", False))
        self.overwritten = 0     # frames overwritten in their buffer by a later one of their CAN-ID (by_priority)
        # a node's acceptance filter (`rx_filter`: the CAN-IDs its on_frame reacts to, None: every frame), as
        # a CAN controller's: the bus offers it no other frame. Read again after each event the node handled.
        self.filtered = is_filtered(node)
        self.accepts = getattr(node, "rx_filter", None)


class Endpoint:
    """A participant that is not a node (the PLC): frames in by `send`, frames out by `receive`."""

    def __init__(self, bus: SimBus, name: str) -> None:
        self.bus, self.name = bus, name
        self.inbox: list[tuple[int, Frame]] = []   # (end time, frame) in delivery order

    def send(self, frame: Frame, t_ns: int | None = None) -> None:
        """Queue a frame, ready at t_ns (default: the bus's current time)."""
        self.bus._submit(self.bus._parts_by_name[self.name], self.bus.now if t_ns is None else t_ns, frame)

    def receive(self) -> list[tuple[int, Frame]]:
        """The frames delivered since the last call, as (end time, frame)."""
        got, self.inbox = self.inbox, []
        return got

    # the node protocol, so that the bus treats it like any participant
    def on_frame(self, frame: Frame, t_ns: int) -> tuple:
        self.inbox.append((t_ns, frame))
        return ()

    def on_timer(self, t_ns: int) -> tuple:
        return ()

    def next_timer_ns(self) -> None:
        return None


class SimBus:
    def __init__(self, bitrate: int = 500_000, *, rx_filters: bool = True) -> None:
        if not isinstance(bitrate, int) or bitrate <= 0 or 1_000_000_000 % bitrate:
            raise ValueError(f"bit rate {bitrate!r} must be a positive integer dividing 1e9 bit/s "
                             f"(e.g. one of {STANDARD_BITRATES})")
        self.bitrate = bitrate
        self.bit_ns = 1_000_000_000 // bitrate
        self.now = 0
        self.trace: list[TraceEntry] = []
        self.faults: list[Fault] = []
        self._parts: list[_Part] = []
        self._parts_by_name: dict[str, _Part] = {}
        # per participant, in the order of _parts, then a NEVER that is no one's: its next timer and the ready time
        # of its queue's head (NEVER: none), kept current wherever either changes; the event loop takes the earliest
        # of each with min() (the first of equal times: the participant attached first, as a loop over them would)
        self._timers: list[int] = [NEVER]
        self._heads: list[int] = [NEVER]
        self._observers: list[Callable[[int], Any]] = []     # the nodes' observe(), in attach order
        # CAN-ID -> the participants whose acceptance filter takes it, in attach order: made at a frame of that ID,
        # dropped when any filter changes (a node's rx_filter read after a call into it is another object); kept
        # only while every filter is None or a frozenset (a set the node could change in place is looked at anew)
        self._receivers: dict[int, tuple[_Part, ...]] = {}
        self._receivers_kept = True
        self._order = 0
        self._seq = 0
        self._tx: list | None = None     # in flight: [part, frame, start, end, status, retransmit]
        self._idle_at = 0                # the bus is free for arbitration from this time on
        self._actions: list[tuple[int, int, Callable[[int], Any]]] = []
        # frame length by (id, data, rtr, rtr_dlc): a tuple hashes in C, a Frame through its dataclass __hash__
        self._length_cache: dict[tuple, int] = {}
        self._stage: dict[str, list[Fault]] = {"queued": [], "start": [], "end": []}
        # nodes' acceptance filters (`rx_filter`) are used; False offers every frame to every node (the
        # reference the filtered runs are compared with: tests/bus/test_bus_rx_filter.py)
        self._rx_filters = rx_filters      # read when a node is attached

    # -- participants -----------------------------------------------------------------------
    def attach(self, node: Any, name: str | None = None, latency_ns: int = 0) -> str:
        """Attach a sans-I/O node; its frames get ``latency_ns`` added to their ready times."""
        check_node(node)
        if latency_ns < 0:
            raise ValueError(f"latency_ns must be >= 0, got {latency_ns}")
        name = name or getattr(node, "name", None) or f"node{self._order + 1}"
        if name in self._parts_by_name:
            raise ValueError(f"a participant named {name!r} is already on the bus")
        self._order += 1
        part = _Part(name, node, latency_ns, self._order)
        if not self._rx_filters:
            part.filtered, part.accepts = False, None
        part.index = len(self._parts)
        self._parts.append(part)
        self._timers.insert(part.index, NEVER)
        self._heads.insert(part.index, NEVER)
        self._parts_by_name[name] = part
        self._observers = [p.observe for p in self._parts if p.observe is not None]
        self._filters_changed()
        self._read_timer(part)
        return name

    def endpoint(self, name: str = "plc", latency_ns: int = 0) -> Endpoint:
        """A participant driven from outside (the PLC): ``send(frame, t_ns)``, ``receive()``."""
        ep = Endpoint(self, name)
        self.attach(ep, name, latency_ns)
        return ep

    def detach(self, name: str) -> None:
        """Remove a participant now (see remove_node for a scheduled removal)."""
        self._remove(self._part(name), self.now)

    def node(self, name: str) -> Any:
        return self._part(name).node

    @property
    def names(self) -> list[str]:
        return [p.name for p in self._parts]

    def _part(self, name: str) -> _Part:
        try:
            return self._parts_by_name[name]
        except KeyError:
            raise KeyError(f"no participant named {name!r} on the bus (have: {', '.join(self.names)})") from None

    # -- scheduled actions and node faults --------------------------------------------------
    def call_at(self, t_ns: int, fn: Callable[[int], Any]) -> None:
        """Call ``fn(t)`` at virtual time t_ns (after deliveries at t, before timers and arbitration at t)."""
        if t_ns < self.now:
            raise ValueError(f"call_at({t_ns}) is in the past (bus time is {self.now})")
        self._seq += 1
        heapq.heappush(self._actions, (t_ns, self._seq, fn))

    def reset_node(self, name: str, at_ns: int, hook: str | None = "power_on") -> None:
        """At ``at_ns`` the node's controller is reset: its transmit queue is lost (a frame it is sending
        is cut off by an error frame), its error counter cleared, then ``node.<hook>(t)`` is called (the
        drive's power_on); frames the hook returns are queued."""
        part = self._part(name)
        if hook is not None and not callable(getattr(part.node, hook, None)):
            raise AttributeError(f"node {name!r} has no {hook}() method to call on reset")

        def reset(t: int) -> None:
            if self._parts_by_name.get(name) is not part:
                return   # removed meanwhile
            self._abort_tx_of(part, t)
            part.queue.clear()
            self._heads[part.index] = NEVER
            part.hold_until = 0
            part.tec, part.bus_off = 0, False
            if hook is not None:
                self._queue_all(part, t, getattr(part.node, hook)(t))
            self._read_timer(part)

        self.call_at(at_ns, reset)

    def remove_node(self, name: str, at_ns: int) -> None:
        """At ``at_ns`` the participant leaves the bus (power cut): its queue is lost, it gets no more
        frames, and a frame it is sending is cut off by an error frame."""
        part = self._part(name)
        self.call_at(at_ns, lambda t: self._remove(part, t) if self._parts_by_name.get(name) is part else None)

    def _remove(self, part: _Part, t: int) -> None:
        self._abort_tx_of(part, t)
        self._parts.remove(part)
        del self._timers[part.index], self._heads[part.index]
        for i, p in enumerate(self._parts):
            p.index = i
        self._observers = [p.observe for p in self._parts if p.observe is not None]
        self._filters_changed()
        del self._parts_by_name[part.name]
        part.queue.clear()

    def _abort_tx_of(self, part: _Part, t: int) -> None:
        tx = self._tx
        if tx is not None and tx[0] is part and t < tx[3]:
            # The receivers see a stuff or form error at once and signal it: model the error frame from t.
            tx[3] = t + ERROR_FRAME_BITS * self.bit_ns
            tx[4], tx[5] = "error", False
            self._idle_at = tx[3] + IFS_BITS * self.bit_ns

    # -- frame faults ------------------------------------------------------------------------
    def _add_fault(self, fault: Fault) -> Fault:
        self.faults.append(fault)
        self._stage[STAGE[fault.kind]].append(fault)
        return fault

    def drop(self, predicate: Predicate, *, sender: str | None = None, count: int | None = None) -> Fault:
        """Matching frames never reach the bus (lost in the sender; no bus time, not in the trace)."""
        return self._add_fault(Fault("drop", predicate, sender, count))

    def delay(self, predicate: Predicate, delay_ns: int, *, sender: str | None = None,
              count: int | None = None, fifo: bool = False) -> Fault:
        """Matching frames become ready ``delay_ns`` later than the sender asked. Later frames of the
        same sender that are ready earlier overtake them, unless ``fifo``: then they wait behind the
        delayed frame, as behind a sender that is slow but keeps its order (a sequential SDO server)."""
        if delay_ns < 0:
            raise ValueError("delay_ns must be >= 0")
        return self._add_fault(Fault("delay", predicate, sender, count, delay_ns=delay_ns, fifo=fifo))

    def duplicate(self, predicate: Predicate, *, sender: str | None = None, count: int | None = None) -> Fault:
        """Matching frames are transmitted twice in a row (receivers get both)."""
        return self._add_fault(Fault("duplicate", predicate, sender, count))

    def corrupt(self, predicate: Predicate, *, sender: str | None = None, count: int | None = None) -> Fault:
        """Matching transmissions are destroyed: the receivers' error frame follows the ACK delimiter,
        nobody receives the frame, the sender retransmits it automatically when the bus is idle.
        Each counts +8 on the sender's transmit error counter; at 256 the sender goes bus-off."""
        return self._add_fault(Fault("corrupt", predicate, sender, count))

    def mutate_payload(self, predicate: Predicate, mutate: Callable[[Frame], Frame], *,
                       sender: str | None = None, count: int | None = None) -> Fault:
        """Receivers get ``mutate(frame)`` instead of the frame: an undetected corruption, which a sound
        CAN bus cannot produce. Use it only to test a receiver's robustness against bad content."""
        return self._add_fault(Fault("mutate_payload", predicate, sender, count, mutate=mutate))

    # -- running ----------------------------------------------------------------------------
    def _read_timer(self, part: _Part) -> None:
        t = part.node.next_timer_ns()
        now = self.now                      # max(int(t), now) without the builtin's call: after every timer
        self._timers[part.index] = NEVER if t is None else (int(t) if t > now else now)
        if part.filtered:
            accepts = part.node.rx_filter
            if accepts is not part.accepts:
                part.accepts = accepts
                self._filters_changed()

    def _filters_changed(self) -> None:
        self._receivers.clear()
        self._receivers_kept = all(p.accepts is None or type(p.accepts) is frozenset for p in self._parts)

    def _submit(self, part: _Part, ready: int, frame: Frame) -> None:
        if ready < self.now:
            raise ValueError(f"{part.name}: frame {frame} ready at {ready} ns is in the past "
                             f"(bus time is {self.now} ns)")
        self._enqueue(part, ready + part.latency, frame)

    def _queue_all(self, part: _Part, t: int, frames: Iterable[tuple[int, Frame]] | None) -> None:
        latency = part.latency
        for ready, frame in frames or ():
            if ready < t:
                raise ValueError(f"{part.name}: returned frame {frame} ready at {ready} ns, before the "
                                 f"event time {t} ns")
            self._enqueue(part, ready + latency, frame)

    def _enqueue(self, part: _Part, ready: int, frame: Frame) -> None:
        if part.bus_off:
            part.discarded += 1
            return
        queued_faults = self._stage["queued"]
        if queued_faults:
            for fault in queued_faults:
                if fault.matches(part.name, frame):
                    fault.hit(ready, part.name, frame)
                    ready += fault.delay_ns
                    if fault.fifo:
                        part.hold_until = max(part.hold_until, ready)
        if ready < part.hold_until:
            ready = part.hold_until
        q = part.queue
        self._seq += 1
        if not q or ready >= q[-1][0]:
            q.append((ready, self._seq, frame))
        else:
            insort(q, (ready, self._seq, frame))
        self._heads[part.index] = q[0][0]

    def next_event_ns(self, refresh: bool = False) -> int | None:
        """Time of the next event (frame end, action, timer, transmission start), None if there is none.
        `refresh` reads every node's timer first, as run_until does (a node changed from outside)."""
        if refresh:
            self._refresh_timers()
        t = min(self._timers)
        if self._tx is not None:
            t = min(t, self._tx[3])
        else:
            ready = min(self._heads)
            if ready != NEVER:
                t = min(t, max(self._idle_at, ready))
        if self._actions:
            t = min(t, self._actions[0][0])
        return None if t == NEVER else t

    def run_until(self, t_end: int, refresh: bool = True) -> None:
        """Advance virtual time to t_end, processing every event up to it (see the module doc). `refresh`
        False skips reading every node's timer first: for a caller that just did (next_event_ns(refresh=True))
        and changed no node since."""
        if t_end < self.now:
            raise ValueError(f"run_until({t_end}): bus time is already {self.now} ns")
        parts, actions, timers, heads = self._parts, self._actions, self._timers, self._heads
        if refresh:
            self._refresh_timers()
        while True:
            tx = self._tx
            # the earliest event; ties go to the first kind checked
            if tx is not None:
                t_next, kind = tx[3], 0
            else:
                t_next, kind = t_end + 1, -1
            if actions and actions[0][0] < t_next:
                t_next, kind = actions[0][0], 1
            pt = min(timers)                      # the earliest timer (NEVER: none)
            if pt < t_next:
                t_next, kind = pt, 2
            if tx is None:
                ready = min(heads)                # the earliest queue head (NEVER: every queue is empty)
                if ready != NEVER:
                    t_arb = ready if ready > self._idle_at else self._idle_at
                    if t_arb < t_next and t_arb < t_end:
                        t_next, kind = t_arb, 3
            if t_next > t_end:              # also when nothing is pending (kind -1: t_next is t_end + 1)
                break
            self.now = t_next
            if kind == 0:
                self._end_tx(tx)
            elif kind == 1:
                heapq.heappop(actions)[2](t_next)
            elif kind == 2:
                self._fire_timer(parts[timers.index(t_next)], t_next)    # the first part whose timer it is
            else:
                self._arbitrate(t_next)
        self.now = t_end
        for observe in self._observers:
            observe(t_end)

    def _refresh_timers(self) -> None:
        # A node may have been changed from outside since the bus last called it (attach, then
        # power_on(0)): read every timer again, so that the order of such calls does not matter.
        now = self.now
        timers = self._timers
        for p in self._parts:
            if p.has_timer:
                t = p.node.next_timer_ns()
                timers[p.index] = NEVER if t is None else (t if t > now else now)
                if p.filtered:
                    accepts = p.node.rx_filter
                    if accepts is not p.accepts:
                        p.accepts = accepts
                        self._filters_changed()

    def _fire_timer(self, part: _Part, t: int) -> None:
        self._queue_all(part, t, part.node.on_timer(t))
        self._read_timer(part)
        timer = self._timers[part.index]
        if timer <= t:
            raise RuntimeError(f"{part.name}: next_timer_ns() is still {timer} after on_timer({t}); "
                               f"a node must move its timer forward when it fires")

    @staticmethod
    def _overwrite(part: _Part, t: int) -> None:
        """One transmit buffer per CAN-ID (a `tx_by_priority` node): of its frames ready by t, an earlier one of
        a CAN-ID a later-ready one also has was overwritten in its buffer before the bus took it (CANopenNode
        copies a PDO's new data into its busy buffer): dropped, counted. Frames ready at the same time stay (a
        FIFO delay, a sequential server's late answer and the next, holds them so)."""
        q = part.queue
        n = 0
        while n < len(q) and q[n][0] <= t:
            n += 1
        if n < 2:
            return
        newest: dict[int, int] = {}        # CAN-ID -> ready time of its latest-ready frame
        for r, _, f in q[:n]:
            newest[f.can_id] = r
        if len(newest) == n:
            return
        kept = [e for e in q[:n] if e[0] >= newest[e[2].can_id]]
        part.overwritten += n - len(kept)
        q[:n] = kept

    def _arbitrate(self, t: int) -> None:
        parts, heads = self._parts, self._heads
        while True:
            winner, best, at = None, 0x800, 0
            for n, head in enumerate(heads):    # the participants whose queue's head is ready (NEVER: empty)
                if head <= t:
                    p = parts[n]
                    q = p.queue
                    k = 0
                    if p.by_priority:       # its ready frame of highest priority (the queue is by ready time)
                        if len(q) > 1:
                            self._overwrite(p, t)
                            heads[n] = q[0][0]
                        for i in range(1, len(q)):
                            if q[i][0] > t:
                                break
                            if q[i][2].can_id < q[k][2].can_id:
                                k = i
                    if q[k][2].can_id < best:
                        winner, best, at = p, q[k][2].can_id, k
            if winner is None:
                return
            q = winner.queue
            frame = q.pop(at)[2]
            self._heads[winner.index] = q[0][0] if q else NEVER
            status = "ok"
            start_faults = self._stage["start"]
            if start_faults:
                for fault in start_faults:
                    if fault.matches(winner.name, frame):
                        fault.hit(t, winner.name, frame)
                        status = fault.kind
                        break
                if status == "drop":
                    continue   # lost before the bus: the next candidate arbitrates at the same instant
            key = (frame.can_id, frame.data, frame.rtr, frame.rtr_dlc)
            bits = self._length_cache.get(key)
            if bits is None:
                if len(self._length_cache) > 100_000:
                    self._length_cache.clear()
                bits = self._length_cache[key] = frame_length_bits(frame)
            if status == "corrupt":
                # the receivers' CRC check fails; their error flag starts after the ACK delimiter
                bits = bits - 7 + ERROR_FRAME_BITS
                end = t + bits * self.bit_ns
                self._tx = [winner, frame, t, end, "error", True]
            else:
                end = t + bits * self.bit_ns
                self._tx = [winner, frame, t, end, "ok", False]
            self._idle_at = end + IFS_BITS * self.bit_ns
            return

    def _end_tx(self, tx: list) -> None:
        part, frame, start, end, status, retransmit = tx
        self._tx = None
        if status == "error":
            self.trace.append(TraceEntry(start, end, part.name, frame, "error"))
            part.tec += 8
            if part.tec >= TEC_BUS_OFF:
                part.bus_off = True
                part.discarded += len(part.queue) + 1
                part.queue.clear()
                if self._parts_by_name.get(part.name) is part:     # (a removed sender's index is another's now)
                    self._heads[part.index] = NEVER
            elif retransmit and self._parts_by_name.get(part.name) is part:
                self._requeue_first(part, end, frame)
            return
        if part.tec:
            part.tec -= 1
        part.sent += 1
        sent = frame
        duplicate = False
        for fault in self._stage["end"]:
            if fault.matches(part.name, sent):
                fault.hit(end, part.name, sent)
                if fault.kind == "duplicate":
                    duplicate = True
                else:
                    frame = fault.mutate(frame)
                    status = "mutated"
        self.trace.append(_new_tuple(TraceEntry, (start, end, part.name, frame, status)))   # no Python __new__
        now = self.now
        cid = frame.can_id
        timers = self._timers
        # the receivers: every other participant whose acceptance filter takes the frame (a node it filters out is
        # untouched), as of the start of the delivery (a node's own call can change only its own filter)
        receivers = self._receivers.get(cid)
        if receivers is None:
            receivers = tuple(p for p in self._parts if p.accepts is None or cid in p.accepts)
            if self._receivers_kept:
                self._receivers[cid] = receivers
        for p in receivers:
            if p is not part:
                node = p.node
                out = node.on_frame(frame, end)
                if out:
                    self._queue_all(p, end, out)
                t = node.next_timer_ns()          # _read_timer, inlined: once per receiver and frame
                timers[p.index] = NEVER if t is None else (int(t) if t > now else now)
                if p.filtered:
                    accepts = node.rx_filter
                    if accepts is not p.accepts:
                        p.accepts = accepts
                        self._filters_changed()
        if duplicate and self._parts_by_name.get(part.name) is part:
            self._requeue_first(part, end, sent)

    def _requeue_first(self, part: _Part, t: int, frame: Frame) -> None:
        """Put a frame back at the head of the sender's queue (automatic retransmission)."""
        q = part.queue
        ready = min(t, q[0][0]) if q else t   # keeps the queue sorted; it is due at once either way
        self._seq += 1
        q.insert(0, (ready, self._seq, frame))
        self._heads[part.index] = ready

    # -- results -------------------------------------------------------------------------------
    def stats(self, t0_ns: int = 0, t1_ns: int | None = None):
        """Bus statistics over [t0, t1) (default: from 0 to the current time); see BusStats."""
        return bus_stats(self.trace, self.bit_ns, t0_ns, self.now if t1_ns is None else t1_ns)

    def write_trace(self, path) -> None:
        """Write the trace in the format of the file's extension (.log candump, .asc, .blf) with python-can."""
        write_trace(self.trace, path)
