"""The fault-injection matrix of the commissioning: every fault family at every phase, checked against the
emulated drive's memory (docs/commissioning.md, "The fault-injection matrix").

    from linmot_st.jobs.commission.faultmatrix import FAMILIES, PHASES, run_cell, totals
    cell = run_cell("lost", "curves")
    cell.problems()          # [] when the cell meets every target

One cell: plc_project (the example dataset, 1 axis, flash, reset, verify, pre-flight) against one emulated
E1100 (fast timings) on the simulated bus. When the axis enters the phase, the fault is armed; the run
goes on until the FB reports Done or Error (or a hang is declared). Then the fault is removed (a removed
drive is switched on again) and a second run on the same PLC and drive must succeed. Each cell records:
  - the outcome: tolerated (Done) or reported (Error), and the time from the fault to the report against
    the bound of docs/commissioning.md ("Error bounds");
  - a false success: Done although the drive's memory differs from the dataset, or the drive is not
    Operational, or its MC does not run;
  - stale confirmations: answers the channel took that ended on the bus before the request they were
    taken for (from the trace and the axis' Replies/Resp after each scan);
  - a duplicate false alarm: an Error in the "duplicated" family (a duplicate must never count);
  - a hang (no Done/Error within the bound), a crash (an exception or a PLC fault);
  - the MC left stopped after a reported failure (the drive present), and a refused dataset that wrote;
  - the recovery: the second run Done and verified.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from linmot_st.bus import Frame, SimBus
from linmot_st.cosim import CoSim
from linmot_st.emulator import DriveTimings
from linmot_st.emulator.models import make_drive
from linmot_st.plc import Plc, PlcFault

from .project import MAILBOX
from .runner import RunOptions, _configure, node_id_table, phase_name
from .testing import example, project_build
from .verify import drive_state, verify

MS = 1_000_000
S = 1_000_000_000
NODE = 1

PHASES = ("check", "compare", "preflight", "params", "curves", "ct", "flash", "reset", "verify")
FAMILIES = ("lost", "delayed_short", "delayed_long", "duplicated", "corrupted", "wrong_cs", "abort",
            "result_code", "drive_reset", "nmt_reset_comm", "removed", "foreign_node", "execute_dropped",
            "two_instances")
# families a correct PLC must ride out: an Error there is a false alarm
TOLERATED = ("delayed_short", "duplicated", "corrupted", "foreign_node", "execute_dropped", "two_instances")

# the FB's and the channel's defaults (plc_project leaves them): docs/commissioning.md, "Error bounds"
SDO_TIMEOUT, MC_TIMEOUT, FLASH_TIMEOUT, BOOT_TIMEOUT, POLL = 1 * S, 10 * S, 10 * S, 10 * S, 10 * MS
TICK = 1 * MS


def bound_ns(phase: str) -> int:
    """The longest time from a fault to its report in this phase (docs/commissioning.md, "Error bounds")."""
    if phase == "flash":
        # the failing request's timeout (McTimeout for 35h/36h), then the MC restart: attempts for
        # FlashTimeout, the last one answered within McTimeout (twice that if it waited for a re-sync)
        return MC_TIMEOUT + FLASH_TIMEOUT + 2 * MC_TIMEOUT + POLL + 2 * TICK
    if phase == "reset":
        # the boot-up within BootTimeout of the reset request, NMT Operational within BootTimeout of it;
        # a request of the check (1017h) within SdoTimeout
        return BOOT_TIMEOUT + SDO_TIMEOUT + 2 * TICK
    return SDO_TIMEOUT + 2 * TICK


@dataclass
class Cell:
    family: str
    phase: str
    armed_ns: int | None = None
    fault_ns: int | None = None          # when the fault acted (None: it never did)
    done: bool = False
    error: bool = False
    error_id: int = 0
    fail_phase: str = ""
    report_ns: int | None = None
    mc_stopped: bool = False             # the FB's McStopped
    mc_running: bool = True              # after run 1
    false_success: bool = False
    stale: int = 0
    hang: bool = False
    crash: str = ""
    wrote_before_writes: bool = False    # failed before the first write, yet the drive changed
    second_done: bool = False
    second_verified: bool = False
    second_error_id: int = 0
    notes: list[str] = field(default_factory=list)

    @property
    def reported(self) -> bool:
        return self.error

    @property
    def delay_ns(self) -> int | None:
        if self.report_ns is None or self.fault_ns is None or not self.error:
            return None
        return self.report_ns - self.fault_ns

    @property
    def within_bound(self) -> bool:
        d = self.delay_ns
        return d is None or d <= bound_ns(self.phase)

    @property
    def false_alarm(self) -> bool:
        return self.error and self.family in TOLERATED

    @property
    def recovered(self) -> bool:
        return self.second_done and self.second_verified

    @property
    def mc_left_stopped(self) -> bool:
        return self.error and self.family != "removed" and not self.mc_running

    def problems(self) -> list[str]:
        out = []
        if self.crash:
            out.append(f"crash: {self.crash}")
        if self.hang:
            out.append("hang: no Done or Error within the bound")
        if self.false_success:
            out.append("false success: Done, but the drive does not hold the dataset (or is not back)")
        if self.stale:
            out.append(f"{self.stale} stale confirmation(s)")
        if self.false_alarm:
            out.append(f"false alarm: ErrorID 16#{self.error_id:04X} for a fault to be tolerated")
        if not self.within_bound:
            out.append(f"reported {self.delay_ns / 1e6:.1f} ms after the fault, bound {bound_ns(self.phase) / 1e6:.0f} ms")
        if self.mc_left_stopped:
            out.append("MC left stopped")
        if self.wrote_before_writes:
            out.append(f"failed in {self.fail_phase}, before any write, yet the drive changed")
        if not self.recovered:
            out.append(f"the next run did not succeed (ErrorID 16#{self.second_error_id:04X})")
        return out


# ---------------------------------------------------------------- fault injection

def _nth_answer(n: int) -> Callable[[Frame], bool]:
    """A predicate true for the n-th answer of the drive it is asked about (once)."""
    seen = {"k": 0}

    def pred(f: Frame) -> bool:
        if f.can_id != 0x580 + NODE:
            return False
        seen["k"] += 1
        return seen["k"] == n
    return pred


def _each_answer_twice() -> Callable[[Frame], bool]:
    state = {"copy": False}

    def pred(f: Frame) -> bool:
        if f.can_id != 0x580 + NODE:
            return False
        state["copy"] = not state["copy"]
        return state["copy"]
    return pred


def _wrong_cs(f: Frame) -> Frame:
    d = bytearray(f.data)
    d[0] = 0x43 if d[0] == 0x60 else 0x60
    return Frame(f.can_id, bytes(d))


def _abort(f: Frame) -> Frame:
    return Frame(f.can_id, bytes([0x80]) + f.data[1:4] + (0x08000000).to_bytes(4, "little"))


def _result_code(f: Frame) -> Frame:
    d = bytearray(f.data.ljust(8, b"\0"))
    if d[0] == 0x60:
        d[6] = 0xC2            # range error in a download answer
    else:
        d[4] = 0xD4            # object state in a get answer's result byte (a value elsewhere)
    return Frame(f.can_id, bytes(d))


class ForeignNode:
    """Another CANopen node (ID 3) on the bus: boot-up, then every millisecond its heartbeat, a PDO and an
    SDO answer of its own; nothing for node 1."""

    def __init__(self, t0: int) -> None:
        self.next = t0

    def on_frame(self, frame, t):
        return []

    def on_timer(self, t):
        first = self.next == t and not getattr(self, "_booted", False)
        self.next = t + 1 * MS
        if first:
            self._booted = True
            return [(t, Frame(0x703, b"\x00"))]
        return [(t, Frame(0x703, b"\x05")), (t, Frame(0x183, bytes(8))),
                (t, Frame(0x583, bytes([0x43, 0x00, 0x10, 0x00, 0x91, 0x01, 0x0F, 0x00])))]

    def next_timer_ns(self):
        return self.next


class _Injector:
    """Arms one family's fault on the bus, the drive or the PLC; tells when it acted; removes it."""

    def __init__(self, family: str, bus, plc, drive) -> None:
        self.family, self.bus, self.plc, self.drive = family, bus, plc, drive
        self.faults: list = []
        self.event_ns: int | None = None
        self.foreign = False
        self.removed = False

    def arm(self, t: int) -> None:
        b, fam = self.bus, self.family
        nth = _nth_answer(2)
        if fam == "lost":
            self.faults.append(b.drop(nth, count=1))
        elif fam in ("delayed_short", "delayed_long"):
            # just inside the timeout; or beyond it: the drive's later answers wait behind it (fifo), so it
            # reaches the PLC right before the answer to the first request of the next run, which in CHECK
            # asks the same object again (the phase's first answer is the one held back)
            late = fam == "delayed_long"
            d = SDO_TIMEOUT + 8 * MS if late else SDO_TIMEOUT - 3 * MS
            self.faults.append(b.delay(_nth_answer(1) if late else nth, d, count=1, fifo=True))
        elif fam == "duplicated":
            self.faults.append(b.duplicate(_each_answer_twice()))
        elif fam == "corrupted":
            self.faults.append(b.corrupt(nth, count=1))
        elif fam in ("wrong_cs", "abort", "result_code"):
            fn = {"wrong_cs": _wrong_cs, "abort": _abort, "result_code": _result_code}[fam]
            self.faults.append(b.mutate_payload(nth, fn, count=1))
        elif fam == "drive_reset":
            self.event_ns = t + 1 * MS
            b.reset_node("drive1", self.event_ns)
        elif fam == "nmt_reset_comm":
            self.event_ns = t + 1 * MS
            master = b.endpoint("master")
            b.call_at(self.event_ns, lambda te: master.send(Frame(0x000, bytes([0x82, NODE])), te))
        elif fam == "removed":
            self.event_ns = t + 1 * MS
            b.remove_node("drive1", self.event_ns)
            self.removed = True
        elif fam == "foreign_node":
            self.event_ns = t
            b.attach(ForeignNode(t), "foreign")
            self.foreign = True
        elif fam == "execute_dropped":
            self.event_ns = t
            self.plc["MAIN.START"] = False
        elif fam == "two_instances":
            self.event_ns = t
            self.plc["MAIN.NODEIDS"] = node_id_table([NODE, NODE])
            self.plc["MAIN.AXES"] = 2
        else:
            raise ValueError(f"unknown fault family {fam!r}")

    def late_frames(self) -> set[int]:
        """The frames held back past their request's timeout (identity): taking one later is stale."""
        if self.family != "delayed_long":
            return set()
        return {id(h[2]) for f in self.faults for h in f.hits}

    def acted_ns(self) -> int | None:
        if self.event_ns is not None:
            return self.event_ns
        hits = [f.hits[0][0] for f in self.faults if f.hits]
        return min(hits) if hits else None

    def stop_streams(self) -> None:
        """End the faults that last (duplicates) when the phase is over."""
        if self.family == "duplicated":
            for f in self.faults:
                f.cancel()

    def remove(self) -> None:
        for f in self.faults:
            f.cancel()
        if self.foreign:
            self.bus.detach("foreign")
        if self.removed:
            self.bus.attach(self.drive, "drive1")
            self.drive.power_on(self.bus.now)
        if self.family == "two_instances":
            self.plc["MAIN.AXES"] = 1
            self.plc["MAIN.NODEIDS"] = node_id_table([NODE])


