"""Co-simulation: a PLC's CAN mailbox (T_CanMailbox, st_lib/types/can.st) coupled to a bus, scan by scan.

`CoSim` runs in virtual time against the simulated bus (docs/architecture.md section 5). Each scan at
PLC time t:
  1. bus.run_until(t): every frame whose transmission ended at or before t is delivered;
  2. the frames the PLC's endpoint received since the previous scan go into Rx[1..RxCount], in
     delivery order; beyond 32 the rest are dropped and counted in RxLost (as a PLC CAN driver does);
  3. plc.step(1);
  4. Tx[1..TxCount] are sent in order, ready at t, and TxCount is set to 0 (a TxCount outside 0..32, or
     a Tx frame with Id > 16#7FF or Dlc > 8, raises CoSimError: no CAN driver could send it).
Idle scans (`fast_idle`, the default): when the scan at t would receive nothing (no frame delivered, no
echo due, no bus event at or before t), the scans up to the next bus event run in one C call
(Plc.step_idle) with RxCount = 0, ending early after the scan that fills Tx or changes a variable that
run_until's predicate watches (its `idle_watch`). The bus sees the same frames at the same times as with
every scan stepped from Python (docs/plc-integration.md section 1.1; tests/cosim/test_cosim_idle.py).
With `echo` (the default) the mailbox's TxEcho is set and step 2 also puts each SDO request the PLC sent
(600h..67Fh) back into Rx once its transmission ended on the bus (Echo TRUE), in bus order with the
received frames: the transmit confirmation of a PLC CAN driver (docs/plc-integration.md section 1).
`RealTimeCoSim` does the same on a python-can bus against the wall clock (`linmot-st commission
--bus virtual|socketcan:CHANNEL`): scan k starts at the wall time of the PLC's clock, and the frames
received until then go into Rx.

Mailbox access uses the loader's bound accessors, each bound once on first use; where Rx and Tx have the library's
T_CanFrame layout, a frame is packed into (or unpacked from) the PLC's memory in one struct call (FrameCodec), so a
scan costs a few attribute accesses plus the PLC step.
"""

from __future__ import annotations

import struct
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

from linmot_st.bus.frame import Frame
from linmot_st.bus.pycan import OwnFrames
from linmot_st.bus.sim import SimBus
from linmot_st.plc import IdleWatch, Plc

if TYPE_CHECKING:
    import can

MAILBOX_FRAMES = 32   # T_CanFrames : ARRAY[1..32] OF T_CanFrame


def is_echoed(can_id: int) -> bool:
    """The PLC's frames the mailbox confirms (TxEcho): its SDO requests, 600h + node."""
    return 0x601 <= can_id <= 0x67F


class CoSimError(Exception):
    """The PLC put something into its mailbox that no CAN driver could send."""


class CoSimTimeout(TimeoutError):
    """run_until() reached max_scans (or its timeout) before the predicate held."""


# T_CanFrame's members as a driver writes and reads them (st_lib/types/can.st), and their struct codes
_FRAME_MEMBERS = {"ID": ("UINT", "H"), "DLC": ("USINT", "B"), "RTR": ("BOOL", "B"), "ECHO": ("BOOL", "B")}


