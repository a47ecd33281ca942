"""Running a commissioning: emulated drives on a bus, the PLC stepped until every axis is done or failed.

    from linmot_st.jobs.commission.runner import RunOptions, run
    result = run(pvl, RunOptions(axes=2), build_result=res)

On the simulated bus (`bus="sim"`) everything runs in virtual time with CoSim; on a python-can bus
(`virtual[:CH]`, `socketcan:CH`, `INTERFACE:CH`) the drives are served by NodeServer threads and the PLC
runs in real time with RealTimeCoSim. After every scan a sampler reads each axis' phase and exchange
counter (that is how the report knows each phase's scans, time and exchanges) and tells the progress
display. Tests pass `drive_factory` (drives with other trees or limits) and `prepare_bus` (fault
injection on the SimBus).
"""

from __future__ import annotations

import functools
import os
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from linmot_st.bus import Frame, SimBus, frame_length_bits, open_bus
from linmot_st.bus.bits import max_bus_bits
from linmot_st.bus.pycan import OwnFrames, parse_bus_spec
from linmot_st.bus.stats import BusStats, bus_stats
from linmot_st.cosim import CoSim, CoSimTimeout, IdlePredicate, RealTimeCoSim
from linmot_st.emulator import DriveTimings
from linmot_st.emulator.models import make_drive
from linmot_st.plc import Plc, PlcFault
from linmot_st.pvl.dataset import expected_exchanges, from_pvl

from ..span import Span
from .datasets import Datasets, Source, check_drive_type, drive_series
from .project import INSTANCE, MAILBOX, MAX_AXES
from .verify import drive_state

PHASES = ("idle", "wait", "start", "check", "compare", "preflight", "params", "curves", "ct", "flash", "reset", "verify", "done")


@functools.cache      # the sampler asks for every axis before every scan
def phase_name(enum_value: str) -> str:
    """LM_COM_PARAMS -> params."""
    return enum_value.removeprefix("LM_COM_").lower()


def item_kind(enum_value: str) -> str:
    """E_LmComItemKind -> dataset, layer, param, curve, entry, service ("" for LM_COM_ITEM_NONE)."""
    kind = enum_value.removeprefix("LM_COM_ITEM_").lower()
    return "" if kind == "none" else kind


def check_bus_spec(spec: str) -> None:
    """Refuse a bus spec that `linmot_st.bus.open_bus` would refuse, before anything is built (ValueError);
    whether the bus exists is known only when it is opened."""
    if spec == "sim":
        return

    parse_bus_spec(spec, where=f"--bus {spec!r}", forms="sim, virtual[:CHANNEL], or INTERFACE:CHANNEL")


@dataclass
class RunOptions:
    axes: int = 1
    node_ids: list[int] | None = None          # default 1..axes
    bus: str = "sim"                           # sim | virtual[:CH] | socketcan:CH | INTERFACE:CH
    bitrate: int = 500_000
    live_ram: bool = False
    flash: bool = True
    reset: bool = True
    verify: bool = True
    preflight: bool = True                     # the FB asks each drive whether it can take the dataset first
    force: bool = False                        # write everything (Force); default: only what differs
    curve_memory: int | None = None            # bytes of curve memory (CurveMemory); None: the emulated
                                               # drive's capacity, 0 with real drives (not checked)
    timings: str | None = None                 # "real" | "fast"; default real on sim, fast on real-time buses
    latency_ns: int = 0                        # extra latency of the drives' frames on the simulated bus
    timeout_s: float | None = None             # virtual (sim) or wall seconds; default from the dataset
    emulate: bool = True                       # False: real drives on the bus (python-can buses only)
    drive_model: str | None = None             # the emulated drives' model (emulator/models.py); None: each
                                               # node's drive is of the series its PVL file is for
    drive_models: dict = field(default_factory=dict)   # node ID -> model (`--drive NODE=MODEL`), before both
    series: dict = field(default_factory=dict)  # node ID -> the series its PVL file is for (set by run())
    fast_idle: bool = True                     # sim: idle scans run in C (linmot_st.cosim); False: every scan
                                               # from Python (the same frames at the same times, slower)

    def nodes(self) -> list[int]:
        ids = list(self.node_ids) if self.node_ids else list(range(1, self.axes + 1))
        if not 1 <= len(ids) <= MAX_AXES:
            raise ValueError(f"{len(ids)} axes: plc_project commissions 1..{MAX_AXES}")
        if len(set(ids)) != len(ids) or not all(1 <= n <= 127 for n in ids):
            raise ValueError(f"node IDs {ids}: each 1..127, no duplicates")
        return ids

    @property
    def simulated(self) -> bool:
        return self.bus == "sim"

    def timing_kind(self) -> str:
        return self.timings or ("real" if self.simulated else "fast")