# ---------------------------------------------------------------- one cell

class _Watch:
    """Per scan: the axis' outputs, and whether an answer the channel took could not be its request's."""

    def __init__(self, plc, bus) -> None:
        v = plc.var
        self.plc, self.bus = plc, bus
        self.phase, self.done, self.error = v("MAIN.A1.COM.PHASE"), v("MAIN.A1.COM.DONE"), v("MAIN.A1.COM.ERROR")
        self.replies, self.resp = v("MAIN.A1.AX.REPLIES"), v("MAIN.A1.AX.RESP")
        self.last_replies = self.replies.value
        self.pos = len(bus.trace)
        self.req_end = 0                 # end of the last SDO request of a service on the bus
        self.stale = 0
        self.late: set[int] = set()      # frames held back past their request's timeout

    def after_scan(self, t_scan: int) -> None:
        trace = self.bus.trace
        new, self.pos = trace[self.pos:], len(trace)
        delivered = []
        for e in new:
            if e.status == "error":
                continue
            f = e.frame
            if f.can_id == 0x580 + NODE:
                delivered.append(e)
            elif (e.sender == "plc" and f.can_id == 0x600 + NODE and len(f.data) == 8 and f.data[0] != 0x80
                  and f.data[:4] != b"\x40\x00\x10\x00"):
                # every request on the bus by now was sent before this scan: the last one is the pending one
                self.req_end = max(self.req_end, e.end_ns)
        n = self.replies.value
        if n != self.last_replies:
            resp = bytes(self.resp.value)
            same = [e for e in delivered if bytes(e.frame.data) == resp]
            fresh = [e for e in same if id(e.frame) not in self.late]
            # stale: no frame with that content ended after the pending request, or only a held-back one did
            if not same or max(e.end_ns for e in same) < self.req_end or not fresh:
                self.stale += 1
            self.last_replies = n


