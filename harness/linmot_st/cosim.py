"""Co-simulation: a PLC's CAN mailbox (T_CanMailbox, st_lib/types/can.st) coupled to a bus, scan by scan.

`CoSim` runs in virtual time against the simulated bus (docs/architecture.md section 5). Each scan at
PLC time t:
  1. bus.run_until(t): every frame whose transmission ended at or before t is delivered;
  2. the frames the PLC's endpoint received since the previous scan go into Rx[1..RxCount], in
     delivery order; beyond 32 the rest are dropped and counted in RxLost (as a PLC CAN driver does);
  3. plc.step(1);
  4. Tx[1..TxCount] are sent in order, ready at t, and TxCount is set to 0 (a TxCount outside 0..32, or
     a Tx frame with Id > 16#7FF or Dlc > 8, raises CoSimError: no CAN driver could send it).
`RealTimeCoSim` does the same on a python-can bus against the wall clock (`linmot-st commission
--bus virtual|socketcan:CHANNEL`): scan k starts at the wall time of the PLC's clock, and the frames
received until then go into Rx.

Mailbox access uses the loader's bound accessors, each bound once on first use, so a scan costs a few
attribute accesses plus the PLC step.
"""

from __future__ import annotations

import time
from typing import Any, Callable

from linmot_st.bus.frame import Frame

MAILBOX_FRAMES = 32   # T_CanFrames : ARRAY[1..32] OF T_CanFrame


class CoSimError(Exception):
    """The PLC put something into its mailbox that no CAN driver could send."""


class CoSimTimeout(TimeoutError):
    """run_until() reached max_scans (or its timeout) before the predicate held."""


class Mailbox:
    """Bound accessors of one T_CanMailbox variable of a PLC (RxCount, Rx, RxLost, TxCount, Tx, TxLost)."""

    def __init__(self, plc: Any, path: str) -> None:
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

    def _bind(self, which: str, i: int) -> tuple:
        """(Id, Dlc, Rtr, Data) accessors of one frame slot. Data is the whole ARRAY[0..7] OF BYTE when
        the loader offers raw byte access (one call per frame), else a list of its 8 elements."""
        var, p = self.plc.var, f"{self.path}.{which}[{i}]"
        data = var(f"{p}.Data")
        if not (hasattr(data, "write_bytes") and hasattr(data, "read_bytes") and getattr(data, "nbytes", 0) == 8):
            data = [var(f"{p}.Data[{j}]") for j in range(8)]
        return (var(f"{p}.Id"), var(f"{p}.Dlc"), var(f"{p}.Rtr"), data)

    @property
    def rx_count(self) -> int:
        return self._rx_count.value

    @property
    def rx_lost(self) -> int:
        return self._rx_lost.value

    @property
    def tx_lost(self) -> int:
        return self._tx_lost.value

    def write_rx(self, frames: list[Frame]) -> int:
        """Rx[1..n] := frames (n <= 32), RxCount := n, RxLost += the surplus; returns the surplus."""
        n = len(frames)
        lost = 0
        if n > MAILBOX_FRAMES:
            lost, n = n - MAILBOX_FRAMES, MAILBOX_FRAMES
            self._rx_lost.value = (self._rx_lost.value + lost) & 0xFFFFFFFF
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
        self._rx_count.value = n
        return lost

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


class CoSim:
    """A PLC stepped scan by scan against a SimBus; the PLC is the bus endpoint named `name`."""

    def __init__(self, plc: Any, bus: Any, mailbox: str = "CONFIG0.RES0.CAN0", name: str = "plc") -> None:
        self.plc = plc
        self.bus = bus
        self.mailbox = Mailbox(plc, mailbox)
        self.endpoint = bus.endpoint(name)
        self.scans = 0
        self.frames_sent = 0
        self.frames_received = 0
        self.rx_dropped = 0   # frames that did not fit into Rx (also counted in the PLC's RxLost)

    def step(self, n: int = 1) -> None:
        """Run n scans."""
        plc, bus, ep, mb = self.plc, self.bus, self.endpoint, self.mailbox
        send = ep.send
        for _ in range(n):
            t = plc.time_ns
            if t < bus.now:
                raise CoSimError(f"PLC time {t} ns is behind the bus ({bus.now} ns): was the PLC reset?")
            bus.run_until(t)
            inbox = ep.inbox
            if inbox:
                ep.inbox = []
                self.frames_received += len(inbox)
                self.rx_dropped += mb.write_rx([f for _, f in inbox])
            else:
                mb._rx_count.value = 0
            plc.step(1)
            self.scans += 1
            if mb._tx_count.value:
                frames = mb.take_tx()
                for f in frames:
                    send(f, t)
                self.frames_sent += len(frames)

    def run_until(self, predicate: Callable[[], bool], max_scans: int) -> int:
        """Step until predicate() is true (checked before each scan and after the last); returns the
        scans run. Raises CoSimTimeout when it is still false after max_scans."""
        for k in range(max_scans):
            if predicate():
                return k
            self.step(1)
        if predicate():
            return max_scans
        raise CoSimTimeout(f"condition not met within {max_scans} scans (PLC time {self.plc.time_ns} ns)")


class RealTimeCoSim:
    """A PLC stepped against the wall clock on a python-can bus (its own thread: the caller's).

    Scan k of a `step`/`run_until` call starts when the wall clock has advanced as far as the PLC's
    clock since the call began; the frames received meanwhile go into Rx. A scan that starts a tick or
    more late is an overrun (`overruns`, `max_lateness_ns`): it still runs, but at the wall time (the
    PLC's clock moves on by the whole ticks missed, `skipped_ticks`), so that the PLC's timers and
    timeouts keep real time on a machine too slow for the task, as on a PLC whose task overran.
    """

    def __init__(self, plc: Any, can_bus: Any, mailbox: str = "CONFIG0.RES0.CAN0", *,
                 clock: Callable[[], int] = time.monotonic_ns) -> None:
        self.plc = plc
        self.can_bus = can_bus
        self.mailbox = Mailbox(plc, mailbox)
        self.clock = clock
        self.scans = 0
        self.frames_sent = 0
        self.frames_received = 0
        self.rx_dropped = 0
        self.send_errors = 0
        self.overruns = 0             # scans that started one tick or more after their due time
        self.max_lateness_ns = 0
        self.skipped_ticks = 0        # task activations missed by those scans (the PLC clock moved on)
        self._pending: list[Frame] = []

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
                pending.append(Frame.from_message(msg))
            if remaining > 0:
                now = clock()

    def _scans(self, n: int | None, predicate: Callable[[], bool] | None, timeout_s: float | None) -> int:
        plc, mb, send = self.plc, self.mailbox, self.can_bus.send
        tick = plc.tick_ns
        wall0, plc0 = self.clock(), plc.time_ns
        wall_end = None if timeout_s is None else wall0 + int(timeout_s * 1e9)
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
            frames, self._pending = self._pending, []
            self.frames_received += len(frames)
            self.rx_dropped += mb.write_rx(frames)
            plc.step(1)
            self.scans += 1
            k += 1
            for f in mb.take_tx():
                try:
                    send(f.to_message())
                    self.frames_sent += 1
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
