"""Running the motion job: commissioning (linmot_st.jobs.commission.runner), then, on the same PLC, bus and drives,
plc_project's motion steps on every axis (plc_project/motion.st), sampled scan by scan.

    from linmot_st.jobs.motion.job import run_job
    result = run_job(pvl, RunOptions(axes=2, timings="fast"), build_result, plan(pvl))
    result.commission            # the commissioning RunResult (its .after is the MotionResult)
"""

from __future__ import annotations

import time
from contextlib import contextmanager
from dataclasses import dataclass, field

from linmot_st.cosim import CoSimTimeout, IdlePredicate
from linmot_st.emulator.linmot.master_encoder import SpeedProfile
from linmot_st.jobs.commission.project import INSTANCE
from linmot_st.jobs.commission.runner import RunOptions, RunResult, emulated_drive, run
from linmot_st.protocol.upids import P_MASTER_ENCODER_SOURCE, P_TRIGGER_MODE

from ..span import Span
from .budget import admission_capacity, job_inputs, measured_load, step_burst, step_load
from .plan import CAM_TURN_MS, INPUT_EDGE_DELAY_MS, INPUT_PULSE_MS, MAX_STEPS, Plan

MS = 1_000_000
TRIGGER_MODE_DIRECT = 1         # 170Ch: the trigger input's edges as they come ([MC] 7.2.2)
INPUT_OF_STEP = {"trigger": "X4.6", "probe": "X4.5"}     # the emulated input the job toggles in the step
TOGGLED = frozenset((*INPUT_OF_STEP, "cam"))               # the steps in which the job's hand moves the rig
ENCODER_SOURCE_X10 = 1          # 172Ah: the master encoder on X10 ([MC] 7.3; the default 0 has none)


@dataclass
class StepRecord(Span):
    index: int                  # 1-based, as StepNo
    kind: str
    label: str
    t0_ns: int
    scan0: int
    t1_ns: int = 0
    scan1: int = 0
    ok: bool = False
    error_id: int = 0
    drive_error: int = 0
    # real time: the drive's clock minus the PLC's when the start / the end was seen (read right after that
    # scan, so the drive's state then is at least what the PLC saw); 0 in virtual time (one clock)
    off0_ns: int = 0
    off1_ns: int = 0
    edge_ns: int = 0            # trigger, probe: when the job raised the input; cam: when the conveyor started
                                # turning (the drive's clock)
    edge_end_ns: int = 0        # cam: when it stopped
    probed_mm: float | None = None      # probe: the position the PLC read


@dataclass
class AxisMotion:
    axis: int
    node_id: int
    steps: list[StepRecord] = field(default_factory=list)
    done: bool = False
    error: bool = False
    error_id: int = 0
    drive_error: int = 0
    fail_step: int = 0


@dataclass
class MotionResult:
    plan: Plan
    axes: list[AxisMotion]
    t0_ns: int
    t1_ns: int = 0
    scans: int = 0
    wall_s: float = 0.0
    timed_out: bool = False
    clock_offsets: dict = field(default_factory=dict)   # node -> drive time - PLC time (real time; 0 on sim)
    clock_margin_ns: int = 0                            # how far that offset may be off (real time)
    inhibit_100us: int = 0                              # TxPDO2's inhibit time the bus budget chose
    bus_load: tuple | None = None                       # (mean, peak of 100 ms) load after the PDO setup (sim)
    # emulated drives: parameters whose RAM value the steps changed (MC_Jog and MC_MoveVelocity write the
    # predefined VA interpolator's 14B0h..14C0h): node -> {upid: (RAM before the motion, after)}
    ram_changed: dict = field(default_factory=dict)
    # emulated drives: command-table entries the steps wrote to RAM (the CTLOOP step's program): node -> {entry:
    # (the entry before the motion or None, after)}
    ct_changed: dict = field(default_factory=dict)

    @property
    def finished(self) -> bool:
        return all(a.done for a in self.axes) and not self.timed_out


