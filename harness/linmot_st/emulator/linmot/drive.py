"""E1100Drive: the emulated LinMot E1100 with CANopen firmware, as a sans-I/O bus node (docs/architecture.md 3, 4).

Frames go in with the time they ended on the bus (`on_frame`), frames come out with the time they are ready to
be sent; timed work (boot, heartbeat, flash writes, MC start/stop, set-to-default) runs from `on_timer` at
`next_timer_ns()`. No threads and no clock inside: the same model runs in virtual time on the simulated bus and
in real time on a python-can bus (`attach`).
"""

from __future__ import annotations

import heapq
import itertools
import threading
from dataclasses import dataclass, field

from ...bus.frame import Frame
from ...protocol.upids import P_BRAKE_OPERATION_ENABLED
from ...protocol.words import ERROR, SETUP_ERROR
from .. import codes
from ..cia301.nmt import BOOTING, OFF, OPERATIONAL, PRE_OPERATIONAL, STOPPED, NmtSlave
from ..cia301.objects import CommObjects
from ..cia301.pdo import ProcessData
from ..cia301.sdo import Pending, Reply, SdoServer
from ..codes import SdoAbort
from .command_table import CommandTable
from .curves import CurveStore
from .errorlog import ErrorLog
from .io import DriveIO, IoSettings
from .manufacturer import ManufacturerObjects
from .model import E1100, DriveModel
from .motion import MotionControl, MotionSettings
from .options import ProtocolOptions
from .params import ParameterStore
from .profile import DriveProfile

MS = 1_000_000
S = 1_000_000_000

MOTOR_TYPE_UPID = 0x1194
PRODUCE_HEARTBEAT_UPID, PRODUCER_TIME_UPID = 0x2020, 0x2021


@dataclass(frozen=True)
class DriveTimings:
    """Durations of the drive's work, in ns. docs/emulator.md says which come from the sources."""
    sdo_turnaround_ns: int = 150_000          # request received -> response ready (INVENTED, 100..200 us)
    boot_ns: int = 4 * S                      # power-on / reset -> boot-up message (INVENTED)
    reset_communication_ns: int = 10 * MS     # NMT Reset Communication -> boot-up message (INVENTED)
    mc_stop_ns: int = 100 * MS                # 35h stop MC -> response (INVENTED)
    mc_start_ns: int = 3 * S                  # 36h start MC -> response (LinRS: "response after completion, ~3 s")
    set_default_ns: tuple[int, int, int, int] = (500 * MS, 2 * S, 500 * MS, 500 * MS)  # 07h..0Ah ([CO1100]; 0Ah INVENTED)
    flash_base_ns: int = 300 * MS             # 40h / 80h flash save: erase + fixed part (INVENTED)
    flash_per_kib_ns: int = 20 * MS           # ... plus this per KiB written (INVENTED)
    hw_test_ns: int = 300 * MS                # MC state 5 "HW tests" (seeds 004 3.6: about 300 ms)
    pdo_latency_ns: int = 100_000             # event -> TxPDO ready (INVENTED)

    @classmethod
    def fast(cls, **changes) -> DriveTimings:
        """Short durations for real-time tests on python-can buses (nothing waits seconds)."""
        base = dict(boot_ns=20 * MS, reset_communication_ns=2 * MS, mc_stop_ns=5 * MS, mc_start_ns=20 * MS,
                    set_default_ns=(10 * MS, 20 * MS, 10 * MS, 10 * MS), flash_base_ns=10 * MS,
                    flash_per_kib_ns=1 * MS, hw_test_ns=10 * MS)
        base.update(changes)
        return cls(**base)


@dataclass(order=True)
class _Event:
    t: int
    seq: int
    drive_gen: int = field(compare=False)
    comm_gen: int | None = field(compare=False)
    fn: object = field(compare=False)


