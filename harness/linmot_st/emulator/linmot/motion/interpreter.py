"""The motion command interpreter of the MC software (seed 004 4.1, [MC] 4.3): a command from the interface or
a command-table entry is looked up in the protocol catalogue (linmot_st/protocol/commands/) and run by the
handler of its kind. A part of MotionControl (control.py).

A command of an existing kind needs only its catalogue row; a new kind needs one handler in HANDLERS. A
catalogued command whose kind has no handler here answers 0081h (unknown motion command), as the drive does
for a command it does not have.
"""

from __future__ import annotations

from collections.abc import Callable

from ....protocol import commands as C
from ....protocol import words as W
from ....protocol.commands import CommandDef, Kind, Start, Target
from ....protocol.upids import (
    P_CURVE_AMPLITUDE,
    P_CURVE_OFFSET,
    P_CURVE_TIME_SCALE,
    P_HOME_POSITION,
    P_PREDEF_ACC,
    P_PREDEF_DEC,
    P_PREDEF_VMAX,
    P_QUICK_STOP_DEC,
    P_SCALE_ACC,
    P_SCALE_POS,
    P_SCALE_VEL,
)
from . import ct_language
from . import vai_variants as VV
from .curve_modify import modify_curve
from .setpoints import CurvePlan, StopPlan, VaPlan
from .stream import stop_streaming, stream_setpoint
from .units import ACC_RAW, VEL_RAW

Handler = Callable[["Interpreter", CommandDef, dict, int], bool]     # (mc, row, field values, t) -> no error


class Interpreter:
    """execute() and the helpers the handlers share (a mixin of MotionControl)."""

    drive_type = C.E1100        # the drive series: a command whose row lacks it answers 0081h (B1100: b1100.py)

    def execute(self, header: int, params: bytes, t: int, from_table: bool = False) -> bool:
        """Run one motion command at t; False when it raised an error."""
        c, f = C.decode(header, params)
        self.executed.append((t, header, bytes(params[:16])))
        handler = HANDLERS.get(c.kind) if c is not None and self.drive_type in c.drives else None
        if handler is None:
            return self._fail(W.ERR_UNKNOWN_MOTION_CMD, t)
        if c.needs_homing and self.s.motion_requires_homing and not self.homed:
            return self._fail(W.ERR_NOT_HOMED, t)
        return handler(self, c, f, t)

    def _acc16(self) -> float:
        return self.par(P_SCALE_ACC, 10000) * ACC_RAW

    def _predef(self) -> tuple[float, float, float]:
        return (self.par(P_PREDEF_VMAX) * VEL_RAW, self.par(P_PREDEF_ACC) * ACC_RAW,
                self.par(P_PREDEF_DEC) * ACC_RAW)

    def _last_target(self) -> float:
        return self.last_vai[0] if self.last_vai else self.gen.target

    def _vai(self, t: int, p: float, v: float, target: float, vmax: float, acc: float, dec: float) -> None:
        self.last_vai = (float(target), vmax, acc, dec)
        self._start(VaPlan(t, p, v, target, vmax, acc, dec))

    def _write_live(self, upid: int, raw: int) -> None:
        """002xh: the RAM value of a live parameter, masked to its width (INFERRED: anything else is ignored)."""
        p = getattr(self.params, "store", self.params)     # the drive's own UPIDs (a B1100's: E1100View.store)
        if upid in p:
            d = p[upid].d
            if d.kind == "par" and d.live and d.access == "rw":
                value = d.type.from_raw(raw & 0xFFFFFFFF)
                if d.min <= value <= d.max:
                    p[upid].ram = value


# ---------------------------------------------------------------- the handlers, one per kind

def _nothing(mc, c: CommandDef, f: dict, t: int) -> bool:
    """NOP; a wait from the interface (waits act only inside a command-table sequence: ct_runner.py)."""
    return True


def _control_word(mc, c: CommandDef, f: dict, t: int) -> bool:
    mc.set_control_word(f["control_word"], t)
    return True


def _live_parameter(mc, c: CommandDef, f: dict, t: int) -> bool:
    mc._write_live(f["upid"], f["value"])
    return True


def _master_homing(mc, c: CommandDef, f: dict, t: int) -> bool:
    if P_HOME_POSITION in mc.params:
        mc.params[P_HOME_POSITION].ram = mc.params[P_HOME_POSITION].d.type.from_raw(f["home_position"])
    mc._reference(f["home_position"], t)
    return True


def _command_table(mc, c: CommandDef, f: dict, t: int) -> bool:
    return mc.ct_runner.start(f["entry"], t)


def _vai_values(mc, c: CommandDef, f: dict) -> tuple[float, float, float, float]:
    """Position (or increment), vmax, acc, dec of a VAI command in pu, pu/s, pu/s^2, by its kind's units."""
    if c.kind is Kind.VAI_16BIT:
        acc16 = mc._acc16()
        return (f["target"] * mc.par(P_SCALE_POS, 1000), f["vmax"] * mc.par(P_SCALE_VEL, 1000) * VEL_RAW,
                f["acc"] * acc16, f["dec"] * acc16)
    if c.kind is Kind.PREDEF_VAI:
        return (f["target"], *mc._predef())
    if c.kind in VV.UNITS:
        return VV.UNITS[c.kind](mc, f)
    return f["target"], f["vmax"] * VEL_RAW, f["acc"] * ACC_RAW, f["dec"] * ACC_RAW