class FrameCodec:
    """One ARRAY OF T_CanFrame in the PLC's memory as a struct.Struct per element: Id, Dlc, Rtr, Data (and Echo)
    packed or unpacked in one call, the same bytes the per-member accessors write (Data's unused bytes 0, BOOL 0/1).
    `of` gives None where the element is not exactly those members of those types (another mailbox type: the
    accessors then do it member by member)."""

    def __init__(self, view: memoryview, fmt: str, stride: int, echo: bool) -> None:
        self.view, self.stride, self.echo = view, stride, echo
        self.struct = struct.Struct(fmt)

    @classmethod
    def of(cls, var: Any, echo: bool) -> FrameCodec | None:
        info = getattr(var, "info", None)
        if info is None or not hasattr(var, "view") or info.kind != "array" or len(info.dims) != 1:
            return None
        elem = info.inner
        names = ["ID", "DLC", "RTR", "DATA"] + (["ECHO"] if echo else [])
        if elem.kind != "struct" or sorted(elem.field_order) != sorted(names):
            return None
        fmt, at = "=", 0           # native byte order, no implicit alignment: the offsets say where each member is
        for name in sorted(names, key=lambda n: elem.fields[n][0]):
            offset, t = elem.fields[name]
            if name == "DATA":
                ok = t.kind == "array" and t.size == 8 and t.inner.name in ("BYTE", "USINT")
                code, size = "8s", 8
            else:
                ok = t.kind == "elementary" and t.name == _FRAME_MEMBERS[name][0]
                code, size = _FRAME_MEMBERS[name][1], t.size
            if not ok or offset < at:
                return None
            fmt += "x" * (offset - at) + code     # padding between members: no member lies there
            at = offset + size
        codec = cls(var.view(), fmt, elem.size, echo)
        return codec if codec.struct.size <= elem.size else None

    def write(self, frames: list[Frame], echoes: list[bool] | None) -> None:
        """Elements 0..len(frames)-1 := frames (their Echo := echoes[i] where the element has it)."""
        pack, view, stride = self.struct.pack_into, self.view, self.stride
        for i, f in enumerate(frames):
            # a remote frame: its DLC, no data ("8s" pads with zero bytes, as the accessors' ljust did)
            dlc, data = (f.rtr_dlc, b"") if f.rtr else (len(f.data), f.data)
            if self.echo:
                pack(view, i * stride, f.can_id, dlc, f.rtr, data, bool(echoes and echoes[i]))
            else:
                pack(view, i * stride, f.can_id, dlc, f.rtr, data)

    def read(self, i: int) -> tuple:
        """(Id, Dlc, Rtr, Data as 8 bytes) of element i (0-based)."""
        return self.struct.unpack_from(self.view, i * self.stride)[:4]


