"""A direct link to one sans-I/O node in virtual time, for tests and quick experiments: no bus in between,
frames are delivered at their ready time and take no bus time.

    link = DirectLink(make_drive("E1100", 1)) # powers the drive on and waits for its boot-up message
    link.sdo("40 00 10 00 00 00 00 00")       # -> the 8 response bytes, or None after the timeout
"""

from __future__ import annotations

import heapq
import itertools
import time
import uuid

from ..bus.frame import Frame
from ..protocol.commands import encode

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
        observe = getattr(self.node, "observe", None)
        if observe is not None:
            observe(self.t)                     # a drive that computed ahead: its state as of now
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


class RawSdoClient:
    """Hand-built frames to one node on a python-can bus (tests against a drive served in real time).

    `exchange(request)` sends an SDO request on 600h+ID and returns the data of the next frame on 580h+ID;
    other frames received meanwhile are kept for `wait_for`, so a heartbeat or boot-up message that arrives
    during an exchange is not lost. Timeouts are generous: a loaded machine may delay the server thread.
    """

    def __init__(self, bus, node_id: int = 1, timeout_s: float = 5.0):
        self.bus = bus
        self.node_id = node_id
        self.timeout_s = timeout_s
        self.others: list = []          # python-can messages that were not the awaited SDO answer

    def send(self, can_id: int, data: bytes | str) -> None:
        import can

        self.bus.send(can.Message(arbitration_id=can_id, data=hexbytes(data), is_extended_id=False))

    def exchange(self, request: bytes | str, timeout_s: float | None = None) -> bytes | None:
        """Send the request, return the answer's data (None: no answer within the timeout)."""
        self.send(0x600 + self.node_id, request)
        msg = self._recv(lambda m: m.arbitration_id == 0x580 + self.node_id, timeout_s, keep_others=True)
        return None if msg is None else bytes(msg.data)

    def wait_for(self, predicate, timeout_s: float | None = None):
        """The first message (kept ones first) matching `predicate(msg)`, None after the timeout; messages
        kept before the match are dropped."""
        for k, msg in enumerate(self.others):
            if predicate(msg):
                del self.others[:k + 1]
                return msg
        self.others.clear()
        return self._recv(predicate, timeout_s, keep_others=False)

    def _recv(self, predicate, timeout_s: float | None, keep_others: bool):
        deadline = time.monotonic() + (self.timeout_s if timeout_s is None else timeout_s)
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                return None
            msg = self.bus.recv(timeout=left)
            if msg is None:
                continue
            if predicate(msg):
                return msg
            if keep_others:
                self.others.append(msg)


class ServedDrive:
    """A drive attached (`drive.attach`) to a fresh python-can `virtual` channel, with a raw client on the
    same channel; a context manager that waits for the boot-up message and detaches at the end.

        with ServedDrive(make_drive("E1100", 1, timings=DriveTimings.fast())) as served:
            served.client.exchange("40 A2 33 01 00 00 00 00")
    """

    def __init__(self, drive, channel: str | None = None, boot_timeout_s: float = 10.0):
        self.drive = drive
        self.channel = channel or f"linmot-st-{uuid.uuid4().hex[:12]}"
        self.boot_timeout_s = boot_timeout_s
        self.client: RawSdoClient | None = None
        self._buses: list = []

    def __enter__(self) -> ServedDrive:
        import can

        drive_bus = can.Bus(interface="virtual", channel=self.channel)
        raw = can.Bus(interface="virtual", channel=self.channel)
        self._buses = [drive_bus, raw]
        self.client = RawSdoClient(raw, self.drive.node_id)
        try:
            self.drive.attach(drive_bus)
            boot = self.client.wait_for(lambda m: m.arbitration_id == 0x700 + self.drive.node_id,
                                        self.boot_timeout_s)
            if boot is None or bytes(boot.data) != b"\x00":
                raise RuntimeError(f"no boot-up message from node {self.drive.node_id} within {self.boot_timeout_s} s")
        except BaseException:
            self.__exit__()
            raise
        return self

    def __exit__(self, *exc) -> None:
        try:
            self.drive.detach()
        finally:
            for bus in self._buses:
                bus.shutdown()
            self._buses = []


