"""Encoder cams on the emulated E1100 ([MC] 4.3.63..68, 4.3.150..162, 5.5): the cam definitions, the setpoint
generator that follows the master encoder, and the handlers of the ENCODER_CAM and TRIGGERED_CAM kinds.

A cam maps the master-encoder counter to a demand position: cam y covers `length` counts from its start count,
N curve setpoints equally spaced over them, linear between (as a time curve over its time, [CFG] 5.3),
position = offset + amplitude x setpoint. The generator is a pure function of the counter, so the demand follows
the master at any speed, forwards and backwards, and the MC's quiet cycles (fast_path.py) run it like any plan.

Cam mode 1527h ([MC] 5.5): 0 infinite length (a cam runs once from its start count; triggered cams), 1 modulo
cam length (the counter taken modulo the cam length 1529h, or counts/revolution 1291h when 0: repeated cams).
Between cams, the demand rests at the end of the cam whose start the counter passed last (INFERRED). The cam
definitions are RAM: an MC start or stop clears them (control.py, INFERRED).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ....protocol import commands as C
from ....protocol import words as W
from ....protocol.commands import CommandDef
from ....protocol.upids import (
    P_CAM_MODE,
    P_CAM_MODULO_LENGTH,
    P_CURVE_AMPLITUDE,
    P_CURVE_OFFSET,
    P_QUICK_STOP_DEC,
    P_TRIG_CAM_CURVE_FALL,
    P_TRIG_CAM_CURVE_RISE,
    P_TRIG_CAM_DELAY_FALL,
    P_TRIG_CAM_DELAY_RISE,
)
from .setpoints import StopPlan, _demands_by_at
from .units import ACC_RAW

CAM_OBJECT_TYPE = 0x0103        # seed 000 5.2: position over master-encoder increments
MODULO = 1                      # 1527h: modulo cam length (INFERRED value; 0 = infinite length)
NEVER = 1 << 62


@dataclass
class Cam:
    """One defined cam: the curve's setpoints over `length` counts from `start`, offset + amplitude x y.
    `changes` are 1y8xh's (first cycle, amplitude, length), taking effect at a later cam start."""
    y: list[float]
    start: int
    length: int
    offset: float
    amplitude: float
    changes: list[tuple[int, float, int]] = field(default_factory=list)

    def scaled(self, cycle: int) -> tuple[float, int]:
        amp, length = self.amplitude, self.length
        for first, a, n in self.changes:
            if cycle >= first:
                amp, length = a, n
        return amp, length

    def value(self, rel: float, amp: float, length: int) -> tuple[float, float]:
        """Position and d(position)/d(count) at `rel` counts into the cam (clamped to it)."""
        n = len(self.y) - 1
        x = min(max(rel, 0.0), float(length)) / length * n
        i = min(int(x), n - 1)
        y0, y1 = self.y[i], self.y[i + 1]
        slope = amp * (y1 - y0) * n / length if 0 <= rel < length else 0.0
        return self.offset + amp * (y0 + (x - i) * (y1 - y0)), slope


class EncoderCams:
    """The cam state of one MC: cams 1 and 2 and the triggered one, which are enabled, what a trigger arms."""

    def __init__(self, mc):
        self.mc = mc
        self.cams: dict[object, Cam] = {}
        self.enabled: dict[object, bool] = {1: False, 2: False}

    def modulo(self) -> int:
        """The modulo cam length, or 0 in infinite-length mode."""
        mc = self.mc
        if mc.par(P_CAM_MODE) != MODULO:
            return 0
        return mc.par(P_CAM_MODULO_LENGTH) or mc.encoder.counts_per_rev()

    def _cycle(self, cam: Cam, count: int, modulo: int) -> int:
        if modulo:
            return (count - cam.start) // modulo
        return 0 if count >= cam.start else -1

    def position(self, count: int) -> tuple[float, float] | None:
        """Demand position and its slope per count at the counter value `count` (None: no cam enabled)."""
        enabled = self.enabled
        active = [(k, c) for k, c in self.cams.items() if enabled.get(k)]
        if not active:
            return None
        modulo = self.modulo()
        best = None
        for k, cam in active:
            rel = (count - cam.start) % modulo if modulo and k != "trigger" else count - cam.start
            if rel >= 0 and (best is None or rel < best[0]):
                best = (rel, cam)
        if best is None:        # infinite length, before every cam: rest at the first one's start
            cam = min((c for _, c in active), key=lambda c: c.start)
            amp, length = cam.scaled(-1)
            return cam.value(0, amp, length)[0], 0.0
        rel, cam = best
        amp, length = cam.scaled(self._cycle(cam, count, modulo))
        return cam.value(rel, amp, length)