class MotionSampler(IdlePredicate):
    """Reads each axis' StepNo and end flags after every scan; records step boundaries; tells progress."""

    def __init__(self, plc, node_ids: list[int], plan: Plan, progress=None, drives: dict | None = None,
                 toggle_inputs: bool = True):
        self.plan, self.progress = plan, progress
        self.toggle_inputs = toggle_inputs       # False: a broken rig, the trigger / capture input never moves
        self.drives = drives or {}
        self.axes = [AxisMotion(k + 1, n) for k, n in enumerate(node_ids)]
        v = plc.var
        self._vars = [dict(step=v(f"{INSTANCE}.A{k}.MOT.STEPNO"), done=v(f"{INSTANCE}.A{k}.MOT.DONE"),
                           error=v(f"{INSTANCE}.A{k}.MOT.ERROR"), armed=v(f"{INSTANCE}.A{k}.MOT.ARMED"),
                           probed=v(f"{INSTANCE}.A{k}.MOT.PROBED"))
                      for k in range(1, len(node_ids) + 1)]
        super().__init__(plc, [vs[n] for vs in self._vars for n in ("step", "done", "error", "armed")])
        # the axes still moving, each with the accessors every call reads (a finished axis records nothing more)
        self._open = [(ax, vs, (vs["step"], vs["done"], vs["error"])) for ax, vs in zip(self.axes, self._vars)]

    def __call__(self) -> bool:
        self.changes_nodes = False      # until _toggle moves a drive's input or conveyor
        if self.begin_call():
            t = self.plc.time_ns       # the end of the scan that just ran
            n_steps = len(self.plan.steps)
            finished = False
            for ax, vs, (step, done, error) in self._open:
                k = step.value
                cur = ax.steps[-1] if ax.steps else None
                if k >= 1 and (cur is None or cur.index != k) and k <= n_steps:
                    cur = self._next_step(ax, vs, cur, k, t)
                if cur is not None and cur.kind in TOGGLED and not cur.t1_ns:
                    self._toggle(ax, cur, vs, t)
                is_done, is_error = done.value, error.value
                if is_done or is_error:
                    ax.done, ax.error = is_done, is_error
                    finished = True
                    if cur is not None and not cur.t1_ns:
                        cur.t1_ns, cur.scan1, cur.ok = t, self.scans, ax.done
                        cur.off1_ns = self._offset(ax.node_id, t)
                        if self.progress:
                            self.progress.step_done(ax, cur)
            if finished:
                self._open = [o for o in self._open if not (o[0].done or o[0].error)]
        self.end_call()
        return not self._open

    def _next_step(self, ax: AxisMotion, vs: dict, cur: StepRecord | None, k: int, t: int) -> StepRecord:
        """The PLC moved the axis on to step k in the scan that just ran (ending at t): the step before ends there."""
        t_scan = t - self.plc.tick_ns
        off = self._offset(ax.node_id, t_scan)
        if cur is not None:
            cur.t1_ns, cur.scan1, cur.ok, cur.off1_ns = t_scan, self.scans - 1, True, off
            if cur.kind == "probe":       # Probed is set in the scan the step ends
                cur.probed_mm = vs["probed"].value
            if self.progress:
                self.progress.step_done(ax, cur)
        s = self.plan.steps[k - 1]
        ax.steps.append(StepRecord(k, s.kind, s.label, t_scan, self.scans - 1, off0_ns=off))
        return ax.steps[-1]

    def _toggle(self, ax: AxisMotion, rec: StepRecord, vs: dict, t: int) -> None:
        """The job's hand on the rig: once the PLC armed the step (Armed), the step's input pulses on the
        emulated drive INPUT_EDGE_DELAY_MS later; a probe step's reading is taken when it ends."""
        if rec.kind == "probe":
            rec.probed_mm = vs["probed"].value
        drive = self.drives.get(ax.node_id)
        if rec.edge_ns or not vs["armed"].value or drive is None or not self.toggle_inputs:
            return
        rec.edge_ns = t + self._offset(ax.node_id, t) + INPUT_EDGE_DELAY_MS * MS
        self.changes_nodes = True
        if rec.kind == "cam":               # the conveyor: one cam length in CAM_TURN_MS, then it stops
            cam = self.plan.steps[rec.index - 1].cam
            now = rec.edge_ns - INPUT_EDGE_DELAY_MS * MS
            rec.edge_end_ns = rec.edge_ns + CAM_TURN_MS * MS
            drive.mc.encoder.drive_with(SpeedProfile([(rec.edge_ns, cam.length * 1000 / CAM_TURN_MS),
                                                      (rec.edge_end_ns, 0.0)],
                                                     start=drive.mc.encoder.counts(now)), now)
            return
        pin = INPUT_OF_STEP[rec.kind]
        drive.io.set_input(pin, 1, rec.edge_ns)
        drive.io.set_input(pin, 0, rec.edge_ns + INPUT_PULSE_MS * MS)

    def _offset(self, node: int, plc_t: int) -> int:
        drive = self.drives.get(node)
        now = drive.clock_now_ns() if drive is not None else None
        return 0 if now is None else now - plc_t