class Mailbox:
    """Bound accessors of one T_CanMailbox variable of a PLC (RxCount, Rx, RxLost, TxCount, Tx, TxLost)."""

    def __init__(self, plc: Plc, path: str) -> None:
        self.plc = plc
        self.path = path
        try:
            self._rx_count = plc.var(f"{path}.RxCount")
            self._rx_lost = plc.var(f"{path}.RxLost")
            self._tx_count = plc.var(f"{path}.TxCount")
            self._tx_lost = plc.var(f"{path}.TxLost")
        except KeyError as exc:
            raise KeyError(f"{path} is not a T_CanMailbox variable of this PLC: {exc}") from None
        self._rx: list[tuple | None] = [None] * (MAILBOX_FRAMES + 1)   # 1-based, bound lazily
        self._tx: list[tuple | None] = [None] * (MAILBOX_FRAMES + 1)
        # TxEcho and Rx[i].Echo: absent from a mailbox type older than the transmit confirmation
        try:
            self._tx_echo = plc.var(f"{path}.TxEcho")
        except KeyError:
            self._tx_echo = None
        has_echo = self._tx_echo is not None
        try:
            self._rx_codec = FrameCodec.of(plc.var(f"{path}.Rx"), has_echo)
            self._tx_codec = FrameCodec.of(plc.var(f"{path}.Tx"), has_echo)
        except KeyError:        # a PLC that binds the members only: the accessors do it
            self._rx_codec = self._tx_codec = None

    @property
    def has_echo(self) -> bool:
        return self._tx_echo is not None

    def set_tx_echo(self, on: bool) -> None:
        """Tell the library whether Rx holds the echoes of the PLC's frames (an error without the field)."""
        if self._tx_echo is None:
            if on:
                raise KeyError(f"{self.path} has no TxEcho field: its T_CanMailbox predates the transmit "
                               "confirmation (use echo=False)")
            return
        self._tx_echo.value = on

    def _bind(self, which: str, i: int) -> tuple:
        """(Id, Dlc, Rtr, Data) accessors of one frame slot. Data is the whole ARRAY[0..7] OF BYTE when
        the loader offers raw byte access (one call per frame), else a list of its 8 elements."""
        var, p = self.plc.var, f"{self.path}.{which}[{i}]"
        data = var(f"{p}.Data")
        if not (hasattr(data, "write_bytes") and hasattr(data, "read_bytes") and getattr(data, "nbytes", 0) == 8):
            data = [var(f"{p}.Data[{j}]") for j in range(8)]
        echo = var(f"{p}.Echo") if self._tx_echo is not None else None
        return (var(f"{p}.Id"), var(f"{p}.Dlc"), var(f"{p}.Rtr"), data, echo)

    @property
    def rx_count(self) -> int:
        return self._rx_count.value

    @property
    def rx_lost(self) -> int:
        return self._rx_lost.value

    @property
    def tx_lost(self) -> int:
        return self._tx_lost.value

    def write_rx(self, frames: list[Frame], echoes: list[bool] | None = None) -> int:
        """Rx[1..n] := frames (n <= 32), RxCount := n, RxLost += the surplus; returns the surplus.
        `echoes[i]` marks frames[i] as the echo of one of the PLC's own frames."""
        n = len(frames)
        lost = 0
        if n > MAILBOX_FRAMES:
            lost, n = n - MAILBOX_FRAMES, MAILBOX_FRAMES
            self._rx_lost.value = (self._rx_lost.value + lost) & 0xFFFFFFFF
        if self._rx_codec is not None:
            self._rx_codec.write(frames[:n] if lost else frames, echoes)
            self._rx_count.value = n
            return lost
        rx = self._rx
        for i in range(n):
            slot = rx[i + 1] or self._bind_rx(i + 1)
            frame = frames[i]
            slot[0].value = frame.can_id
            slot[1].value = frame.dlc
            slot[2].value = frame.rtr
            data, dst = frame.data, slot[3]
            if type(dst) is list:
                for j, byte_var in enumerate(dst):
                    byte_var.value = data[j] if j < len(data) else 0
            else:
                dst.write_bytes(data if len(data) == 8 else data.ljust(8, b"\0"))
            if slot[4] is not None:
                slot[4].value = bool(echoes and echoes[i])
        self._rx_count.value = n
        return lost

    def count_rx_lost(self, n: int) -> None:
        """RxLost += n: frames the driver could not hold."""
        self._rx_lost.value = (self._rx_lost.value + n) & 0xFFFFFFFF

    def _bind_rx(self, i: int) -> tuple:
        slot = self._rx[i] = self._bind("Rx", i)
        return slot

    def take_tx(self) -> list[Frame]:
        """The frames Tx[1..TxCount], then TxCount := 0. A TxCount outside 0..32 raises CoSimError: the
        PLC program wrote past its Tx array (no driver would send those frames, and none was counted in
        TxLost)."""
        n = self._tx_count.value
        if n == 0:
            return []
        if not 0 < n <= MAILBOX_FRAMES:
            self._tx_count.value = 0
            raise CoSimError(f"{self.path}.TxCount = {n}: outside 0..{MAILBOX_FRAMES} (Tx holds "
                             f"{MAILBOX_FRAMES} frames; a full Tx is counted in TxLost, not in TxCount)")
        frames = []
        codec = self._tx_codec
        if codec is not None:
            for i in range(n):
                can_id, dlc, rtr, data = codec.read(i)
                if can_id > 0x7FF or dlc > 8:
                    self._tx_count.value = 0
                    raise CoSimError(f"{self.path}.Tx[{i + 1}]: Id {can_id:#x} Dlc {dlc} is not a CAN 2.0A frame "
                                     f"(Id 0..16#7FF, Dlc 0..8)")
                # checked just above: an 11-bit identifier, at most 8 bytes
                frames.append(Frame(can_id, b"", True, dlc) if rtr else Frame.checked_by_caller(can_id, data[:dlc]))
            self._tx_count.value = 0
            return frames
        tx = self._tx
        for i in range(1, n + 1):
            slot = tx[i]
            if slot is None:
                slot = tx[i] = self._bind("Tx", i)
            can_id, dlc = slot[0].value, slot[1].value
            if can_id > 0x7FF or dlc > 8:
                self._tx_count.value = 0
                raise CoSimError(f"{self.path}.Tx[{i}]: Id {can_id:#x} Dlc {dlc} is not a CAN 2.0A frame "
                                 f"(Id 0..16#7FF, Dlc 0..8)")
            src = slot[3]
            if slot[2].value:  # a remote frame: a DLC, no data
                frames.append(Frame(can_id, b"", True, dlc))
                continue
            if not dlc:
                data = b""
            elif type(src) is list:
                data = bytes(src[j].value for j in range(dlc))
            else:
                data = src.read_bytes()[:dlc]
            frames.append(Frame(can_id, data, slot[2].value))
        self._tx_count.value = 0
        return frames