class CamFollower:
    """The setpoint generator while the cam operation is on: the demand is the cam's position at the master
    encoder's counter; its velocity the cam's slope times the counter's rate (the feedforward)."""

    kind = "cam"

    def __init__(self, origin_ns: int, cams: EncoderCams, hold: float):
        self.origin_ns = origin_ns
        self.cams, self.encoder = cams, cams.mc.encoder
        self.target = float(hold)       # where the demand rests while no cam is enabled
        self.end_ns = NEVER

    def at(self, t_ns: int) -> tuple[float, float, float]:
        count, rate = self.encoder.sample(t_ns)
        found = self.cams.position(count)
        if found is None:
            return self.target, 0.0, 0.0
        p, slope = found
        return p, slope * rate, 0.0

    def done(self, t_ns: int) -> bool:
        return False

    def demands(self, t_ns: int, step_ns: int):
        return _demands_by_at(self, t_ns, step_ns)


def cams_of(mc) -> EncoderCams:
    cams = getattr(mc, "_encoder_cams", None)
    if cams is None:
        cams = mc._encoder_cams = EncoderCams(mc)
    return cams


def cam_operating(mc) -> bool:
    return isinstance(mc.gen, CamFollower)


def _curve(mc, curve_id: int):
    c = mc.curves.ram.get(curve_id)
    return c if c is not None and c.object_type == CAM_OBJECT_TYPE else None


def _define(mc, c: CommandDef, f: dict, t: int, key) -> bool:
    """1y0xh..1y5xh: cam `key` from a curve, its start count and the row's scaling."""
    curve = _curve(mc, f["curve_id"])
    if curve is None:
        return mc._fail(W.ERR_CURVE_NOT_DEFINED, t)     # INFERRED: as a time curve that is not in RAM
    y = [float(v) for v in curve.setpoints]
    sub = c.cid & 0xF
    length = f.get("cam_length") or curve.x_length
    amp = mc.par(P_CURVE_AMPLITUDE, 1000) / 1000.0
    offset = float(mc.par(P_CURVE_OFFSET))
    here = mc.gen.at(t)[0]
    if "amplitude" in f:
        amp = f["amplitude"] / 1000.0
    if "start_pos" in f:                                # 1y3h: from the start position to the target
        here = f["start_pos"]
    if "target" in f:                                   # from here to the target (1y2h, 1y3h, 1y4h)
        if y[-1] == y[0]:
            return mc._fail(W.ERR_CURVE_AMP_SCALE, t)
        amp = (f["target"] - here) / (y[-1] - y[0])
    if sub == C.CAM_DEFINE_FROM_ACT_POS:
        here = mc.axis.position
    if sub in (C.CAM_DEFINE_FROM_ACT_POS, C.CAM_DEFINE_TO_POS, C.CAM_DEFINE_FROM_POS_TO_POS_IN_COUNTS,
               C.CAM_DEFINE_TO_POS_IN_COUNTS):
        offset = here - amp * y[0]                     # the motor stands at the cam's start ([MC] 4.3.155)
    if length <= 0 or not -20.0 <= amp <= 20.0:
        return mc._fail(W.ERR_CURVE_AMP_SCALE, t)
    cams_of(mc).cams[key] = Cam(y, f["start_count"], int(length), offset, amp)
    return True