@dataclass
class PhaseRecord(Span):
    phase: str
    t0_ns: int                  # time of its first scan
    scan0: int
    exch0: int
    t1_ns: int = 0              # time of the first scan after it
    scan1: int = 0
    exchanges: int = 0
    items_total: int = 0


@dataclass
class AxisResult:
    axis: int
    node_id: int
    done: bool = False
    error: bool = False
    error_id: int = 0
    abort_code: int = 0
    fail_phase: str = ""
    fail_item: int = 0
    fail_kind: str = ""                        # what fail_item names: dataset, layer, param, curve, entry, service
    fail_step: int = 0
    fail_expected: int = 0
    fail_actual: int = 0
    drive_layer: tuple[int, int, int] = (0, 0, 0)
    exchanges: int = 0
    live_written: int = 0
    written: int = 0                           # items written, skipped (the drive held them), read back equal
    skipped: int = 0
    verified: int = 0
    mc_stopped: bool = False                   # the run left the drive's MC stopped (McStopped)
    fail_delay_ns: int = 0                     # from the failure to its report (the MC restart; FailDelay)
    up_ns: int | None = None                   # when the PLC first heard the drive
    phases: list[PhaseRecord] = field(default_factory=list)

    @property
    def started_ns(self) -> int | None:
        return self.phases[0].t0_ns if self.phases else None

    @property
    def ended_ns(self) -> int | None:
        return self.phases[-1].t1_ns if self.phases and (self.done or self.error) else None

    @property
    def finished(self) -> bool:
        return self.done or self.error


@dataclass
class TraceRecord:
    """A frame seen on a python-can bus (the in-memory trace of a real-time run), shaped like SimBus's
    TraceEntry so that one statistics function serves both."""
    start_ns: int
    end_ns: int
    sender: str
    frame: Frame
    status: str = "ok"


@dataclass
class RunResult:
    options: RunOptions
    node_ids: list[int]
    tick_ns: int
    bit_ns: int
    axes: list[AxisResult]
    trace: list                                # SimBus TraceEntry or TraceRecord
    drives: dict                               # node ID -> emulated drive (emulator/models.py)
    scans: int = 0
    wall_s: float = 0.0
    timed_out: bool = False
    interrupted: bool = False                  # Ctrl-C ended the run (the report says what was done)
    fault: str = ""                            # a PLC fault (division by zero, index out of range) ended the run
    overruns: int = 0
    max_lateness_ns: int = 0
    skipped_ticks: int = 0                     # real time: task activations late scans missed (cosim.py)
    stats: BusStats | None = None              # over the commissioning span
    before: dict = field(default_factory=dict)  # node ID -> verify.drive_state() when switched on
    wear_before: dict = field(default_factory=dict)  # node ID -> drive_wear() when switched on
    wear_after: dict = field(default_factory=dict)   # and at the end of the run
    after: Any = None                          # what run(after=...) returned (the motion job's result)
    ram_commissioned: dict = field(default_factory=dict)  # node -> {UPID: RAM} before run(after=...): what
                                               # the commissioning left, for the verification (a move's
                                               # live parameter writes come later)
    datasets: Datasets | None = None           # each node's PVL and dataset

    @property
    def t_start_ns(self) -> int:
        starts = [a.started_ns for a in self.axes if a.started_ns is not None]
        return min(starts) if starts else 0

    @property
    def t_end_ns(self) -> int:
        ends = [a.phases[-1].t1_ns for a in self.axes if a.phases]
        return max(ends) if ends else self.t_start_ns

    def wear(self, node: int) -> dict | None:
        """What the run cost the emulated drive's non-volatile memory: flash saves per store, ROM writes."""
        if node not in self.wear_before or node not in self.wear_after:
            return None
        now, then = self.wear_after[node], self.wear_before[node]
        return {k: now[k] - then[k] for k in now}

    @property
    def commissioned(self) -> bool:
        return all(a.done for a in self.axes) and not self.timed_out and not self.fault and not self.interrupted