class IdlePredicate:
    """Base of a run_until predicate that lets idle scans run in C between its calls: it watches the
    variables it reads (`idle_watch`) and counts scans by the PLC's scan counter. `scans` is what a
    counter of its calls would hold (the predicate is called before each scan and after the last): the
    scans run so far inside a call, one more after it.

    `changes_nodes` False after a call: that call changed no node of the bus (no drive's input, clock or
    state), so the bus need not ask every node for its next timer again before the next scan (an O(nodes)
    round per scan; run_until's first scan asks all the same). True, the default, is always safe."""

    changes_nodes = True

    def __init__(self, plc: Plc, watched: list) -> None:
        self.plc = plc
        self.idle_watch = IdleWatch(watched) if hasattr(plc, "step_idle") else None
        self._scan0 = plc.scan_count
        self._in_call = True      # until the first call ends: no scan counted yet

    @property
    def scans(self) -> int:
        return self.plc.scan_count - self._scan0 + (0 if self._in_call else 1)

    def begin_call(self) -> int:
        """At the start of a call: the scans run so far."""
        self._in_call = True
        return self.plc.scan_count - self._scan0

    def end_call(self) -> None:
        self._in_call = False


class CoSim:
    """A PLC stepped scan by scan against a SimBus; the PLC is the bus endpoint named `name`. `echo`
    (default: when the mailbox type has the field) gives the PLC the echo of its transmitted frames."""

    def __init__(self, plc: Plc, bus: SimBus, mailbox: str = "CONFIG0.RES0.CAN0", name: str = "plc",
                 echo: bool | None = None, fast_idle: bool = True) -> None:
        self.plc = plc
        self.bus = bus
        self.mailbox = Mailbox(plc, mailbox)
        self.endpoint = bus.endpoint(name)
        self.name = name
        self.echo = self.mailbox.has_echo if echo is None else echo
        self.mailbox.set_tx_echo(self.echo)
        self._trace_pos = len(bus.trace)   # the PLC's own frames are read from the bus trace (bus order)
        self.scans = 0
        self.frames_sent = 0
        self.frames_received = 0
        self.rx_dropped = 0   # frames that did not fit into Rx (also counted in the PLC's RxLost)
        # idle scans in C need the loader's step_idle, INT counters (the glue writes them as C shorts) and a
        # bus that tells its next event
        mb = self.mailbox
        self.fast_idle = bool(fast_idle and hasattr(plc, "step_idle") and hasattr(bus, "next_event_ns")
                              and getattr(mb._rx_count, "nbytes", 0) == 2 and getattr(mb._tx_count, "nbytes", 0) == 2)
        self.idle_scans = 0   # scans run by the fast idle path

    def step(self, n: int = 1) -> None:
        """Run n scans."""
        done = 0
        while done < n:
            done += self._advance(n - done, None)

    def _advance(self, limit: int, watch: Any, current: bool = False) -> int:
        """Idle scans in C (at most `limit`) when the next scan is idle, else one scan from Python; returns
        the scans run. `current`: no node changed from outside since the bus last ran (its timers hold)."""
        refreshed = current
        if self.fast_idle:
            k = self._idle(limit, watch, current)
            if k > 0:
                return k
            refreshed = current or k < 0    # the bus has just read every node's timer: no need again
        self._scan(refreshed)
        return 1

    def _idle(self, limit: int, watch: Any, current: bool = False) -> int:
        """Up to `limit` idle scans in C when the next scan would receive nothing; returns the scans run (0:
        the next scan is not idle; -1: not idle, and the bus's timers were read just now)."""
        plc, bus = self.plc, self.bus
        t = plc.time_ns
        if t < bus.now or self.endpoint.inbox or (self.echo and len(bus.trace) != self._trace_pos):
            return 0
        until = bus.next_event_ns(refresh=not current)
        if until is not None and until <= t:
            return -1
        mb = self.mailbox
        k = plc.step_idle(limit, (1 << 64) - 1 if until is None else until, mb._rx_count, mb._tx_count, watch)
        if not k:
            return -1                   # the timers were read just now too
        self.scans += k
        self.idle_scans += k
        t_last = plc.time_ns - plc.tick_ns     # the start of the last scan: its frames are ready then
        bus.run_until(t_last, refresh=False)   # no event on the way (only C scans since the timers were read)
        if mb._tx_count.value:
            self._send(mb.take_tx(), t_last)
        return k

    def _send(self, frames: list[Frame], t: int) -> None:
        send = self.endpoint.send
        for f in frames:
            send(f, t)
        self.frames_sent += len(frames)

    def _scan(self, refreshed: bool = False) -> None:
        """One scan stepped from Python: deliver, fill Rx, step, send. `refreshed`: the bus read every node's
        timer since the last event (nothing outside can have changed a node since)."""
        plc, bus, ep, mb = self.plc, self.bus, self.endpoint, self.mailbox
        t = plc.time_ns
        if t < bus.now:
            raise CoSimError(f"PLC time {t} ns is behind the bus ({bus.now} ns): was the PLC reset?")
        bus.run_until(t, refresh=not refreshed)
        inbox = ep.inbox
        own = self._echoes() if self.echo else None
        if own:
            ep.inbox = []
            self.frames_received += len(inbox)
            merged = sorted([(te, 0, f) for te, f in inbox] + [(te, 1, f) for te, f in own],
                            key=lambda x: x[0])
            self.rx_dropped += mb.write_rx([f for _, _, f in merged], [o == 1 for _, o, _ in merged])
        elif inbox:
            ep.inbox = []
            self.frames_received += len(inbox)
            self.rx_dropped += mb.write_rx([f for _, f in inbox])
        else:
            mb._rx_count.value = 0
        plc.step(1)
        self.scans += 1
        if mb._tx_count.value:
            self._send(mb.take_tx(), t)

    def _echoes(self) -> list[tuple[int, Frame]]:
        """The PLC's frames whose transmission ended since the previous scan, as (end time, frame)."""
        trace, i, name = self.bus.trace, self._trace_pos, self.name
        out = [(e.end_ns, e.frame) for e in trace[i:]
               if e.sender == name and e.status != "error" and is_echoed(e.frame.can_id)]
        self._trace_pos = len(trace)
        return out

    def run_until(self, predicate: Callable[[], bool], max_scans: int) -> int:
        """Step until predicate() is true (checked before each scan and after the last); returns the
        scans run. Raises CoSimTimeout when it is still false after max_scans.

        A predicate with an `idle_watch` (a plc.IdleWatch) declares that its result and what it records
        change only when one of those variables does (it counts scans by plc.scan_count, not by its
        calls): idle scans then run in C between its calls, each run ending after the scan that changed
        one. Without it the predicate is called before every scan."""
        watch = getattr(predicate, "idle_watch", None)
        k = 0
        current = False         # the first scan reads every node's timer (the caller may have changed a node)
        while k < max_scans:
            if predicate():
                return k
            current = current and not getattr(predicate, "changes_nodes", True)
            k += self._advance(max_scans - k, watch, current) if watch is not None else self._advance(1, None, current)
            current = True
        if predicate():
            return max_scans
        raise CoSimTimeout(f"condition not met within {max_scans} scans (PLC time {self.plc.time_ns} ns)")


