"""Did every axis do what the motion job asked? Each step checked against the emulated drive's trajectory
record and the bus trace, with the expectations of plan.py (the PVL as written):

- move, ct: at the end of the step the actual position is within POSITION_TOLERANCE_MM of the target;
- curve: from the moment the drive took the curve command (its record of executed commands; on the simulated
  bus that is the end of the command's RxPDO3, tests/jobs/motion/test_motion_job.py checks it) over the curve time, the demand position follows the curve as written within CURVE_DEMAND_TOLERANCE_MM and the actual
  position within CURVE_ACTUAL_TOLERANCE_MM (the following error);
- jog: over the step the demand velocity reached the jog velocity (within VELOCITY_TOLERANCE) in the jog's
  direction, the axis moved that way, and at the end it stands still (the jog input fell);
- velocity: over the step the demand velocity reached the command in its direction and it still runs at it at
  the end of the step (the velocity is kept until the next step, a stop);
- stop: at its end the demand velocity is 0;
- trigger: the axis did not move from the step's start to the edge the job raised on X4.6, then moved to the
  target (within POSITION_TOLERANCE_MM at the end);
- cam: from when the job started turning the master encoder until it stopped, the demand position is the cam
  as written at the encoder's counter (relative to where the axis stood, scaled by the curve amplitude) within
  CAM_DEMAND_TOLERANCE_MM;
- probe: the position the PLC read equals the actual position at the edge the job raised on X4.5 (within
  CAPTURE_TOLERANCE_MM);
- home: the drive is homed; power: Operation Enabled; off: switched off; setup: done.
"""

from __future__ import annotations

import math
import struct
from dataclasses import dataclass, field

from linmot_st.emulator.linmot.command_table import build_entry  # the entry layout (seeds table 10)
from linmot_st.protocol import commands as C
from linmot_st.protocol import words as W

from .plan import (
    CAM_DEMAND_TOLERANCE_MM,
    CAPTURE_TOLERANCE_MM,
    CURVE_ACTUAL_TOLERANCE_MM,
    CURVE_DEMAND_TOLERANCE_MM,
    MM,
    POSITION_TOLERANCE_MM,
    STREAM_DEMAND_TOLERANCE_MM,
    STREAM_PERIOD_MS,
    VELOCITY_TOLERANCE,
    Plan,
    Step,
)


@dataclass
class StepCheck:
    axis: int
    index: int
    kind: str
    ok: bool
    what: str                               # the check in words, with the figures
    reached_mm: float | None = None
    demand_dev_mm: float | None = None
    actual_dev_mm: float | None = None
    t_exec_ns: int | None = None            # curve: when the drive took the command


@dataclass
class MotionCheck:
    steps: list[StepCheck] = field(default_factory=list)

    @property
    def passed(self) -> bool:
        return bool(self.steps) and all(s.ok for s in self.steps)


def curve_start(drive, curve_id: int, t0_ns: int, t1_ns: int) -> int | None:
    """When the drive executed a 040xh command for `curve_id` in [t0, t1] (the drive's clock)."""
    for t, header, params in drive.mc.executed:
        if t0_ns <= t <= t1_ns and C.command_id(header) == C.TIME_CURVE \
                and struct.unpack_from("<H", params)[0] == curve_id:
            return t
    return None