class MotionLink(DirectLink):
    """A DirectLink that drives the motion side with raw PDO frames (tests, experiments):

        link = MotionLink(E1100Drive(1, profile_with_motor))   # booted and Operational
        link.enable()                                          # 003Eh, 003Fh: state 8
        link.command(0x090, target=500, vmax=1000, acc=100, dec=100)   # RxPDO2 + RxPDO3, next count
        link.wait(lambda: link.drive.mc.state_var & 0x0020 == 0)
    """

    def __init__(self, node, t_ns: int = 0, *, operational: bool = True, **kw):
        super().__init__(node, t_ns, **kw)
        self.drive = node
        self.count = 0
        if operational:
            self.nmt(0x01)
            self.advance(1_000_000)

    def cw(self, word: int, dt_ns: int = 0) -> None:
        """RxPDO1: the control word (with RxPDO1 mapping 2040h = 1 followed by the last command's header and
        parameter bytes 0..3, so that the control word alone starts nothing)."""
        data = word.to_bytes(2, "little")
        if self.node.pdo.rx1_mode == 1:
            data += self.rx1_command
        self.send(Frame(0x200 + self.node.node_id, data), dt_ns)

    rx1_command = bytes(6)

    def enable(self, timeout_ns: int = 5 * S) -> None:
        """Switch on to Operation Enabled (state 8) from state 0..2."""
        self.cw(0x003E)
        self.cw(0x003F, 1_000_000)
        if not self.wait(lambda: self.node.mc.state == 8, timeout_ns):
            raise RuntimeError(f"not enabled: state var {self.node.mc.state_var:04X}h")

    def home(self, timeout_ns: int = 30 * S) -> None:
        """083Fh until homing finished (sub state 0Fh), then 003Fh ([CO1100] section 14)."""
        self.cw(0x083F)
        if not self.wait(lambda: self.node.mc.state_var == 0x090F, timeout_ns):
            raise RuntimeError(f"homing did not finish: state var {self.node.mc.state_var:04X}h")
        self.cw(0x003F)

    def command_frames(self, cid: int, **fields) -> list[Frame]:
        """RxPDO2 (header + par bytes 0..5) and RxPDO3 (slave header + par bytes 6..7, 6..9 or 6..11 as the
        drive's RxPDO3 mapping 2041h says) of a command with the next count (1..15, 0 skipped as LinMot's own
        demo does)."""
        self.count = self.count % 15 + 1
        raw = encode(cid, self.count, **fields).ljust(14, b"\0")
        par_end = {0: 10, 1: 12, 2: 14}.get(self.node.pdo.rx3_mode, 10)
        nid = self.node.node_id
        return [Frame(0x300 + nid, raw[0:8]), Frame(0x400 + nid, raw[0:2] + raw[8:par_end])]

    def command(self, cid: int, dt_ns: int = 0, **fields) -> None:
        frames = self.command_frames(cid, **fields)
        self.send(frames[0], dt_ns)
        self.send(frames[1])

    def wait(self, predicate, timeout_ns: int = 5 * S, step_ns: int = 1_000_000) -> bool:
        """Advance in steps until predicate() holds (True) or the timeout passes (False)."""
        end = self.t + timeout_ns
        while not predicate():
            if self.t >= end:
                return False
            self.advance(step_ns)
        return True

    def pdos(self, n: int, since_ns: int = 0) -> list[tuple[int, bytes]]:
        """(time, data) of TxPDO n (1..3) sent since since_ns."""
        cob = (0x180, 0x280, 0x380)[n - 1] + self.node.node_id
        return [(t, bytes(f.data)) for t, f in self.received if f.can_id == cob and t >= since_ns]