class E1100Drive(NmtSlave):
    """The emulated LinMot drive. `E1100Drive(node_id=1)` is the seeds' example drive (the E1100 model,
    data/e1100_default.json); build drives of any model with emulator/models.py's make_drive(model, node_id).

    model          DriveModel (linmot/model.py): profile data, manufacturer services, quirks (default: E1100)
    profile        another parameter set / tree versions / identity (profile.py: load_profile().with_tree(...))
    timings        DriveTimings
    protocol       ProtocolOptions: the alternatives where the sources leave the frame layout open (the
                   defaults are what the ST library implements; docs/emulator.md, "Protocol options")
    error_log      a prepared ErrorLog (kept over resets, like the drive's own)
    motion         MotionSettings: the motion model's choices (MC cycle, axis dynamics, stroke, windows)
    """

    # On the simulated bus the drive's ready frames leave highest priority first, as from a CANopen stack with
    # one transmit buffer per message kind (CANopenNode's CO_CANtx buffers are sent lowest index first, the
    # heartbeat last): a heartbeat that loses arbitration on a busy bus then does not hold up an SDO answer
    # (INFERRED: the E1100's controller is not documented; docs/emulator.md). False: one FIFO, in queue order.
    tx_by_priority = True

    def __init__(self, node_id: int = 1, profile: DriveProfile | None = None, timings: DriveTimings | None = None,
                 *, protocol: ProtocolOptions | None = None, curve_capacity_bytes: int = 256 * 1024,
                 error_log: ErrorLog | None = None, motion: MotionSettings | None = None,
                 model: DriveModel = E1100, io: IoSettings | None = None):
        if not 1 <= node_id <= 127:
            raise ValueError(f"CANopen node ID {node_id} is outside 1..127")
        self.node_id = node_id
        self.model = model
        self.profile = profile or model.load_profile()
        self.timings = timings or DriveTimings()
        self.protocol = protocol or ProtocolOptions()
        self.params = ParameterStore(self.profile.all_definitions())
        self.curves = CurveStore(curve_capacity_bytes)
        self.ct = CommandTable()
        # a real drive's flash has limited write cycles: every completed save of a store counts one
        self.flash_cycles = {"curves": 0, "ct": 0}
        self.errlog = error_log or ErrorLog()
        self.motion = motion or MotionSettings()
        self.mc = MotionControl(self.motion, self.timings.hw_test_ns, self.motion_params(self.params), self.curves,
                                self.ct, self._log_error)
        self.mc.drive_type = model.name    # the catalogue rows' `drives` say which commands it has
        self.params.live = self.mc.variable
        self.mc.on_reset = lambda t: self._at(t, self._start_boot)     # 00Fxh: the whole firmware restarts
        self.io = DriveIO(io, par=self.mc.par)
        self._wire_io()
        self.pdo = ProcessData(self)
        self.mc_phase = "stopped"          # stopped | starting | running | stopping
        self.comm = CommObjects(node_id, self.profile.identity, self._heartbeat_power_on_ms,
                                self._error_register, self._comm_changed)
        self.mfr = ManufacturerObjects(self, model.services)
        self.sdo = SdoServer(self.comm, self.mfr, lambda: self.nmt_state == PRE_OPERATIONAL)
        self.nmt_state = OFF
        self.now_ns = 0
        # the COB-IDs on_frame can react to now (NMT, its SDO requests, and while Operational SYNC and its
        # RxPDOs; bus/node.py): the simulated bus offers the drive no other frame and NodeServer makes it the
        # python-can bus's receive filters, as a CAN controller's acceptance filter (both read it after each
        # call into the drive; kept current in _take)
        self._rx_base = frozenset((0x000, 0x600 + node_id))
        self.rx_filter = self._rx_base
        self.lock = threading.RLock()      # held by the real-time server around each call (inspection may take it)
        self._events: list[_Event] = []
        self._seq = itertools.count()
        self._drive_gen = 0                # bumped by a drive reset: cancels every pending event
        self._comm_gen = 0                 # bumped by a communication reset: cancels SDO answers, heartbeat
        self._hb_gen = 0
        self._sdo_busy = False
        self._flash_busy: str | None = None
        self._out: list[tuple[int, object]] = []
        self._server = None
        for quirk in model.quirks:        # last: a quirk sees (and may change) the drive as built
            quirk.apply(self)

    # ------------------------------------------------------------------ node protocol
    def power_on(self, t_ns: int) -> None:
        """Switch the drive on at t_ns: it boots and sends its boot-up message after `timings.boot_ns`."""
        self.now_ns = t_ns
        self._start_boot(t_ns)

    def power_off(self) -> None:
        self.nmt_state = OFF
        self._drive_gen += 1
        self._comm_gen += 1
        self.mc.stop(self.now_ns)
        self.pdo.stop()
        self.mc_phase = "stopped"

    def on_frame(self, frame, t_ns: int) -> list:
        if t_ns > self.now_ns:              # max() without the builtin call: every frame the filter lets in
            self.now_ns = t_ns
        if self.nmt_state in (OFF, BOOTING) or frame.rtr:
            return []
        cid, data = frame.can_id, frame.data
        if cid == 0x000:
            self.mc.sync(t_ns)
            self._nmt_command(data, t_ns)
        elif cid == 0x600 + self.node_id:
            if self.nmt_state != STOPPED and not self._sdo_busy:
                self.mc.sync(t_ns)                       # the MC's variables as of now; a write may follow
                self._sdo_request(bytes(data), t_ns)
        elif self.nmt_state == OPERATIONAL and self.pdo.handles(cid):
            self.mc.observe(t_ns)                        # the MC's own inputs forget what it computed ahead
            self.pdo.on_frame(cid, bytes(data), t_ns)
        return self._take(t_ns)

    def on_timer(self, t_ns: int) -> list:
        self.now_ns = max(self.now_ns, t_ns)
        while self._events and self._events[0].t <= t_ns:
            ev = heapq.heappop(self._events)
            if self._live(ev):
                self.now_ns = max(self.now_ns, ev.t)
                ev.fn(ev.t)
        if self.io._events and self.io._events[0][0] <= t_ns:
            self.io.on_timer(t_ns)              # input changes (each brings the MC to its time first)
            self.pdo.publish(t_ns)
        mc_t = self.mc.next_timer_ns()
        if mc_t is not None and mc_t <= t_ns:
            self.mc.on_timer(t_ns)
            self.pdo.publish(t_ns)
        pdo_t = self.pdo.next_timer_ns()
        if pdo_t is not None and pdo_t <= t_ns:
            self.mc.observe(t_ns)
            self.pdo.on_timer(t_ns)
        return self._take(t_ns)

    def observe(self, t_ns: int) -> None:
        """Bring the inspectable state (drive.mc) and the drive's clock to t_ns: the bus and DirectLink call it
        after running (so that a call from outside, power_off, sees the bus's time, not its last frame's)."""
        if t_ns > self.now_ns:
            self.now_ns = t_ns
        self.mc.observe(t_ns)

    def inject_error(self, code: int, at_ns: int) -> None:
        """Test hook: the MC detects error `code` at at_ns (e.g. a fatal 000Dh over current)."""
        def fire(t: int) -> None:
            self.mc.inject_error(code, t)
            self.pdo.publish(t)
        self._at(at_ns, fire)

    def next_timer_ns(self) -> int | None:
        events = self._events              # the bus asks after every frame: kept free of allocations
        while events and not self._live(events[0]):
            heapq.heappop(events)
        t = events[0].t if events else None
        pdo = self.pdo
        other = self.mc.next_timer_ns(pdo.cycle_sensitive)
        if other is not None and (t is None or other < t):
            t = other
        other = pdo.next_timer_ns()
        if other is not None and (t is None or other < t):
            t = other
        io = self.io._events
        if io and (t is None or io[0][0] < t):
            t = io[0][0]
        return t

    def _wire_io(self) -> None:
        """The I/O's listeners: the MC runs to the time of a change first; the trigger edges go to its event
        handler, the limit switches to their check; X4.5 captures the actual position."""
        io, mc = self.io, self.mc
        io.changes = mc.trajectory.io
        io.clock = lambda: self.now_ns
        io.before_change = mc.sync
        io.on_trigger = mc.events.on_trigger
        io.on_capture = lambda t: int(round(mc.axis.position))
        io.on_analog = lambda volts, t: mc.events.on_analog(t)
        io.on_level = mc.events.on_limit_switch if io.s.limit_switches else (lambda pin, level, t: None)
        # [MC] 7.2.1.1: with brake mode 1717h the brake is released (X4.3 = 24 V) while status word bit 0
        # (Operation Enabled) is set; the other brake modes (1716h, 1718h, delays) are not modelled
        io.brake = lambda: (mc.status_word & 1) if mc.par(P_BRAKE_OPERATION_ENABLED) else None
        mc.io = io

    # ------------------------------------------------------------------ inspection
    @property
    def booted(self) -> bool:
        return self.nmt_state in (PRE_OPERATIONAL, OPERATIONAL, STOPPED)

    def rom(self, upid: int) -> int:
        return self.params[upid].rom

    def ram(self, upid: int) -> int:
        return self.params[upid].ram

    def string(self, upid: int, which: str = "rom") -> str:
        return self.params.string(upid, which)

    def flash_busy(self) -> bool:
        return self._flash_busy is not None

    @property
    def sdo_busy(self) -> bool:
        return self._sdo_busy

    # ------------------------------------------------------------------ real time
    def attach(self, bus) -> None:
        """Serve this drive on a python-can `bus` in real time from a background thread until `detach()`.

        The bus package's NodeServer runs the node; its clock starts at 0, so attaching is a power cycle:
        the drive boots (boot-up message after `timings.boot_ns`) with its ROM, flash and error log kept.
        While attached, take `drive.lock` to inspect or change the drive from another thread.
        """
        from ...bus import NodeServer

        if self._server is not None:
            raise RuntimeError("drive is already attached to a bus")
        server = NodeServer(self, bus, on_start=self.power_on, name=f"{self.model.name} node {self.node_id}")
        self.lock = server.lock
        self.mc.lookahead = False          # in real time every cycle runs when due: state is current to inspect
        self._server = server.start()

    def clock_now_ns(self) -> int | None:
        """While attached: the drive's time now (ns since it was attached); None in virtual time."""
        return self._server.now_ns() if self._server is not None else None

    def detach(self) -> None:
        """Stop serving (joins the thread); re-raises an exception the drive raised meanwhile."""
        server, self._server = self._server, None
        if server is not None:
            try:
                server.stop()
            finally:
                self.lock = threading.RLock()
                self.mc.lookahead = True

    # ------------------------------------------------------------------ internals: scheduling
    def _live(self, ev: _Event) -> bool:
        return ev.drive_gen == self._drive_gen and (ev.comm_gen is None or ev.comm_gen == self._comm_gen)

    def _at(self, t: int, fn, comm: bool = False) -> None:
        heapq.heappush(self._events, _Event(t, next(self._seq), self._drive_gen,
                                            self._comm_gen if comm else None, fn))

    def _send(self, t: int, can_id: int, data: bytes) -> None:
        self._out.append((t, Frame(can_id, data)))

    def _take(self, t_ns: int) -> list:
        pdo = self.pdo                      # the end of every on_frame/on_timer: the filter as of now
        self.rx_filter = pdo.rx_ids if pdo.operational else self._rx_base
        out = self._out
        if not out:
            return []
        self._out = []
        for t, _ in out:
            if t < t_ns:
                return [(t if t > t_ns else t_ns, f) for t, f in out]
        return out                          # all ready at or after t_ns (a TxPDO2 on every SYNC): no copy

    def _operating_ms(self, t_ns: int) -> int:
        return self.profile.identity.operating_hours * 3_600_000 + t_ns // MS

    # ------------------------------------------------------------------ boot (NMT, heartbeat: cia301/nmt.py)
    def _start_boot(self, t: int) -> None:
        """Power-on, software reset (0Bh) and NMT Reset Node: the whole firmware starts again."""
        self._drive_gen += 1
        self._comm_gen += 1
        self.nmt_state = BOOTING
        self._sdo_busy = False
        self._flash_busy = None
        self.mc.stop(t)
        self.mc.power_on_reset()
        self.pdo.stop()
        self.pdo.reset_image()
        self.mc_phase = "stopped"
        self.params.load_ram_from_rom()
        self.curves.boot()
        self.ct.boot()
        self.mfr.reset()
        self.sdo.reset()
        self.comm.reset()
        self._at(t + self.timings.boot_ns, self._boot_done)

    def _boot_done(self, t: int) -> None:
        self._mc_start_now(t)
        self._enter_pre_operational(t)

    def _heartbeat_power_on_ms(self) -> int:
        """1017h at power-on: the interface parameters "Produce Heartbeat" / "Producer Time" (RAM)."""
        p = self.mc.params
        if PRODUCE_HEARTBEAT_UPID in p and PRODUCER_TIME_UPID in p and p[PRODUCE_HEARTBEAT_UPID].ram:
            return p[PRODUCER_TIME_UPID].ram
        return 0

    def motion_params(self, store):
        """The parameters as the motion control and the PDOs name them (E1100 UPIDs): the store itself here; a
        model with other UPIDs gives a view keyed by their E1100 counterparts (b1100.py)."""
        return store

    def _error_register(self) -> int:
        return 0x01 if self.mc.running and self.mc.state in (SETUP_ERROR, ERROR) else 0x00

    # ------------------------------------------------------------------ SDO
    def _sdo_request(self, data: bytes, t: int) -> None:
        res = self.sdo.handle(data)
        if res is None:
            return
        ready = t + self.timings.sdo_turnaround_ns
        tx = 0x580 + self.node_id
        if isinstance(res, Pending):
            self._sdo_busy = True
            comm_gen = self._comm_gen

            def finish(te, res=res):
                # the operation completes even after a Reset Communication; only its answer is dropped then
                if comm_gen == self._comm_gen:
                    self._sdo_busy = False
                    if self.nmt_state in (PRE_OPERATIONAL, OPERATIONAL):
                        self._send(te, tx, res.response)
                if res.then is not None:
                    res.then()
            self._at(ready + res.delay_ns, finish)
        else:
            self._send(ready, tx, res)

    # --- system services called by the manufacturer objects ---
    def set_layer_default(self, layer: int) -> Reply:
        return Reply(delay_ns=self.timings.set_default_ns[layer - 1],
                     then=lambda: self.params.set_layer_default(layer))

    def software_reset(self) -> None:
        self._start_boot(self.now_ns)

    def stop_mc(self) -> int | Reply:
        if self.mc_phase == "stopped":
            return codes.RC_OK
        self.mc_phase = "stopping"

        def stopped():
            self.mc.stop(self.now_ns)
            self.mc_phase = "stopped"
            self._mc_changed(self.now_ns)
        return Reply(delay_ns=self.timings.mc_stop_ns, then=stopped)

    def start_mc(self) -> int | Reply:
        if self.flash_busy():
            raise SdoAbort(codes.ABORT_STATE, "flash save in progress")
        if self.mc_phase == "running":
            return codes.RC_OK
        self.mc_phase = "starting"

        def started():
            # a firmware start copies ROM to RAM (seeds 2.3): MC and application layers start again
            self.params.load_ram_from_rom({2, 4})
            self._mc_start_now(self.now_ns)
        return Reply(delay_ns=self.timings.mc_start_ns, then=started)

    def _mc_start_now(self, t: int) -> None:
        p = self.mc.params
        motor = p[MOTOR_TYPE_UPID].ram if MOTOR_TYPE_UPID in p else 1
        error = self.mc.start(t, motor_defined=motor != 0)
        self.mc_phase = "running"
        if error is not None:
            self.errlog.log(error, self._operating_ms(t))
        self._mc_changed(t)

    def save_to_flash(self, what: str) -> int:
        if self.mc_phase != "stopped":
            if self.protocol.save_refusal == "abort":
                raise SdoAbort(codes.ABORT_STATE, "MC software runs: stop it (35h) before a flash save")
            return codes.RC_MC_NOT_STOPPED
        store = self.curves if what == "curves" else self.ct
        kib = -(-store.flash_image_bytes() // 1024)
        self._flash_busy = what

        def done(te):
            store.commit_to_flash()
            self.flash_cycles[what] += 1
            self._flash_busy = None
        self._at(self.now_ns + self.timings.flash_base_ns + kib * self.timings.flash_per_kib_ns, done)
        return codes.RC_OK

    # ------------------------------------------------------------------ MC and PDOs
    def _mc_changed(self, t: int) -> None:
        """The MC changed outside its own cycle (start, stop): event-driven TxPDOs follow."""
        self.pdo.publish(t)

    def _log_error(self, code: int, t: int) -> None:
        self.errlog.log(code, self._operating_ms(t))

    def interface_error(self, code: int, t: int) -> None:
        """An error of the CANopen interface (bad PDO mapping, spec 4.5): shown as the drive's error."""
        self.mc.inject_error(code, t)

    def send_pdo(self, t: int, cob: int, payload: bytes) -> None:
        # TxPDO2 goes on every SYNC: the frame is built without the checks its mapping already made
        self._out.append((t + self.timings.pdo_latency_ns, Frame.checked_by_caller(cob, payload)))