def _cam_command(mc, c: CommandDef, f: dict, t: int) -> bool:
    """ENCODER_CAM: 100xh..104xh and the cam-y commands 1y0xh..1y8xh."""
    cams = cams_of(mc)
    cid = c.cid
    if cid == C.ENCODER_CAM_ENABLE:
        mc._start(CamFollower(t, cams, mc.gen.at(t)[0]))
        return True
    if cid == C.ENCODER_CAM_DISABLE:
        if cam_operating(mc):                           # INFERRED: a stop ramp with the quick-stop deceleration
            p, v, _ = mc.gen.at(t)
            mc._start(StopPlan(t, p, v, mc.par(P_QUICK_STOP_DEC, 5_000_000) * ACC_RAW))
        return True
    if cid == C.ENCODER_CAM_GO_TO_SYNC_POS:
        found = cams.position(mc.encoder.counts(t))
        if found is None:
            return True
        p, v, _ = mc.gen.at(t)
        mc._vai(t, p, v, found[0], *mc._predef())       # INFERRED: with the predefined VAI parameters
        return True
    if cid == C.ENCODER_CAM_SET_VALUE:
        mc.encoder.set_value(f["counter_value"], t)
        return True
    y, sub = (cid >> 4) & 0xF, cid & 0xF
    if sub == C.CAM_Y_ENABLE:
        cams.enabled[y] = True
    elif sub == C.CAM_Y_DISABLE:
        cams.enabled[y] = False
    elif sub == C.CAM_Y_CHANGE_AMPLITUDE_LENGTH:
        cam = cams.cams.get(y)
        if cam is None:
            return mc._fail(W.ERR_CURVE_NOT_DEFINED, t)
        first = cams._cycle(cam, mc.encoder.counts(t), cams.modulo()) + 1     # at the next cam start
        cam.changes.append((first, f["amplitude"] / 1000.0, f["cam_length"] or cam.length))
    else:
        return _define(mc, c, f, t, y)
    return True


_RISING = frozenset({C.TRIG_CAM_RISE, C.TRIG_CAM_RISE_TARGET_LENGTH, C.TRIG_CAM_RISE_AMPLITUDE_LENGTH})


def _triggered_cam(mc, c: CommandDef, f: dict, t: int) -> bool:
    """069xh..06Exh: "setup in the event handler to start a cam curve on the trigger event" ([MC] 4.3.63..68): the
    curve ID and delay go to 154Ah..154Dh's RAM values (06Exh's text names the rising-edge UPIDs: taken as a copy
    error, INFERRED 154Bh/154Dh), and the event handler runs the cam start on every matching edge until 008xh
    (events.py, [MC] 4.3.6)."""
    if _curve(mc, f["curve_id"]) is None:
        return mc._fail(W.ERR_CURVE_NOT_DEFINED, t)
    rising = c.cid in _RISING
    for upid, value in ((P_TRIG_CAM_CURVE_RISE if rising else P_TRIG_CAM_CURVE_FALL, f["curve_id"]),
                        (P_TRIG_CAM_DELAY_RISE if rising else P_TRIG_CAM_DELAY_FALL, f["delay"])):
        if upid in mc.params:
            mc.params[upid].ram = value
    fields = dict(f)
    mc.events.arm(rising, lambda tc: _start_triggered(mc, fields, mc.events.last_edge.get(rising, tc), tc))
    return True


def _start_triggered(mc, f: dict, t_edge: int, t: int) -> bool:
    """The armed edge came at t_edge (its action runs in the MC cycle at t): the cam starts `delay` counts after
    the counter at the edge, from the demand position then (INFERRED), running once over its length (the
    infinite cam length [MC] 5.5.1 asks for)."""
    curve = _curve(mc, f["curve_id"])
    if curve is None:
        return mc._fail(W.ERR_CURVE_NOT_DEFINED, t)
    cams = cams_of(mc)
    y = [float(v) for v in curve.setpoints]
    here = mc.gen.at(t)[0]
    amp = f.get("amplitude", mc.par(P_CURVE_AMPLITUDE, 1000)) / 1000.0
    if "target" in f and y[-1] != y[0]:
        amp = (f["target"] - here) / (y[-1] - y[0])
    length = f.get("cam_length") or curve.x_length
    if length <= 0 or not -20.0 <= amp <= 20.0:
        return mc._fail(W.ERR_CURVE_AMP_SCALE, t)
    cams.cams["trigger"] = Cam(y, mc.encoder.counts(t_edge) + f["delay"], int(length), here - amp * y[0], amp)
    cams.enabled["trigger"] = True
    if not cam_operating(mc):
        mc._start(CamFollower(t, cams, here))
    return True


HANDLERS = {C.Kind.ENCODER_CAM: _cam_command, C.Kind.TRIGGERED_CAM: _triggered_cam}