def check_motion(result, plan: Plan, drives: dict) -> MotionCheck:
    """In a real-time run each drive has its own clock: a step's end is mapped to it by the reading taken right
    after the scan that saw it (StepRecord.off1_ns), and a state is checked anywhere within
    result.clock_margin_ns of it."""
    out = MotionCheck()
    margin = result.clock_margin_ns
    for ax in result.axes:
        drive = drives.get(ax.node_id)
        if ax.error or not ax.done:
            out.steps.append(StepCheck(ax.axis, ax.fail_step, "job", False,
                                       f"the motion program stopped at step {ax.fail_step}"
                                       if ax.error else "the motion program did not finish"))
        for rec in ax.steps:
            step = plan.steps[rec.index - 1]
            if drive is None:                     # a real drive: only what the PLC saw
                out.steps.append(StepCheck(ax.axis, rec.index, rec.kind, rec.ok, "done by the PLC"))
                continue
            traj = drive.mc.trajectory
            off = rec.off1_ns
            end = traj.at(rec.t1_ns + off)
            around = [end] + traj.between(rec.t1_ns + off - margin, rec.t1_ns + off + margin) if margin else [end]
            if step.kind == "cam" and not rec.edge_ns and not rec.error_id:
                out.steps.append(StepCheck(ax.axis, rec.index, "cam", False, "the master encoder never turned: "
                                           "the job started no conveyor (the cam never came in sync?)"))
                continue
            if step.kind in ("trigger", "probe") and not rec.edge_ns and not rec.error_id:
                pin = "X4.6" if step.kind == "trigger" else "X4.5"
                out.steps.append(StepCheck(ax.axis, rec.index, step.kind, False,
                                           f"no edge on {pin}: the job never raised the input, the armed "
                                           f"{'move' if step.kind == 'trigger' else 'capture'} waited "
                                           f"(at {end.actual / MM:.3f} mm)", reached_mm=end.actual / MM))
                continue
            if not rec.ok:
                out.steps.append(StepCheck(ax.axis, rec.index, rec.kind, False, f"failed: ErrorID 16#{rec.error_id:04X}"
                                           + (f", drive error {rec.drive_error:04X}h" if rec.drive_error else "")))
                continue
            if step.kind in ("move", "ct"):
                reached = end.actual / MM
                ok = abs(reached - step.target_mm) <= POSITION_TOLERANCE_MM
                out.steps.append(StepCheck(ax.axis, rec.index, step.kind, ok,
                                           f"at {reached:.3f} mm, target {step.target_mm:g} mm "
                                           f"(tolerance {POSITION_TOLERANCE_MM} mm)", reached_mm=reached))
            elif step.kind == "curve":
                out.steps.append(_check_curve(ax, rec, step, drive))
            elif step.kind == "cam":
                out.steps.append(_check_cam(ax, rec, step, drive))
            elif step.kind == "stream":
                out.steps.append(_check_stream(ax, rec, step, drive))
            elif step.kind == "ctwrite":
                out.steps.append(_check_ct_write(ax, rec, step, drive))
            elif step.kind == "ctloop":
                out.steps.append(_check_ct_loop(ax, rec, step, drive, end))
            elif step.kind == "trigger":
                out.steps.append(_check_trigger(ax, rec, step, traj, end))
            elif step.kind == "probe":
                at = traj.at(rec.edge_ns).actual / MM
                got = rec.probed_mm
                ok = got is not None and abs(got - at) <= CAPTURE_TOLERANCE_MM
                out.steps.append(StepCheck(ax.axis, rec.index, "probe", ok,
                                           f"captured {got if got is None else f'{got:.4f}'} mm, actual position at "
                                           f"the edge {at:.4f} mm (tolerance {CAPTURE_TOLERANCE_MM} mm)",
                                           reached_mm=got))
            elif step.kind in ("jog", "velocity"):
                out.steps.append(_check_velocity(ax, rec, step, traj, end))
            elif step.kind == "stop":
                s = next((s for s in around if s.demand_velocity == 0), end)
                out.steps.append(StepCheck(ax.axis, rec.index, "stop", s.demand_velocity == 0,
                                           f"demand velocity {s.demand_velocity / MM:g} mm/s at the end"))
            elif step.kind == "home":
                ok = any(s.status_word & W.SW_HOMED for s in around)
                out.steps.append(StepCheck(ax.axis, rec.index, "home", ok, "homed" if ok else "not homed"))
            elif step.kind == "power":
                s = next((s for s in around if s.state >= 8), end)
                out.steps.append(StepCheck(ax.axis, rec.index, "power", s.state >= 8, f"state {s.state}"))
            elif step.kind == "off":
                s = next((s for s in around if s.state < 8), end)
                out.steps.append(StepCheck(ax.axis, rec.index, "off", s.state < 8, f"state {s.state}"))
            else:
                out.steps.append(StepCheck(ax.axis, rec.index, step.kind, True, "done"))
    return out


def _check_curve(ax, rec, step, drive) -> StepCheck:
    run = step.curve
    t_exec = curve_start(drive, step.curve_id, rec.t0_ns + rec.off0_ns - 5_000_000,
                         rec.t1_ns + rec.off1_ns + 5_000_000)
    if t_exec is None:
        return StepCheck(ax.axis, rec.index, "curve", False, "the drive executed no 040xh command for this curve")
    samples = drive.mc.trajectory.between(t_exec, t_exec + run.duration_ns)
    if not samples:
        return StepCheck(ax.axis, rec.index, "curve", False, "no trajectory samples over the curve time")
    dem = max(abs(s.demand - run.position(s.t_ns - t_exec)) for s in samples) / MM
    act = max(abs(s.actual - run.position(s.t_ns - t_exec)) for s in samples) / MM
    ok = dem <= CURVE_DEMAND_TOLERANCE_MM and act <= CURVE_ACTUAL_TOLERANCE_MM
    return StepCheck(ax.axis, rec.index, "curve", ok,
                     f"demand within {dem:.4f} mm of the curve as written (tolerance {CURVE_DEMAND_TOLERANCE_MM}), "
                     f"actual within {act:.3f} mm (tolerance {CURVE_ACTUAL_TOLERANCE_MM}), {len(samples)} samples",
                     demand_dev_mm=dem, actual_dev_mm=act, t_exec_ns=t_exec - rec.off0_ns)