class RealTimeCoSim:
    """A PLC stepped against the wall clock on a python-can bus (its own thread: the caller's).

    Scan k of a `step`/`run_until` call starts when the wall clock has advanced as far as the PLC's
    clock since the call began; the frames received meanwhile go into Rx. A scan that starts a tick or
    more late is an overrun (`overruns`, `max_lateness_ns`): it still runs, but at the wall time (the
    PLC's clock moves on by the whole ticks missed, `skipped_ticks`), so that the PLC's timers and
    timeouts keep real time on a machine too slow for the task, as on a PLC whose task overran. Frames
    beyond the 32 that Rx holds wait for the next scans, as in a CAN driver's receive queue (`rx_queue`
    frames; beyond that they are lost and counted in RxLost): a stalled PLC sees every frame, late.
    """

    def __init__(self, plc: Plc, can_bus: can.BusABC, mailbox: str = "CONFIG0.RES0.CAN0", *,
                 clock: Callable[[], int] = time.monotonic_ns, echo: bool = False, rx_queue: int = 1024) -> None:
        self.plc = plc
        self.rx_queue = rx_queue      # frames the driver holds beyond the 32 of one scan (a CAN driver's FIFO)
        self.can_bus = can_bus
        self.mailbox = Mailbox(plc, mailbox)
        self.clock = clock
        # echo: the bus was opened with receive_own_messages=True, so it returns the PLC's own frames once
        # sent: they go into Rx as echoes, in the order received (OwnFrames tells them from other nodes')
        self.echo = echo
        self._own = OwnFrames()
        self.mailbox.set_tx_echo(echo)
        self._pending_echo: list[bool] = []
        self.scans = 0
        self.frames_sent = 0
        self.frames_received = 0
        self.rx_dropped = 0
        self.send_errors = 0
        self.overruns = 0             # scans that started one tick or more after their due time
        self.max_lateness_ns = 0
        self.skipped_ticks = 0        # task activations missed by those scans (the PLC clock moved on)
        self._pending: list[Frame] = []
        # the wall time and PLC time that scan pacing counts from; kept across step()/run_until() calls, so
        # that step(1) in a caller's loop paces scan after scan as one long call does
        self._anchor: tuple[int, int] | None = None

    def _paced_from(self, now: int, tick: int) -> tuple[int, int]:
        """(wall, PLC time) the next scans are due from. A caller that held the PLC between two calls (it
        inspected, forced, waited: a tick or more) is not an overrun of the PLC's task: pacing starts anew."""
        plc_now = self.plc.time_ns
        if self._anchor is not None:
            wall0, plc0 = self._anchor
            if plc_now >= plc0 and now - (wall0 + plc_now - plc0) < tick:
                return self._anchor
        self._anchor = (now, plc_now)
        return self._anchor

    def _collect(self, until_wall_ns: int) -> int:
        """Receive into the pending frames until the wall clock reaches `until_wall_ns`; returns the wall
        time then. A scan already due only drains what has arrived (no clock read per frame: on a machine
        where a system call is dear, such as User-Mode Linux, the clock is read once)."""
        bus, pending, clock = self.can_bus, self._pending, self.clock
        now = clock()
        while True:
            remaining = until_wall_ns - now
            msg = bus.recv(timeout=remaining / 1e9 if remaining > 0 else 0)
            if msg is None:
                if remaining <= 0:
                    return now
                now = clock()
                if now >= until_wall_ns:
                    return now
                continue
            if not (msg.is_error_frame or msg.is_extended_id or getattr(msg, "is_fd", False)):
                own = self.echo and self._own.is_own(msg)
                if not own or is_echoed(msg.arbitration_id):
                    pending.append(Frame.from_message(msg))
                    self._pending_echo.append(own)
            if remaining > 0:
                now = clock()

    def _scans(self, n: int | None, predicate: Callable[[], bool] | None, timeout_s: float | None) -> int:
        plc, mb, send = self.plc, self.mailbox, self.can_bus.send
        tick = plc.tick_ns
        now = self.clock()
        wall0, plc0 = self._paced_from(now, tick)
        wall_end = None if timeout_s is None else now + int(timeout_s * 1e9)
        k = 0
        while n is None or k < n:
            if predicate is not None and predicate():
                return k
            due = wall0 + (plc.time_ns - plc0)
            if wall_end is not None and due > wall_end:
                break
            late = self._collect(due) - due
            if late > self.max_lateness_ns:
                self.max_lateness_ns = late
            if late >= tick:
                # an overrun: the PLC's clock keeps real time (its timers and timeouts measure the wall
                # clock, as on a PLC whose task overran), so this scan runs at the wall time in whole ticks
                self.overruns += 1
                missed = late // tick
                self.skipped_ticks += missed
                plc.time_ns = plc.time_ns + missed * tick
            # the driver's receive queue: Rx takes the oldest 32, the rest waits for the next scans (a PLC
            # that stalled gets every frame late rather than none); beyond rx_queue frames are lost
            pending, echo_flags = self._pending, self._pending_echo
            if len(pending) > MAILBOX_FRAMES + self.rx_queue:
                surplus = len(pending) - MAILBOX_FRAMES - self.rx_queue
                del pending[-surplus:], echo_flags[-surplus:]
                self.rx_dropped += surplus
                mb.count_rx_lost(surplus)
            frames, self._pending = pending[:MAILBOX_FRAMES], pending[MAILBOX_FRAMES:]
            echoes, self._pending_echo = echo_flags[:MAILBOX_FRAMES], echo_flags[MAILBOX_FRAMES:]
            self.frames_received += len(frames) - sum(echoes)
            self.rx_dropped += mb.write_rx(frames, echoes)
            plc.step(1)
            self.scans += 1
            k += 1
            for f in mb.take_tx():
                try:
                    msg = f.to_message()
                    send(msg)
                    self.frames_sent += 1
                    if self.echo:
                        self._own.sent(msg)
                except Exception:  # noqa: BLE001 - a full Tx queue loses the frame, like a PLC driver would
                    self.send_errors += 1
        if predicate is not None:
            if predicate():
                return k
            raise CoSimTimeout(f"condition not met within {k} scans")
        return k

    def step(self, n: int = 1) -> None:
        """Run n scans in real time."""
        self._scans(n, None, None)

    def run_until(self, predicate: Callable[[], bool], max_scans: int | None = None,
                  timeout_s: float | None = None) -> int:
        """Step in real time until predicate() holds; CoSimTimeout after max_scans or timeout_s."""
        if max_scans is None and timeout_s is None:
            raise ValueError("give max_scans or timeout_s")
        return self._scans(max_scans, predicate, timeout_s)