class Sampler(IdlePredicate):
    """Reads each axis' outputs after every scan; records phase boundaries; tells the progress display."""

    changes_nodes = False       # it reads the PLC only

    def __init__(self, plc, node_ids: list[int], progress=None) -> None:
        self.progress = progress
        self.axes = [AxisResult(k + 1, n) for k, n in enumerate(node_ids)]
        v = plc.var
        self._vars = [dict(phase=v(f"{INSTANCE}.A{k}.COM.PHASE"), exch=v(f"{INSTANCE}.A{k}.COM.EXCHANGES"),
                           done=v(f"{INSTANCE}.A{k}.COM.DONE"), error=v(f"{INSTANCE}.A{k}.COM.ERROR"),
                           up=v(f"{INSTANCE}.A{k}.UP"), items=v(f"{INSTANCE}.A{k}.COM.ITEMSDONE"),
                           total=v(f"{INSTANCE}.A{k}.COM.ITEMSTOTAL"))
                      for k in range(1, len(node_ids) + 1)]
        # what __call__ records depends on these alone (ITEMSDONE only feeds the live progress line)
        super().__init__(plc, [vs[name] for vs in self._vars for name in ("phase", "exch", "done", "error",
                                                                            "up", "total")])
        self._last_exch = [0] * len(node_ids)
        self._started = [False] * len(node_ids)
        # the axes still commissioning: each call looks at these only (a finished axis records nothing more)
        self._open = list(enumerate(zip(self.axes, self._vars)))

    def __call__(self) -> bool:
        """Called before each scan (and after the last): True when every axis has finished."""
        plc = self.plc
        run = self.begin_call()
        if run:
            t_scan = plc.time_ns - plc.tick_ns      # the scan that just ran
            scan = run - 1
            finished = False
            for k, (ax, vs) in self._open:
                if ax.up_ns is None and vs["up"].value:
                    ax.up_ns = t_scan
                phase = phase_name(vs["phase"].value)
                exch = vs["exch"].value
                cur = ax.phases[-1] if ax.phases else None
                if not self._started[k]:
                    if phase != "start" and not vs["error"].value:
                        self._last_exch[k] = exch
                        continue
                    self._started[k] = True
                if cur is None or (phase != cur.phase and phase not in ("done",)):
                    if cur is not None:
                        cur.t1_ns, cur.scan1 = t_scan, scan
                        cur.exchanges = self._last_exch[k] - cur.exch0
                    ax.phases.append(PhaseRecord(phase, t_scan, scan, self._last_exch[k]))
                    cur = ax.phases[-1]
                    if self.progress and len(ax.phases) > 1:
                        self.progress.phase_done(ax, ax.phases[-2], t_scan)
                cur.items_total = vs["total"].value
                if vs["done"].value or vs["error"].value:
                    # the scan that finished belongs to the phase it finished
                    cur.t1_ns, cur.scan1 = t_scan + plc.tick_ns, scan + 1
                    cur.exchanges = exch - cur.exch0
                    ax.done, ax.error = bool(vs["done"].value), bool(vs["error"].value)
                    finished = True
                    if self.progress:
                        self.progress.axis_finished(ax, cur, cur.t1_ns)     # the time the report gives
                self._last_exch[k] = exch
            if finished:
                self._open = [o for o in self._open if not o[1][0].finished]
            if self.progress:
                self.progress.tick(self, plc.time_ns)
        self.end_call()
        return not self._open

    def close(self) -> None:
        """After the run: an axis still in a phase (timeout, PLC fault) ends it at the last scan."""
        for ax, vs in zip(self.axes, self._vars):
            if ax.phases and not ax.finished and not ax.phases[-1].t1_ns:
                cur = ax.phases[-1]
                cur.t1_ns, cur.scan1 = self.plc.time_ns, max(self.scans - 1, cur.scan0)
                cur.exchanges = vs["exch"].value - cur.exch0

    def live(self, k: int) -> tuple[str, int, int]:
        """(phase, items done, items total) of axis k (0-based) now."""
        vs = self._vars[k]
        return phase_name(vs["phase"].value), vs["items"].value, vs["total"].value