def _write_steps(plc, plan: Plan, inhibit_100us: int = 0, budget_in=None) -> None:
    # every step carries the TxPDO2 inhibit time of the bus budget (linmot_st.jobs.motion.budget); SETUP uses it.
    # With budget_in, each step its Load and the program the steps' capacity (FB_PlcMotion's bus admission)

    def load(kind):
        if budget_in is None:
            return {"LOAD": 0, "BURST": 0}
        return {"LOAD": step_load(kind, budget_in, inhibit_100us), "BURST": step_burst(kind, budget_in)}
    values = [{**s.plc_value(), "INHIBIT100US": inhibit_100us, **load(s.kind)} for s in plan.steps]
    blank = {"KIND": "PLC_STEP_NONE", "POSITION": 0.0, "VELOCITY": 0.0, "ACCELERATION": 0.0, "CURVEID": 0,
             "ENTRY": 0, "INHIBIT100US": 0, "HOLD": 0, "AMPLITUDE": 0.0, "FREQUENCY": 0.0, "LOAD": 0,
             "BURST": 0, "BACK": 0.0, "COUNT": 0}
    plc[f"{INSTANCE}.STEPS"] = values + [blank] * (MAX_STEPS - len(values))
    plc[f"{INSTANCE}.NSTEPS"] = len(values)
    plc[f"{INSTANCE}.STEPBUDGET"] = admission_capacity(budget_in) if budget_in is not None else 0