def _project():
    return project_build()


_baseline: dict[int, int] = {}


def _baseline_ns(build) -> int:
    """PLC time from switch-on to Done of a run without fault (once per build and process)."""
    key = id(build)
    if key not in _baseline:
        plc, bus = Plc(build), SimBus(500_000)
        drive = make_drive("E1100", NODE, timings=DriveTimings.fast())
        bus.attach(drive, "drive1")
        drive.power_on(0)
        sim = CoSim(plc, bus, mailbox=MAILBOX)
        _configure(plc, RunOptions(axes=1, reset=True, timings="fast"), [NODE], drive.curves.capacity_bytes)
        sim.run_until(lambda: plc["MAIN.A1.COM.DONE"] or plc["MAIN.A1.COM.ERROR"], max_scans=120_000)
        if not plc["MAIN.A1.COM.DONE"]:
            raise RuntimeError("the fault matrix's reference run did not succeed")
        _baseline[key] = plc.time_ns
    return _baseline[key]


def run_cell(family: str, phase: str, build=None, timings=None) -> Cell:
    """One cell; `timings`: the drive's (default DriveTimings.fast(); a longer boot_ns leaves the drive
    rebooting when run 1 fails)."""
    cell = Cell(family, phase)
    pvl = example()
    opts = RunOptions(axes=1, reset=True, timings="fast")
    build = build or _project()
    plc = Plc(build)
    bus = SimBus(500_000)
    timings = timings or DriveTimings.fast()
    drive = make_drive("E1100", NODE, timings=timings)
    bus.attach(drive, "drive1")
    drive.power_on(0)
    before = drive_state(drive)
    sim = CoSim(plc, bus, mailbox=MAILBOX)
    _configure(plc, opts, [NODE], drive.curves.capacity_bytes)
    inj = _Injector(family, bus, plc, drive)
    watch = _Watch(plc, bus)
    timeouts = plc.var("MAIN.A1.AX.TIMEOUTS")
    timeouts_at_arm = timeouts.value
    target = phase
    # a hang: no Done or Error by the end of a run without fault plus the phase's bound and a margin for the
    # waits a tolerated fault adds (a late answer, a re-synchronisation)
    limit_ns = _baseline_ns(build) + bound_ns(phase) + 2 * SDO_TIMEOUT \
        + 3 * max(0, timings.boot_ns - DriveTimings.fast().boot_ns)      # a slower boot: run 2 waits, resets
    try:
        while True:
            t = plc.time_ns
            sim.step(1)
            if timeouts.value != timeouts_at_arm:      # the held-back answer's request timed out
                watch.late = inj.late_frames()
            watch.after_scan(t)
            ph = phase_name(watch.phase.value)
            if cell.armed_ns is None and ph == target:
                cell.armed_ns = plc.time_ns
                timeouts_at_arm = timeouts.value
                inj.arm(bus.now)
            elif cell.armed_ns is not None and ph != target:
                inj.stop_streams()
            if watch.done.value or watch.error.value:
                cell.report_ns = t + plc.tick_ns
                break
            if plc.time_ns > limit_ns:
                cell.hang = True
                break
        cell.fault_ns = inj.acted_ns()
        com = plc["MAIN.A1.COM"]
        cell.done, cell.error, cell.error_id = bool(com["DONE"]), bool(com["ERROR"]), com["ERRORID"]
        cell.fail_phase = phase_name(com["FAILPHASE"]) if cell.error else ""
        cell.mc_stopped = bool(com.get("MCSTOPPED", False))
        cell.stale = watch.stale
        present = not inj.removed
        # a drive still rebooting has no MC running yet, and the FB cannot start it: not left stopped
        cell.mc_running = present and (drive.mc_phase == "running" or not drive.booted)
        if cell.done:
            v = verify(pvl, {NODE: drive}, opts)
            back = drive.nmt_state == "OPERATIONAL" and drive.mc_phase == "running"
            cell.false_success = not (v.ok and back)
            if cell.false_success:
                cell.notes += [d for c in v.checks if not c.ok for d in c.differences[:3]]
        if cell.error and cell.fail_phase in ("wait", "start", "check", "compare", "preflight") and present:
            cell.wrote_before_writes = drive_state(drive) != before
        if family == "two_instances" and plc["MAIN.A2.COM.ERRORID"] != 0x0208:
            cell.notes.append(f"second instance: ErrorID 16#{plc['MAIN.A2.COM.ERRORID']:04X}, not NodeIdInUse")
            cell.false_success = True
        # the next run: the fault removed, Start again on the same PLC and drive
        inj.remove()
        def scan() -> None:              # a late answer of run 1 must not complete a request of run 2
            t = plc.time_ns
            sim.step(1)
            watch.after_scan(t)

        # Start again right away: a drive switched on again, or still rebooting, is waited for by the run
        # (its WAIT phase), not by the harness
        plc["MAIN.START"] = False
        scan()
        scan()
        plc["MAIN.START"] = True
        end = plc.time_ns + limit_ns
        while not (watch.done.value or watch.error.value) and plc.time_ns < end:
            scan()
        cell.stale = watch.stale
        cell.second_done = bool(plc["MAIN.A1.COM.DONE"])
        cell.second_error_id = plc["MAIN.A1.COM.ERRORID"]
        cell.second_verified = cell.second_done and verify(pvl, {NODE: drive}, opts).ok
    except PlcFault as exc:
        cell.crash = str(exc)
    except Exception as exc:   # noqa: BLE001 - a crash of the harness or the PLC is what the cell counts
        cell.crash = f"{type(exc).__name__}: {exc}"
    return cell


def run_matrix(families=FAMILIES, phases=PHASES, build=None, progress: Callable[[Cell], Any] | None = None
               ) -> list[Cell]:
    build = build or _project()
    cells = []
    for fam in families:
        for ph in phases:
            c = run_cell(fam, ph, build)
            cells.append(c)
            if progress:
                progress(c)
    return cells


def totals(cells: list[Cell]) -> dict[str, int]:
    """The matrix totals the issue sets targets for (all 0 but cells and recovered)."""
    return dict(
        cells=len(cells),
        reported=sum(c.reported for c in cells),
        tolerated=sum(c.done for c in cells),
        false_successes=sum(c.false_success for c in cells),
        stale_confirmations=sum(c.stale for c in cells),
        duplicate_false_alarms=sum(c.error for c in cells if c.family == "duplicated"),
        false_alarms=sum(c.false_alarm for c in cells),
        beyond_bound=sum(not c.within_bound for c in cells),
        hangs=sum(c.hang for c in cells),
        crashes=sum(bool(c.crash) for c in cells),
        mc_left_stopped=sum(c.mc_left_stopped for c in cells),
        wrote_before_writes=sum(c.wrote_before_writes for c in cells),
        recovered=sum(c.recovered for c in cells),
    )