def node_id_table(nodes: list[int]) -> list[int]:
    """plc_project's NodeIds[1..MAX_AXES] for these axes' node IDs (the rest 0: no axis)."""
    return list(nodes) + [0] * (MAX_AXES - len(nodes))


def drive_wear(drive) -> dict:
    """The emulated drive's write counters (docs/emulator.md): flash saves of each store, ROM writes."""
    return dict(flash_curves=drive.flash_cycles["curves"], flash_ct=drive.flash_cycles["ct"],
                rom_writes=drive.params.rom_writes)


def _configure(plc, opts: RunOptions, nodes: list[int], curve_memory: int = 0, bases: list[int] | None = None,
               drives_series: dict[int, str] | None = None) -> None:
    """The program's settings; `drives_series` {node: "E1100" | "B1100"} gives each axis its channel's Drive."""
    p = INSTANCE
    plc[f"{p}.AXES"] = len(nodes)
    plc[f"{p}.NODEIDS"] = node_id_table(nodes)
    plc[f"{p}.DATABASES"] = (bases or [1] * len(nodes)) + [1] * (MAX_AXES - len(nodes))
    series = [f"LM_{(drives_series or {}).get(n, 'E1100')}" for n in nodes]
    plc[f"{p}.DRIVES"] = series + ["LM_E1100"] * (MAX_AXES - len(nodes))
    plc[f"{p}.WAITBOOT"] = opts.emulate            # emulated drives are switched on with the PLC
    plc[f"{p}.LIVERAM"] = opts.live_ram
    plc[f"{p}.FLASH"] = opts.flash
    plc[f"{p}.RESET"] = opts.reset
    plc[f"{p}.VERIFY"] = opts.verify
    plc[f"{p}.PREFLIGHT"] = opts.preflight
    plc[f"{p}.CURVEMEMORY"] = curve_memory
    for k in range(1, len(nodes) + 1):
        plc[f"{p}.A{k}.FORCE"] = opts.force        # an input of each axis (FB_PlcAxis), not of the program
    plc[f"{p}.START"] = True


def _collect(plc, sampler: Sampler) -> None:
    for ax in sampler.axes:
        c = plc[f"{INSTANCE}.A{ax.axis}.COM"]
        ax.error_id, ax.abort_code = c["ERRORID"], c["ABORTCODE"]
        ax.fail_phase = phase_name(c["FAILPHASE"]) if ax.error else ""
        ax.fail_item, ax.fail_step = c["FAILITEM"], c["FAILSTEP"]
        ax.fail_kind = item_kind(c["FAILKIND"]) if ax.error else ""
        ax.fail_expected, ax.fail_actual = c["FAILEXPECTED"], c["FAILACTUAL"]
        dl = c["DRIVELAYER"]
        ax.drive_layer = (dl["TREEID"], dl["MAINVERSION"], dl["SUBVERSION"])
        ax.exchanges, ax.live_written = c["EXCHANGES"], c["LIVEWRITTEN"]
        ax.written, ax.skipped, ax.verified = c["WRITTEN"], c["SKIPPED"], c["VERIFIED"]
        ax.mc_stopped, ax.fail_delay_ns = bool(c["MCSTOPPED"]), c["FAILDELAY"]