def _check_velocity(ax, rec, step, traj, end) -> StepCheck:
    """A jog or a velocity move: the peak demand velocity in the step's direction against the command; the
    distance moved; a jog stands still at its end, a velocity move still runs at the command."""
    samples = traj.between(rec.t0_ns + rec.off0_ns, rec.t1_ns + rec.off1_ns)
    if not samples:
        return StepCheck(ax.axis, rec.index, step.kind, False, "no trajectory samples over the step")
    sign = 1 if step.velocity > 0 else -1
    want = abs(step.velocity)
    peak = max(sign * s.demand_velocity for s in samples) / MM
    moved = sign * (end.actual - samples[0].actual) / MM
    reached = abs(peak - want) <= VELOCITY_TOLERANCE * want
    if step.kind == "jog":
        ended = end.demand_velocity == 0
        ok = reached and moved > 0 and ended
        tail = "at standstill at the end" if ended else f"still at {end.demand_velocity / MM:g} mm/s at the end"
    else:
        ended = abs(sign * end.demand_velocity / MM - want) <= VELOCITY_TOLERANCE * want
        ok = reached and moved > 0 and ended
        tail = f"{'still' if ended else 'no longer'} at it at the end ({end.demand_velocity / MM:g} mm/s)"
    direction = "forward" if sign > 0 else "back"
    return StepCheck(ax.axis, rec.index, step.kind, ok,
                     f"peak demand velocity {peak:.2f} mm/s {direction} (command {want:g}, tolerance "
                     f"{VELOCITY_TOLERANCE:.0%}), moved {moved:+.3f} mm {direction}, {tail}", reached_mm=end.actual / MM)


def _check_trigger(ax, rec, step, traj, end) -> StepCheck:
    """Still until the edge (no demand velocity between the step's start and the edge), then at the target."""
    before = traj.between(rec.t0_ns + rec.off0_ns, rec.edge_ns)
    early = next((s for s in before if s.demand_velocity != 0), None)
    reached = end.actual / MM
    at = abs(reached - step.target_mm) <= POSITION_TOLERANCE_MM
    ok = early is None and at
    first = ("moved before the edge (demand velocity "
             f"{early.demand_velocity / MM:g} mm/s {(rec.edge_ns - early.t_ns) / 1e6:.1f} ms before it)"
             if early is not None else "still until the edge on X4.6")
    return StepCheck(ax.axis, rec.index, "trigger", ok,
                     f"{first}, then at {reached:.3f} mm, target {step.target_mm:g} mm "
                     f"(tolerance {POSITION_TOLERANCE_MM} mm)", reached_mm=reached)


def _check_cam(ax, rec, step, drive) -> StepCheck:
    """The demand against the cam as written at the recorded master-encoder counter while the conveyor turned."""
    cam, traj = step.cam, drive.mc.trajectory
    here = traj.at(rec.edge_ns).demand
    samples = traj.between(rec.edge_ns, rec.edge_end_ns)
    if not samples:
        return StepCheck(ax.axis, rec.index, "cam", False, "no trajectory samples while the conveyor turned")
    counts = traj.master_counts if hasattr(traj, "master_counts") else drive.mc.encoder.counts
    dev = max(abs(s.demand - cam.position(counts(s.t_ns), here)) for s in samples) / MM
    top = max(abs(s.demand - here) for s in samples) / MM
    ok = dev <= CAM_DEMAND_TOLERANCE_MM
    return StepCheck(ax.axis, rec.index, "cam", ok,
                     f"demand within {dev:.4f} mm of the cam as written at the master count (tolerance "
                     f"{CAM_DEMAND_TOLERANCE_MM}), up to {top:.3f} mm from where it coupled, {len(samples)} samples",
                     demand_dev_mm=dev)


def stream_position(step: Step, tau_ns: int) -> float:
    """The PLC's sine (plc_project/motion.st, STREAM) at its time tau, in 0.1 um: (1 - cos) from the base."""
    tau = min(max(tau_ns, 0), step.hold_ms * 1_000_000) * 1e-9
    w = 2 * math.pi * step.frequency_hz
    return step.position_mm * MM + step.amplitude_mm * MM * (1 - math.cos(w * tau)) / 2