def _stop_deceleration(mc, c: CommandDef, f: dict) -> float:
    if c.kind is Kind.VAI_16BIT:
        return f["dec"] * mc._acc16()
    if c.kind in VV.QUICK_STOP_KINDS:
        return mc.par(P_QUICK_STOP_DEC, 5_000_000) * ACC_RAW      # the quick-stop deceleration
    return f["dec"] * ACC_RAW


def _vai(mc, c: CommandDef, f: dict, t: int) -> bool:
    """Every VAI family: the row's start and target say where the motion starts and what the position field
    means (vai_variants.py: the families' units, infinite motion, transitions, the queue, max current)."""
    p, v, _ = mc.gen.at(t)
    if c.target is Target.STOP:
        mc._start(StopPlan(t, p, v, _stop_deceleration(mc, c, f)))
        if mc.s.stop_drops_pending:
            mc.pending.clear()
        return True
    if VV.no_position(mc, c, f, t, _vai_values):
        return True
    pos, vmax, acc, dec = _vai_values(mc, c, f)
    if c.start is Start.AFTER_ACTUAL_COMMAND:
        mc.pending.queue(pos, vmax, acc, dec)
        mc._wake(t)
        return True
    if "max_current" in f:
        VV.set_max_current(mc, f["max_current"])
    if c.start is Start.ACTUAL:
        p, v = mc.axis.position, mc.axis.velocity
    elif c.start is Start.ACTUAL_AT_REST:
        p, v = mc.axis.position, 0.0
    if c.target is Target.FROM_START:
        target = p + pos
    elif c.target is Target.FROM_LAST_TARGET:
        target = mc._last_target() + pos
    else:
        target = pos
    mc._vai(t, p, v, target, vmax, acc, dec)
    return True


def _time_curve(mc, c: CommandDef, f: dict, t: int) -> bool:
    """A time curve: what the command's fields leave out comes from the curve parameters (14D0h..14D2h); the
    row's target FROM_START puts the curve's offset at the demand position."""
    curve = mc.curves.ram.get(f["curve_id"])
    if curve is None or curve.object_type != 0x0003:
        # not in RAM; a cam (0103h) has no time axis: INFERRED the same error as an undefined curve
        return mc._fail(W.ERR_CURVE_NOT_DEFINED, t)
    y = curve.setpoints
    nominal_ns = curve.x_length * 10_000                  # x-length in 10 us
    offset = mc.par(P_CURVE_OFFSET)
    time_scale = mc.par(P_CURVE_TIME_SCALE, 10000)       # 0.01 %: stretches the time axis (INFERRED)
    amp = mc.par(P_CURVE_AMPLITUDE, 1000) / 1000.0        # 0.1 %
    duration = nominal_ns * time_scale // 10000
    if "offset" in f:
        offset = f["offset"]
    elif c.target is Target.FROM_START:
        offset = mc.gen.at(t)[0]
    if "target" in f:                                   # to a position: the amplitude that ends there
        if y[-1] == 0:
            return mc._fail(W.ERR_CURVE_AMP_SCALE, t)
        amp = (f["target"] - offset) / y[-1]
    if "amplitude" in f:
        amp = f["amplitude"] / 1000.0
    if "curve_time" in f:
        duration = f["curve_time"] * 10_000
    elif "time_scale" in f:
        duration = nominal_ns * f["time_scale"] // 10000
    if not -20.0 <= amp <= 20.0:                           # -2000 % .. 2000 %
        return mc._fail(W.ERR_CURVE_AMP_SCALE, t)
    mc._start(CurvePlan(t, curve.curve_id, y, max(duration, 0), offset, amp))
    return True


HANDLERS: dict[Kind, Handler] = {
    Kind.NOP: _nothing,
    Kind.WAIT: _nothing,
    Kind.CONTROL_WORD: _control_word,
    Kind.LIVE_PARAMETER: _live_parameter,
    Kind.MASTER_HOMING: _master_homing,
    Kind.COMMAND_TABLE: _command_table,
    Kind.VAI: _vai,
    Kind.VAI_16BIT: _vai,
    Kind.PREDEF_VAI: _vai,
    Kind.TIME_CURVE: _time_curve,
    Kind.PREDEF_VAI_16BIT: _vai,
    Kind.VAI_PREDEF_ACC: _vai,
    Kind.VAI_DEC_ACC: _vai,
    Kind.VAI_16BIT_DEC_ACC: _vai,
    Kind.SELECT_CONTROLLER_SET: VV.select_controller_set,
    Kind.RESET: VV.reset,
    Kind.CT_MODIFY: ct_language.modify_entry,
    Kind.CT_VARIABLE: ct_language.variable,
    Kind.CT_IF: ct_language.if_jump,
    Kind.VAI_CT_VAR: ct_language.vai_to_variable,
    Kind.STREAM: stream_setpoint,
    Kind.STREAM_STOP: stop_streaming,
    Kind.CURVE_MODIFY: modify_curve,
}

# the kinds of their own modules (one line each)
from . import encoder_cams, force_control, position_indexing, winding  # noqa: E402

HANDLERS.update(encoder_cams.HANDLERS)
HANDLERS.update(position_indexing.HANDLERS)
HANDLERS.update(winding.HANDLERS)
HANDLERS.update(force_control.HANDLERS)