def motion_phase(plan: Plan, timeout_s: float, progress=None, inhibit_100us: int = 0, toggle_inputs: bool = True,
                 budget_in=None):
    """The `after` hook of the commissioning runner: runs the steps on every commissioned axis, with this TxPDO2
    inhibit time (the bus budget's, linmot_st.jobs.motion.budget); `budget_in` (BudgetInputs): the steps start as the
    bus has room for them (FB_PlcMotion's admission; None: each as soon as the axis is ready)."""

    def after(plc, sim, drives) -> MotionResult:
        nodes = list(drives) or list(range(1, plc[f"{INSTANCE}.AXES"] + 1))
        _write_steps(plc, plan, inhibit_100us, budget_in)
        plc[f"{INSTANCE}.RUNMOTION"] = True
        sampler = MotionSampler(plc, nodes, plan, progress, drives, toggle_inputs)
        result = MotionResult(plan, sampler.axes, plc.time_ns)
        for n, d in drives.items():
            now = d.clock_now_ns()
            if now is not None:
                # real time: the PLC's clock and each drive's clock count from different starts (the plot's
                # time axis; the checks use each step's own readings, StepRecord.off0_ns / off1_ns)
                result.clock_offsets[n] = now - plc.time_ns
                result.clock_margin_ns = 5 * plc.tick_ns
        ram0 = {n: {u: p.ram for u, p in d.params.by_upid.items()} for n, d in drives.items()
                if hasattr(d, "params")}
        ct0 = {n: dict(d.ct.ram) for n, d in drives.items() if hasattr(d, "ct")}
        wall0 = time.perf_counter()
        try:
            sim.run_until(sampler, max_scans=int(timeout_s * 1e9 // plc.tick_ns))
        except CoSimTimeout:
            result.timed_out = True
        result.wall_s = time.perf_counter() - wall0
        result.t1_ns, result.scans = plc.time_ns, sampler.scans
        result.inhibit_100us = inhibit_100us
        for n, before in ram0.items():
            params = drives[n].params.by_upid
            changed = {u: (v, params[u].ram) for u, v in before.items() if params[u].ram != v}
            if changed:
                result.ram_changed[n] = changed
        for n, before in ct0.items():
            now = drives[n].ct.ram
            changed = {k: (before.get(k), now.get(k)) for k in set(before) | set(now) if before.get(k) != now.get(k)}
            if changed:
                result.ct_changed[n] = changed
        bus = getattr(sim, "bus", None)
        if getattr(bus, "trace", None) is not None and hasattr(bus, "bit_ns"):
            # from the end of the last axis' PDO setup: its SDO exchanges precede the process data
            ends = [r.t1_ns for ax in sampler.axes for r in ax.steps if r.kind == "setup" and r.t1_ns]
            result.bus_load = measured_load(bus.trace, bus.bit_ns, max(ends, default=result.t0_ns), result.t1_ns)
        for ax in sampler.axes:
            mot = f"{INSTANCE}.A{ax.axis}.MOT"      # three members, not the whole FB read into a dict
            ax.error_id, ax.drive_error, ax.fail_step = plc[f"{mot}.ERRORID"], plc[f"{mot}.DRIVEERROR"], plc[f"{mot}.FAILSTEP"]
            if ax.error and ax.steps:
                ax.steps[-1].ok = False
                ax.steps[-1].error_id, ax.steps[-1].drive_error = ax.error_id, ax.drive_error
        return result

    return after


@contextmanager
def as_commissioned(result: RunResult):
    """While inside, the emulated drives' RAM holds what the commissioning left there: the commissioning's
    memory check is of the commissioning, not of the parameters and command-table entries the motion steps wrote
    since (their lists: MotionResult.ram_changed, printed by the job, and MotionResult.ct_changed)."""
    m = result.after
    changed = m.ram_changed if m is not None else {}
    entries = m.ct_changed if m is not None else {}

    def put(side: int) -> None:
        # side 0: the RAM as commissioning left it; 1: as the motion job left it (None: an entry not there)
        for n, ps in changed.items():
            for u, values in ps.items():
                result.drives[n].params.by_upid[u].ram = values[side]
        for n, es in entries.items():
            table = result.drives[n].ct.ram
            for k, blocks in es.items():
                if blocks[side] is None:
                    table.pop(k, None)
                else:
                    table[k] = blocks[side]
    put(0)
    try:
        yield
    finally:
        put(1)


def placed_drives(stroke, opts: RunOptions, datasets=None, trigger_mode: int | None = None,
                  encoder_source: int | None = None):
    """A drive factory: the runner's emulated drive (of the series of its node's file, `datasets`) with the
    mechanics `stroke` places; `trigger_mode`: the
    trigger input's mode 170Ch stored in the drive as the machine was set up (the rig wires X4.6 for the
    trigger step; a PVL that sets 170Ch is written over it by the commissioning); `encoder_source`: 172Ah, the
    master encoder wired (the conveyor of the cam steps), stored the same way."""

    def factory(node: int):
        drive = emulated_drive(node, opts, datasets, motion=stroke.settings())
        stroke.store_home(drive)
        for upid, value in ((P_TRIGGER_MODE, trigger_mode), (P_MASTER_ENCODER_SOURCE, encoder_source)):
            if value is not None and upid in drive.params.by_upid:      # (a B1100 has neither)
                # stored (ROM) before the drive is switched on: its firmware start loads it into RAM
                drive.params.write(upid, value, ram=False, rom=True)
                drive.params.by_upid[upid].ram = value
        return drive
    return factory


def job_drives(plan: Plan, opts: RunOptions, datasets=None):
    """The drive factory of the job: the emulated drives with the mechanics the plan's stroke places, the trigger
    input wired when a step needs it, the master encoder when a cam step runs."""
    triggered = any(s.kind == "trigger" for s in plan.steps)
    cams = any(s.kind == "cam" for s in plan.steps)
    return placed_drives(plan.stroke, opts, datasets, TRIGGER_MODE_DIRECT if triggered else None,
                         ENCODER_SOURCE_X10 if cams else None)


def run_job(pvl, opts: RunOptions, build_result, plan: Plan, *, dataset=None, progress=None,
            motion_progress=None, timeout_s: float = 60.0, inhibit_100us: int = 0, toggle_inputs: bool = True,
            share_percent: float = 70.0, **kw) -> RunResult:
    """Commission, then move: the commissioning RunResult with the MotionResult in .after (None when the
    commissioning failed). The emulated drives get the mechanics plan.stroke placed (unless the caller passes
    its own drive_factory); a plan that cannot fit is refused (ValueError) before anything runs. The steps are
    admitted to the bus within `share_percent` of its bit rate (linmot_st.jobs.motion.budget.admission_capacity)."""

    if plan.refusals:
        raise ValueError("the motion plan does not fit the axis: " + "; ".join(plan.refusals))
    if plan.stroke is not None and kw.get("drive_factory") is None:
        kw["drive_factory"] = job_drives(plan, opts, kw.get("datasets"))
    return run(pvl, opts, build_result, dataset=dataset, progress=progress,
               after=motion_phase(plan, timeout_s, motion_progress, inhibit_100us, toggle_inputs,
                                  job_inputs(opts.axes, opts.bitrate, share_percent)), **kw)