def _check_stream(ax, rec, step: Step, drive) -> StepCheck:
    """The demand against the PLC's sine 1.5 SYNC periods late ([MC] 5.4; docs/emulator.md 13.4): the sine's time
    zero is the first setpoint's stamp less the sine time the PLC gave that setpoint (a whole number of periods:
    the SYNCs between the start and the first setpoint sent, taken from the setpoint's own position)."""
    period = STREAM_PERIOD_MS * 1_000_000
    t0, t1 = rec.t0_ns + rec.off0_ns, rec.t1_ns + rec.off1_ns
    sent = [(t, struct.unpack_from("<i", p)[0]) for t, h, p in drive.mc.executed
            if t0 <= t <= t1 and C.command_id(h) == 0x033]
    if len(sent) < 2:
        return StepCheck(ax.axis, rec.index, "stream", False, f"{len(sent)} stream setpoint(s) executed")
    t_first, p_first = sent[0]
    k0 = min(range(8), key=lambda k: abs(stream_position(step, k * period) - p_first))
    zero = t_first + period * 3 // 2 - k0 * period            # when the sine's time zero plays
    # the MC cycles' samples: the trajectory also records one at each command's reception (a SYNC between two
    # cycles), whose demand is still the last cycle's
    stamps = {t for t, _ in sent}
    samples = [s for s in drive.mc.trajectory.between(t_first + period * 3 // 2, sent[-1][0] + period * 3 // 2)
               if s.t_ns not in stamps]
    dem = max(abs(s.demand - stream_position(step, s.t_ns - zero)) for s in samples) / MM
    ok = dem <= STREAM_DEMAND_TOLERANCE_MM and drive.mc.error_code == 0
    return StepCheck(ax.axis, rec.index, "stream", ok,
                     f"{len(sent)} setpoints; the demand within {dem:.4f} mm of the PLC's sine 1.5 periods late "
                     f"(tolerance {STREAM_DEMAND_TOLERANCE_MM} mm), {len(samples)} samples", demand_dev_mm=dem,
                     t_exec_ns=zero - rec.off0_ns)


def ct_loop_strokes(samples, out_pu: int, back_pu: int) -> int:
    """How often the demand reached the outer end coming from the inner one (within 0.1 um)."""
    n, out = 0, False
    for smp in samples:
        if not out and smp.demand >= out_pu - 1:
            n, out = n + 1, True
        elif out and smp.demand <= back_pu + 1:
            out = False
    return n


def ct_loop_program(step: Step) -> dict[int, bytes]:
    """The entries the PLC's CTWRITE step writes (plc_project/motion.st), as the catalogue encodes them."""

    base, vad = step.entry, dict(vmax=round(step.velocity * 1000), acc=round(step.acceleration * 100),
                                 dec=round(step.acceleration * 100))
    rows = [(C.SET_CT_VAR1, dict(value=0)), (C.VAI_GO_TO_POS, dict(target=round(step.position_mm * MM), **vad)),
            (C.WAIT_MOTION_FINISHED, {}), (C.VAI_GO_TO_POS, dict(target=round(step.back_mm * MM), **vad)),
            (C.WAIT_MOTION_FINISHED, {}), (C.ADD_CT_VAR1, dict(value=1)),
            (C.IF_VAR1_LESS, dict(value=step.count, if_true=base + 1, if_false=base + 7)), (C.WAIT_MOTION_FINISHED, {})]
    return {base + k: build_entry(cid << 4, C.encode(cid, 0, **f)[2:], name="PLC loop",
                                  link=0xFFFF if k >= 6 else base + k + 1)
            for k, (cid, f) in enumerate(rows)}


def _check_ct_write(ax, rec, step: Step, drive) -> StepCheck:
    """The PLC's program on the drive (RAM), entry by entry as the catalogue encodes it."""
    want, have = ct_loop_program(step), drive.ct.ram
    bad = [k for k, block in want.items() if have.get(k) != block]
    return StepCheck(ax.axis, rec.index, "ctwrite", not bad,
                     f"entries {min(want)}..{max(want)} on the drive as the catalogue encodes the program"
                     if not bad else f"entries {bad} differ from the program as the catalogue encodes it")


def _check_ct_loop(ax, rec, step: Step, drive, end) -> StepCheck:
    """The PLC's command-table program run: the stroke as often as it counts on the trajectory, the axis back at
    the inner end."""
    n = step.count
    out_pu, back_pu = round(step.position_mm * MM), round(step.back_mm * MM)
    t0, t1 = rec.t0_ns + rec.off0_ns, rec.t1_ns + rec.off1_ns
    strokes = ct_loop_strokes(drive.mc.trajectory.between(t0, t1), out_pu, back_pu)
    reached = end.actual / MM
    ok = strokes == n and abs(reached - step.back_mm) <= POSITION_TOLERANCE_MM
    return StepCheck(ax.axis, rec.index, "ctloop", ok,
                     f"{strokes} stroke(s) out to {step.position_mm:g} mm (the program counts {n}), at {reached:.3f} "
                     f"mm, target {step.back_mm:g} mm (tolerance {POSITION_TOLERANCE_MM} mm)", reached_mm=reached)
