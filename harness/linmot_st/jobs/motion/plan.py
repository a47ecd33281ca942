"""The steps of the motion job, from a PVL file: what plc_project's motion program (plc_project/motion.st)
runs on every commissioned axis, and what each step must achieve (docs/motion.md, "The motion job").

    set up the PDOs -> power -> home -> move to a position -> jog forward, jog back -> a velocity move, its
    stop -> a move armed on the trigger input -> a touch probe -> for each cam curve: follow it on the master
    encoder the job turns -> for each time curve: move to its start, run it -> start a command-table entry -> stop -> switch off

The expectations are computed here from the PVL file (the curves as written, the command table's targets),
not taken from the emulated drive.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

from linmot_st.protocol import commands as C
from linmot_st.protocol.upids import P_CURVE_AMPLITUDE, P_CURVE_OFFSET, P_CURVE_TIME_SCALE, P_SCALE_POS

from .stroke import Stroke, fit

CAM_OBJECT_TYPE = 0x0103        # position over master-encoder increments (seed 000 5.2)
MM = 10_000                     # 0.1 um per mm
MAX_STEPS = 24                  # T_PlcSteps
MOVE_VELOCITY = 500.0           # mm/s
MOVE_ACCELERATION = 5000.0      # mm/s^2 (and deceleration)
STOP_DECELERATION = 5000.0
POSITION_TOLERANCE_MM = 0.1     # the emulated drive's in-target window
CURVE_DEMAND_TOLERANCE_MM = 0.001
CURVE_ACTUAL_TOLERANCE_MM = 0.5
JOG_VELOCITY = 50.0             # mm/s
JOG_ACCELERATION = 1000.0       # mm/s^2 (and deceleration)
JOG_HOLD_MS = 300               # the jog input held this long
VELOCITY = 100.0                # mm/s, MC_MoveVelocity
VELOCITY_ACCELERATION = 5000.0  # a short ramp: FB_LmMoveVelocity reads 1BAEh by SDO every scan until InVelocity
VELOCITY_HOLD_MS = 200          # kept this long once InVelocity, then stopped
VELOCITY_TOLERANCE = 0.01       # the demand velocity reached: within 1 % of the command
TRIGGER_POSITION_MM = 60.0      # the move armed on the trigger goes there
INPUT_EDGE_DELAY_MS = 20        # the job raises X4.6 / X4.5 this long after the PLC armed (Armed), for 10 ms
INPUT_PULSE_MS = 10
CAPTURE_TOLERANCE_MM = 0.001    # the captured position against the trajectory at the edge (0.1 um: 1E62h's unit)
CAM_TURN_MS = 500              # the job turns the conveyor (master encoder) one cam length in this time
CAM_HOLD_MS = 600               # the PLC keeps the cam coupled this long after InSync (the turn starts 20 ms in)
CAM_DEMAND_TOLERANCE_MM = 0.001
STREAM_AMPLITUDE_MM = 10.0      # the PLC's sine: (1 - cos) over this stroke ...
STREAM_FREQUENCY_HZ = 2.5       # ... at this frequency ...
STREAM_HOLD_MS = 800            # ... for two periods, one PV setpoint per 2 ms SYNC (FB_LmStream 033xh: the
                                # configured period 14E6h, 2000 us, keeps the SYNC jitter out, [MC] 4.3.41)
STREAM_PERIOD_MS = 2            # the SYNC period (plc_project/commission.st's FB_LmSync)
STREAM_DEMAND_TOLERANCE_MM = 0.001   # the demand against the sine 1.5 periods late (Hermite between setpoints)
VELOCITY_SLACK_S = 0.1          # the span's margin for the PLC's handshakes and InVelocity's SDO reads
CT_LOOP_ENTRIES = 8             # the PLC's command-table program (plc_project/motion.st, CTWRITE) ...
CT_LOOP_FIRST_ENTRY = 200       # ... from the first entry at or above this with 8 entries no PVL file uses
CT_LOOP_OUT_MM = 30.0           # out to here and back ...
CT_LOOP_BACK_MM = 10.0
CT_LOOP_COUNT = 3               # ... this many times (IF Var1 < 3)
CT_LOOP_VELOCITY = 250.0        # mm/s
CT_LOOP_ACCELERATION = 5000.0   # mm/s^2 (and deceleration)

STEP_KINDS = {"setup": "PLC_STEP_SETUP", "power": "PLC_STEP_POWER", "home": "PLC_STEP_HOME",
              "move": "PLC_STEP_MOVE", "curve": "PLC_STEP_CURVE", "ct": "PLC_STEP_CT", "stop": "PLC_STEP_STOP",
              "off": "PLC_STEP_OFF", "jog": "PLC_STEP_JOG", "velocity": "PLC_STEP_VELOCITY",
              "trigger": "PLC_STEP_TRIGGER", "probe": "PLC_STEP_PROBE", "cam": "PLC_STEP_CAM",
              "stream": "PLC_STEP_STREAM", "ctwrite": "PLC_STEP_CTWRITE", "ctloop": "PLC_STEP_CT"}


@dataclass
class CurveRun:
    """A commissioned time curve as the drive runs it with its default parameters (040xh)."""
    curve_id: int
    name: str
    setpoints: list[int]
    duration_ns: int
    offset: float                   # pu
    amplitude: float                # factor

    def position(self, t_ns: int) -> float:
        """The curve as written at t_ns after its start (pu): N setpoints over the curve time, linear between."""
        y = self.setpoints
        if t_ns >= self.duration_ns:
            return self.offset + self.amplitude * y[-1]
        x = max(t_ns, 0) / self.duration_ns * (len(y) - 1)
        i = int(x)
        return self.offset + self.amplitude * (y[i] + (x - i) * (y[i + 1] - y[i]))


@dataclass
class CamRun:
    """A commissioned cam curve (object type 0103h) coupled relative to where the axis stands (1y1xh): the
    setpoints over `length` master counts from count 0, scaled by the curve amplitude parameter."""
    curve_id: int
    name: str
    setpoints: list[int]
    length: int                     # master-encoder counts
    amplitude: float                # factor

    def position(self, count: float, here: float) -> float:
        """The demand (pu) at `count` when the cam was coupled with the axis at `here` (the cam's start there)."""
        y = self.setpoints
        x = min(max(count, 0.0), self.length) / self.length * (len(y) - 1)
        i = min(int(x), len(y) - 2)
        return here + self.amplitude * (y[i] + (x - i) * (y[i + 1] - y[i]) - y[0])

    def reach_mm(self) -> tuple[float, float]:
        y = self.setpoints
        return (self.amplitude * (min(y) - y[0]) / MM, self.amplitude * (max(y) - y[0]) / MM)


@dataclass
class Step:
    kind: str
    label: str
    position_mm: float = 0.0
    velocity: float = 0.0
    acceleration: float = 0.0
    curve_id: int = 0
    entry: int = 0
    target_mm: float | None = None          # where the axis must be at the end of the step
    curve: CurveRun | None = None
    cam: CamRun | None = None
    chain: list[int] = field(default_factory=list)   # CT: the entries the sequence runs
    span_mm: tuple[float, float] | None = None       # the lowest and highest position the step visits
    hold_ms: int = 0                                 # jog, velocity: T_PlcStep.Hold
    reach_mm: tuple[float, float] | None = None      # jog, velocity: how far back / forward it may go from
                                                     # where the step starts (no target: a bound)
    amplitude_mm: float = 0.0                        # stream: the PLC's sine
    frequency_hz: float = 0.0
    back_mm: float = 0.0                             # ctwrite, ctloop: the inner end of the program's stroke
    count: int = 0                                   # ctwrite, ctloop: the strokes it counts

    def plc_value(self) -> dict:
        return {"KIND": STEP_KINDS[self.kind], "POSITION": self.position_mm, "VELOCITY": self.velocity,
                "ACCELERATION": self.acceleration, "CURVEID": self.curve_id, "ENTRY": self.entry,
                "HOLD": self.hold_ms * 1_000_000, "AMPLITUDE": self.amplitude_mm, "FREQUENCY": self.frequency_hz,
                "BACK": self.back_mm, "COUNT": self.count}


@dataclass
class Plan:
    steps: list[Step]
    not_run: list[str]                      # what the PVL holds that the job does not run, and why
    stroke: Stroke | None = None            # where the steps lie in the stroke; the emulated mechanics

    @property
    def refusals(self) -> list[str]:
        """Why the file cannot run on this axis (said before any motion; empty: it can)."""
        return self.stroke.refusals if self.stroke else []


def _param(pvl, upid: int, default: int) -> int:
    layer = pvl.layer(2)
    p = layer.get(upid) if layer is not None else None
    return default if p is None else p.signed_value


def _ct_chain(pvl, entry: int, scale_pos: int) -> tuple[list[int], list[int] | None]:
    """The entries a sequence from `entry` runs and the positions its absolute moves go to (pu), the last one
    last; None when the chain holds something else than absolute VAI moves and waits, or loops."""
    entries = {e.entry_id: e.block for e in pvl.command_table}
    chain, targets, k = [], [], entry
    while k != 0xFFFF:
        if k in chain or k not in entries or len(chain) > 32:
            return chain, None
        chain.append(k)
        b = entries[k]
        cid, params = C.command_id(b.motion_header), b.parameters
        if cid in (C.VAI_GO_TO_POS, C.PREDEF_VAI_GO_TO_POS):
            targets.append(struct.unpack_from("<i", params, 0)[0])
        elif cid == C.VAI16_GO_TO_POS:
            targets.append(struct.unpack_from("<h", params, 0)[0] * scale_pos)
        elif cid not in (C.NOP, C.WAIT_TIME, C.WAIT_MOTION_FINISHED, C.WAIT_IN_TARGET_POSITION):
            return chain, None
        k = b.linked_entry
    return chain, targets or None


def ct_loop_entry(pvl, others=()) -> int:
    """The first of CT_LOOP_ENTRIES consecutive command-table entries, from CT_LOOP_FIRST_ENTRY on, that no PVL
    file of the bus writes at commissioning (the PLC's program must not overwrite the file's entries)."""
    used = {e.entry_id for f in (pvl, *others) for e in f.command_table}
    base = CT_LOOP_FIRST_ENTRY
    while any(k in used for k in range(base, base + CT_LOOP_ENTRIES)):
        base += 1
    if base + CT_LOOP_ENTRIES > 256:
        raise ValueError(f"no {CT_LOOP_ENTRIES} free command-table entries from {CT_LOOP_FIRST_ENTRY} on")
    return base


def _same_curve(a, b) -> bool:
    return a.info_block == b.info_block and list(a.setpoints) == list(b.setpoints)


def _lacking(c, others) -> list:
    """The other nodes' PVL files that do not hold curve `c` as it is (per-node datasets)."""
    return [o for o in others if not any(oc.curve_id == c.curve_id and _same_curve(oc, c) for oc in o.curves)]


def plan(pvl, position_mm: float = 50.0, settings=None, others=(), fb_steps: bool = True,
         stream: bool = True) -> Plan:
    """The steps; `settings`: the emulated drives' MotionSettings whose stroke the plan is fitted into.
    `others`: the PVL files of other nodes on the bus (per-node datasets; every axis runs the same steps): a
    curve or command-table step only where each of them holds the same curve or command table (a B1100 file
    holds neither). `fb_steps` False: without the jog, velocity, trigger, probe and cam steps (the job as it was
    before them: their parameter writes and SDO reads start on every axis in the same scan, a burst the bus
    budget does not plan, docs/motion.md). `stream` False: without the PLC-streamed profile (it needs a PLC
    that keeps its 2 ms SYNC: not a Python PLC in real time on a python-can bus)."""
    steps = [Step("setup", "set up the PDOs (TxPDO1 event timer 50 ms)"), Step("power", "power (MC_Power)"),
             Step("home", "home (MC_Home)")]
    not_run: list[str] = []
    move = dict(velocity=MOVE_VELOCITY, acceleration=MOVE_ACCELERATION)
    steps.append(Step("move", f"move to {position_mm:g} mm", position_mm=position_mm, target_mm=position_mm,
                      **move))
    b1100 = [f for f in (pvl, *others) if f.drive_type.name != "E1100"]
    if fb_steps and b1100:
        # the trigger, probe and cam rows of the catalogue are E1100 only (seed 004 4.2 has no B1100 mark for
        # them, [MC] 5.5: no cams on a B1100), and every axis runs the same steps
        fb_steps = False
        not_run.append("jog, velocity, trigger, probe, stream, cam and command-table loop steps: not on every axis "
                       "(a B1100 node: "
                       f"{', '.join(f.filename or 'PVL' for f in b1100)})")
    steps += _jog_and_velocity() if fb_steps else []
    if fb_steps and not stream:
        steps = [s for s in steps if s.kind != "stream"]
        not_run.append("the PLC-streamed profile: the PLC runs in real time on this bus, its scans too late for a "
                       f"{STREAM_PERIOD_MS} ms SYNC stream (the drive's 1.5-period margin)")
    offset = _param(pvl, P_CURVE_OFFSET, 0)
    time_scale = _param(pvl, P_CURVE_TIME_SCALE, 10000)
    amplitude = _param(pvl, P_CURVE_AMPLITUDE, 1000) / 1000.0
    for c in pvl.curves:
        info = c.info
        if _lacking(c, others):
            not_run.append(f"curve {c.curve_id} {info.name}: not on every axis (per-node PVL files: "
                           f"{', '.join(o.filename or 'PVL' for o in _lacking(c, others))})")
        elif info.object_type == CAM_OBJECT_TYPE and not fb_steps:
            not_run.append(f"curve {c.curve_id} {info.name}: a cam profile (object type 0103h): the cam steps are off")
        elif info.object_type == CAM_OBJECT_TYPE:
            cam = CamRun(c.curve_id, info.name, list(c.setpoints), info.x_length, amplitude)
            steps.append(Step("cam", f"follow cam {c.curve_id} {info.name} on the master encoder (MC_CamIn)",
                              curve_id=c.curve_id, hold_ms=CAM_HOLD_MS, cam=cam, reach_mm=cam.reach_mm()))
    for c in pvl.curves:
        info = c.info
        if info.object_type == CAM_OBJECT_TYPE or _lacking(c, others):
            continue
        if info.object_type != 0x0003:
            not_run.append(f"curve {c.curve_id} {info.name}: object type {info.object_type:04X}h is neither a "
                           "time curve nor a cam")
            continue
        run = CurveRun(c.curve_id, info.name, list(c.setpoints), info.x_length * 10_000 * time_scale // 10000,
                       offset, amplitude)
        start, end = run.position(0) / MM, run.position(run.duration_ns) / MM
        steps.append(Step("move", f"move to the start of curve {c.curve_id} ({start:g} mm)", position_mm=start,
                          target_mm=start, **move))
        # linear between setpoints: the extremes are setpoints
        ends = [run.offset + run.amplitude * y for y in (min(run.setpoints), max(run.setpoints))]
        steps.append(Step("curve", f"run curve {c.curve_id} {info.name} (040xh)", curve_id=c.curve_id,
                          target_mm=end, curve=run, span_mm=(min(ends) / MM, max(ends) / MM)))
    scale_pos = _param(pvl, P_SCALE_POS, 1000)
    table = {e.entry_id: e.data for e in pvl.command_table}
    if pvl.command_table and any({e.entry_id: e.data for e in o.command_table} != table for o in others):
        not_run.append("command table: not the same on every axis (per-node PVL files)")
        table = {}
    for e in sorted(pvl.command_table if table else (), key=lambda e: e.entry_id):
        chain, targets = _ct_chain(pvl, e.entry_id, scale_pos)
        if targets is not None:
            steps.append(Step("ct", f"start command-table entry {e.entry_id} {e.block.name} "
                                    f"(runs {', '.join(map(str, chain))})", entry=e.entry_id,
                              target_mm=targets[-1] / MM, chain=chain,
                              span_mm=(min(targets) / MM, max(targets) / MM)))
            break
    else:
        if table:
            not_run.append("command table: no entry whose sequence is absolute VAI moves and waits only")
    if fb_steps:
        entry = ct_loop_entry(pvl, others)
        # the PLC writes its program (SDO, CTWRITE), then starts it as any command-table entry (200xh, CT)
        loop = dict(entry=entry, position_mm=CT_LOOP_OUT_MM, back_mm=CT_LOOP_BACK_MM, count=CT_LOOP_COUNT,
                    velocity=CT_LOOP_VELOCITY, acceleration=CT_LOOP_ACCELERATION)
        steps += [Step("ctwrite", f"the PLC writes a command-table loop to entries {entry}..{entry + CT_LOOP_ENTRIES - 1}"
                                  f" (Var1, IF Var1 < {CT_LOOP_COUNT})", **loop),
                  Step("ctloop", f"start the PLC's loop (entry {entry}): {CT_LOOP_COUNT} x out to "
                                 f"{CT_LOOP_OUT_MM:g} mm and back to {CT_LOOP_BACK_MM:g} mm", target_mm=CT_LOOP_BACK_MM,
                       span_mm=(CT_LOOP_BACK_MM, CT_LOOP_OUT_MM), **loop)]
    steps += [Step("stop", "stop (MC_Stop)", acceleration=STOP_DECELERATION), Step("off", "switch off")]
    if len(steps) > MAX_STEPS:
        dropped = steps[MAX_STEPS - 2:-2]
        steps = steps[:MAX_STEPS - 2] + steps[-2:]
        not_run.append(f"{len(dropped)} step(s) beyond the {MAX_STEPS} plc_project holds: "
                       + "; ".join(s.label for s in dropped))
    _spans(steps)
    spans = [(k, s.label, *s.span_mm) for k, s in enumerate(steps, 1) if s.span_mm is not None]
    return Plan(steps, not_run, fit(pvl, spans, settings))


def _jog_and_velocity() -> list[Step]:
    """Jog forward, jog back (MC_Jog held JOG_HOLD_MS), a velocity move kept VELOCITY_HOLD_MS (MC_MoveVelocity)
    and the stop that ends it; each bounded by how far it can go: the hold at full speed plus the ramp down
    (the velocity move also its ramp up and the PLC's slack)."""
    jog = JOG_VELOCITY * JOG_HOLD_MS / 1000 + JOG_VELOCITY ** 2 / (2 * JOG_ACCELERATION)
    vel = (VELOCITY ** 2 / (2 * VELOCITY_ACCELERATION) + VELOCITY * (VELOCITY_HOLD_MS / 1000 + VELOCITY_SLACK_S)
           + VELOCITY ** 2 / (2 * STOP_DECELERATION))
    return [Step("jog", f"jog forward at {JOG_VELOCITY:g} mm/s for {JOG_HOLD_MS} ms (MC_Jog)",
                 velocity=JOG_VELOCITY, acceleration=JOG_ACCELERATION, hold_ms=JOG_HOLD_MS, reach_mm=(0.0, jog)),
            Step("jog", f"jog back at {JOG_VELOCITY:g} mm/s for {JOG_HOLD_MS} ms (MC_Jog)",
                 velocity=-JOG_VELOCITY, acceleration=JOG_ACCELERATION, hold_ms=JOG_HOLD_MS, reach_mm=(-jog, 0.0)),
            Step("velocity", f"move at {VELOCITY:g} mm/s for {VELOCITY_HOLD_MS} ms (MC_MoveVelocity)",
                 velocity=VELOCITY, acceleration=VELOCITY_ACCELERATION, hold_ms=VELOCITY_HOLD_MS,
                 reach_mm=(0.0, vel)),
            Step("stop", "stop the velocity move (MC_Stop)", acceleration=STOP_DECELERATION),
            # 02Axh: the target only (01Axh's 16 bytes do not fit the RxPDOs); at the velocity move's 14BEh..14C0h
            Step("trigger", f"move to {TRIGGER_POSITION_MM:g} mm on trigger X4.6 (02Axh), the job raises it",
                 position_mm=TRIGGER_POSITION_MM, target_mm=TRIGGER_POSITION_MM),
            Step("probe", "touch probe on X4.5 (MC_TouchProbe), the job pulses it"),
            # where the trigger step left the axis, the sine's base
            Step("stream", f"stream a {STREAM_AMPLITUDE_MM:g} mm sine at {STREAM_FREQUENCY_HZ:g} Hz computed by the "
                           f"PLC, one PV setpoint per {STREAM_PERIOD_MS} ms SYNC (FB_LmStream, 033xh)",
                 position_mm=TRIGGER_POSITION_MM, target_mm=TRIGGER_POSITION_MM, hold_ms=STREAM_HOLD_MS,
                 amplitude_mm=STREAM_AMPLITUDE_MM, frequency_hz=STREAM_FREQUENCY_HZ,
                 span_mm=(TRIGGER_POSITION_MM, TRIGGER_POSITION_MM + STREAM_AMPLITUDE_MM))]


def _spans(steps: list[Step]) -> None:
    """Each move's span: from where the previous step left the axis to its target (the first from its target:
    homing left the axis inside the stroke); a CT sequence from there over its targets; a jog or velocity move
    from where the axis may be (an interval: they have no target) over how far it may go."""
    here = None                     # (lowest, highest) where the axis may be
    for s in steps:
        if s.kind in ("move", "trigger", "stream", "ctloop") or (s.kind == "ct" and s.span_mm is not None):
            pts = [s.target_mm] + (list(here) if here is not None else []) + (list(s.span_mm) if s.span_mm else [])
            s.span_mm = (min(pts), max(pts))
        elif s.reach_mm is not None and here is not None:
            s.span_mm = (here[0] + s.reach_mm[0], here[1] + s.reach_mm[1])
            here = s.span_mm
        if s.target_mm is not None:
            here = (s.target_mm, s.target_mm)