def _curve_memory(opts: RunOptions, drives: dict) -> int:
    """CurveMemory for the FB: as given; else the smallest curve memory of the emulated drives (what a user
    reads in the drive's documentation; the E1100 does not tell it over CANopen), 0 without them."""
    if opts.curve_memory is not None:
        return opts.curve_memory
    caps = [getattr(getattr(d, "curves", None), "capacity_bytes", 0) for d in drives.values()]
    return min(caps) if caps and all(caps) else 0


def default_timeout_s(dataset, opts: RunOptions) -> float:
    """Generous: 4 ms per expected exchange, plus the drives' slow services (boot, MC start, flash, reset)."""
    n = expected_exchanges(dataset, verify=opts.verify, flash=opts.flash, preflight=opts.preflight)
    return 4e-3 * n + 60.0


def run_timeout_s(datasets, nodes: list[int], opts: RunOptions) -> float:
    """The slowest axis' default_timeout_s, plus 4 x the bus time every axis' exchanges need at the
    worst-case frame length (135 bits): the axes share one bus, so 32 of them take about 32 x one axis'
    bus time."""
    slowest = max(default_timeout_s(datasets.of(n).dataset, opts) for n in nodes)
    exchanges = sum(expected_exchanges(datasets.of(n).dataset, verify=opts.verify, flash=opts.flash,
                                       preflight=opts.preflight) for n in nodes)
    return slowest + 4 * exchanges * 2 * max_bus_bits(8) / opts.bitrate


def drive_model_of(node_id: int, opts: RunOptions, datasets=None) -> str:
    """The model of a node's emulated drive: `--drive NODE=MODEL`, else RunOptions.drive_model, else the
    series the node's PVL file is for (so a B1100 file gets an emulated B1100), else the E1100."""
    model = opts.drive_models.get(node_id) or opts.drive_model
    if model is None and datasets is not None:
        model = datasets.of(node_id).pvl.drive_type.name
    return model or "E1100"


def emulated_drive(node_id: int, opts: RunOptions, datasets=None, motion=None):
    """An emulated drive for this run, of drive_model_of(); `motion`: its MotionSettings (the motion job places
    the mechanics)."""
    timings = DriveTimings.fast() if opts.timing_kind() == "fast" else DriveTimings()
    return make_drive(drive_model_of(node_id, opts, datasets), node_id, timings=timings, motion=motion)


def run(pvl, opts: RunOptions, build_result, *, dataset=None, datasets=None, progress=None,
        drive_factory: Callable[[int], Any] | None = None,
        prepare_bus: Callable[[Any, dict], None] | None = None,
        prepare_plc: Callable[[Any], None] | None = None,
        after: Callable[[Any, Any, dict], Any] | None = None) -> RunResult:
    """Commission with the PLC of `build_result` (plc_project with this PVL's dataset). `prepare_plc(plc)`
    runs after the program's settings are written and before the first scan (tests: patch the dataset).
    `after(plc, cosim, drives)` runs once every axis is commissioned, on the same PLC, bus and drives, before
    they are shut down (the motion job: linmot_st.jobs.motion); its result is RunResult.after. `datasets`
    (datasets.Datasets, built with this PLC's dataset file) gives nodes datasets of their own."""
    nodes = opts.nodes()
    if datasets is None:
        datasets = Datasets(Source(pvl, dataset or from_pvl(pvl), getattr(pvl, "filename", None) or "PVL"))
    timeout_s = opts.timeout_s or run_timeout_s(datasets, nodes, opts)
    plc = Plc(build_result)
    factory = _checked_factory(drive_factory or (lambda n: emulated_drive(n, opts, datasets)), datasets)
    bases = datasets.bases(nodes)
    opts.series = {n: datasets.of(n).pvl.drive_type.name for n in nodes}   # each axis' Drive (the PLC's setting)
    if opts.simulated:
        res = _run_sim(plc, opts, nodes, factory, prepare_bus, prepare_plc, progress, timeout_s, after, bases)
    else:
        res = _run_realtime(plc, opts, nodes, factory, prepare_plc, progress, timeout_s, after, bases)
    res.datasets = datasets
    return res


def _ram_of(drives: dict) -> dict:
    out = {}
    for n, d in drives.items():
        with d.lock:                    # a real-time drive runs in its own thread
            out[n] = {p.upid: p.ram for p in d.params}
    return out


def _checked_factory(factory, datasets):
    """The drive factory, refusing a drive whose series is not what its node's PVL file is for (before the
    drive is powered on, so before the PLC sends it anything)."""
    def make(node: int):
        drive = factory(node)
        check_drive_type(node, datasets.of(node), drive_series(drive))
        return drive
    return make


def _run_sim(plc, opts, nodes, factory, prepare_bus, prepare_plc, progress, timeout_s, after, bases) -> RunResult:
    bus = SimBus(opts.bitrate)
    drives = {}
    for n in nodes:
        d = factory(n)
        bus.attach(d, f"drive{n}", latency_ns=opts.latency_ns)
        d.power_on(0)
        drives[n] = d
    before = {n: drive_state(d) for n, d in drives.items()}
    wear_before = {n: drive_wear(d) for n, d in drives.items()}
    if prepare_bus:
        prepare_bus(bus, drives)
    sim = CoSim(plc, bus, mailbox=MAILBOX, name="plc", fast_idle=opts.fast_idle)
    _configure(plc, opts, nodes, _curve_memory(opts, drives), bases, opts.series)
    if prepare_plc:
        prepare_plc(plc)
    sampler = Sampler(plc, nodes, progress)
    wall0 = time.perf_counter()
    timed_out, fault, interrupted = False, "", False
    try:
        sim.run_until(sampler, max_scans=int(timeout_s * 1e9 // plc.tick_ns))
    except CoSimTimeout:
        timed_out = True
    except PlcFault as exc:
        fault = str(exc)
    except KeyboardInterrupt:                  # Ctrl-C: stop, and report what was done so far
        interrupted = True
    wall = time.perf_counter() - wall0
    sampler.close()
    _collect(plc, sampler)
    commissioned = all(a.done for a in sampler.axes) and not timed_out and not fault
    ram_commissioned = _ram_of(drives) if after is not None else {}
    after_result = after(plc, sim, drives) if after is not None and commissioned else None
    res = RunResult(opts, nodes, plc.tick_ns, bus.bit_ns, sampler.axes, list(bus.trace), drives,
                    scans=sim.scans, wall_s=wall, timed_out=timed_out, fault=fault, before=before,
                    interrupted=interrupted, after=after_result, ram_commissioned=ram_commissioned, wear_before=wear_before,
                    wear_after={n: drive_wear(d) for n, d in drives.items()})
    res.stats = bus.stats(res.t_start_ns, max(res.t_end_ns, res.t_start_ns))
    return res


class _RecordingBus:
    """A python-can Bus wrapper that keeps every frame the PLC sends or receives (the run's trace)."""

    def __init__(self, bus, t0: int, bit_ns: int, echo: bool = False) -> None:
        self.bus, self.t0, self.bit_ns = bus, t0, bit_ns
        self.records: list[TraceRecord] = []
        self._own = OwnFrames() if echo else None      # echo: the bus returns the PLC's own frames

    def _record(self, msg, sender: str) -> None:
        frame = Frame.from_message(msg)
        end = time.monotonic_ns() - self.t0
        self.records.append(TraceRecord(end - frame_length_bits(frame) * self.bit_ns, end, sender, frame))

    def send(self, msg, timeout=None):
        self.bus.send(msg, timeout=timeout)
        self._record(msg, "plc")
        if self._own is not None:
            self._own.sent(msg)

    def recv(self, timeout=None):
        msg = self.bus.recv(timeout=timeout)
        if (msg is not None and not (self._own is not None and self._own.is_own(msg))   # own: recorded by send
                and not (msg.is_error_frame or msg.is_extended_id or getattr(msg, "is_fd", False))):
            self._record(msg, f"node{msg.arbitration_id & 0x7F}")
        return msg


def _run_realtime(plc, opts, nodes, factory, prepare_plc, progress, timeout_s, after, bases) -> RunResult:
    spec = opts.bus
    if spec == "virtual":
        spec = f"virtual:linmot-st-commission-{os.getpid()}"
    if not opts.emulate and spec.startswith("virtual"):
        raise ValueError("--no-emulate needs a real bus (socketcan:CHANNEL): nothing else is on a virtual bus")
    drive_buses, drives = [], {}
    plc_bus = None
    bit_ns = 1_000_000_000 // opts.bitrate
    try:
        def opened(**kwargs):
            try:
                return open_bus(spec, bitrate=opts.bitrate, **kwargs)
            except OSError as exc:
                raise OSError(f"--bus {opts.bus}: cannot open it ({exc}); SocketCAN needs a Linux kernel with "
                              "CAN support and the interface up (docs/bus.md)") from exc

        if opts.emulate:
            for n in nodes:
                drive_buses.append(opened())
                drives[n] = factory(n)
        before = {n: drive_state(d) for n, d in drives.items()}
        wear_before = {n: drive_wear(d) for n, d in drives.items()}
        # the PLC's own frames come back once sent: the mailbox's transmit confirmation (TxEcho), where
        # the interface can give them
        try:
            raw, echo = opened(receive_own_messages=True), True
        except TypeError:
            raw, echo = opened(), False
        plc_bus = _RecordingBus(raw, time.monotonic_ns(), bit_ns, echo)
        for b, d in zip(drive_buses, drives.values()):
            d.attach(b)                                  # switched on now: boots after its boot time
        sim = RealTimeCoSim(plc, plc_bus, mailbox=MAILBOX, echo=echo)
        _configure(plc, opts, nodes, _curve_memory(opts, drives), bases, opts.series)
        if prepare_plc:
            prepare_plc(plc)
        sampler = Sampler(plc, nodes, progress)
        plc_bus.t0 = time.monotonic_ns()                 # trace times = PLC times
        wall0 = time.perf_counter()
        timed_out, fault, interrupted = False, "", False
        try:
            sim.run_until(sampler, timeout_s=timeout_s)
        except CoSimTimeout:
            timed_out = True
        except PlcFault as exc:
            fault = str(exc)
        except KeyboardInterrupt:              # the drives' threads are stopped below, then the report
            interrupted = True
        wall = time.perf_counter() - wall0
        sampler.close()
        commissioned = all(a.done for a in sampler.axes) and not timed_out and not fault
        ram_commissioned = _ram_of(drives) if after is not None else {}
        after_result = after(plc, sim, drives) if after is not None and commissioned else None
    finally:
        for d in drives.values():
            d.detach()
        for b in drive_buses:
            b.shutdown()
        if plc_bus is not None:
            plc_bus.bus.shutdown()
    _collect(plc, sampler)
    # PLC time and wall time run together in a real-time run (scan k at wall start + k ticks)
    trace = sorted(plc_bus.records, key=lambda r: r.end_ns)
    res = RunResult(opts, nodes, plc.tick_ns, bit_ns, sampler.axes, trace, drives, scans=sim.scans,
                    wall_s=wall, timed_out=timed_out, fault=fault, overruns=sim.overruns,
                    max_lateness_ns=sim.max_lateness_ns, skipped_ticks=sim.skipped_ticks, before=before,
                    interrupted=interrupted, after=after_result, ram_commissioned=ram_commissioned, wear_before=wear_before,
                    wear_after={n: drive_wear(d) for n, d in drives.items()})
    res.stats = bus_stats(trace, bit_ns, res.t_start_ns, max(res.t_end_ns, res.t_start_ns))
    return res
