"""The handlers of the I/O, event-handler and triggered commands (protocol/commands/io.py, triggered.py),
registered into the interpreter's HANDLERS table. The plain motions they start are the interpreter's own
(VaPlan through `mc._vai`, the time-curve handler, the command-table runner).
"""

from __future__ import annotations

from ....protocol import commands as C
from ....protocol import words as W
from ....protocol.commands import CommandDef, Kind, Start, Target
from ....protocol.commands.triggered import TRIGGERED, Units
from ....protocol.upids import (
    P_ANALOG_POS_MAX,
    P_ANALOG_POS_MIN,
    P_PREDEF_ACC,
    P_PREDEF_DEC,
    P_SCALE_POS,
    P_SCALE_VEL,
    P_TRIG_FALL_ACC,
    P_TRIG_FALL_DEC,
    P_TRIG_FALL_TARGET,
    P_TRIG_FALL_VMAX,
    P_TRIG_RISE_ACC,
    P_TRIG_RISE_DEC,
    P_TRIG_RISE_TARGET,
    P_TRIG_RISE_VMAX,
)
from .interpreter import HANDLERS
from .units import ACC_RAW, VEL_RAW


def _io_outputs(mc, c: CommandDef, f: dict, t: int) -> bool:
    if mc.io is not None:
        mc.io.write_outputs("X4" if c.cid == C.WRITE_X4_OUTPUTS else "X6", f["mask"], f["value"], t)
    return True


def _clear_events(mc, c: CommandDef, f: dict, t: int) -> bool:
    """008xh: the event handler forgets what is armed; INFERRED: also the queued "after actual command" move and
    the armed position transition (pending.py), which show as the same event-handler bit."""
    mc.events.clear()
    mc.pending.clear()
    return True


def vai_values(mc, units: Units, f: dict) -> tuple[float, float, float, float]:
    """Position (or increment), vmax, acc, dec in pu, pu/s, pu/s^2 of a triggered VAI's fields."""
    if units is Units.V32:
        return f["target"], f["vmax"] * VEL_RAW, f["acc"] * ACC_RAW, f["dec"] * ACC_RAW
    predef = mc._predef()
    if units is Units.P32:
        return (f["target"], *predef)
    pos16 = mc.par(P_SCALE_POS, 1000)
    if units is Units.P16:
        return (f["target"] * pos16, *predef)
    if units is Units.V16:
        acc16 = mc._acc16()
        return (f["target"] * pos16, f["vmax"] * mc.par(P_SCALE_VEL, 1000) * VEL_RAW, f["acc"] * acc16,
                f["dec"] * acc16)
    if units is Units.PA:        # INFERRED: the predefined acceleration and deceleration (14BFh/14C0h)
        return f["target"], f["vmax"] * VEL_RAW, mc.par(P_PREDEF_ACC) * ACC_RAW, mc.par(P_PREDEF_DEC) * ACC_RAW
    return f["target"], f["vmax"] * VEL_RAW, f["acc"] * ACC_RAW, f["acc"] * ACC_RAW     # DA: dec = acc


def _start_vai(mc, c: CommandDef, t: int, pos: float, vmax: float, acc: float, dec: float) -> bool:
    """A VAI from the demand (or actual) position, as the row's start and target say."""
    p, v, _ = mc.gen.at(t)
    if c.start is Start.ACTUAL:
        p, v = mc.axis.position, mc.axis.velocity
    elif c.start is Start.ACTUAL_AT_REST:
        p, v = mc.axis.position, 0.0
    target = mc._last_target() + pos if c.target is Target.FROM_LAST_TARGET else pos
    mc._vai(t, p, v, target, vmax, acc, dec)
    return True


def _on_trigger(mc, c: CommandDef, f: dict, t: int) -> bool:
    """Arm the event handler: the plain counterpart runs on every edge until 008xh ([MC] 4.3.6). The field
    values are taken now; an increment adds to the last target as it is at each edge (INFERRED)."""
    trig = TRIGGERED[c.cid]
    if trig.units is not None:
        def action(te: int) -> bool:
            return _start_vai(mc, c, te, *vai_values(mc, trig.units, f))
    else:
        base = C.COMMANDS[trig.base]

        def action(te: int) -> bool:
            return HANDLERS[base.kind](mc, base, f, te)
    mc.events.arm(trig.rising, action)
    return True


def _vai_captured(mc, c: CommandDef, f: dict, t: int) -> bool:
    """0D0xh: target = the captured position (1E62h) + the increment, at once ([MC] 4.3.122/123)."""
    captured = mc.io.captured_position if mc.io is not None else 0
    pos, vmax, acc, dec = vai_values(mc, Units.V32, f)
    return _start_vai(mc, c, t, captured + pos, vmax, acc, dec)


def analog_position(mc) -> float:
    """The target X4.4 sets: linear between 14DCh (at the range's low end) and 14DDh (high end); INVENTED
    scaling, sampled when the command runs (INFERRED)."""
    frac = mc.io.analog_fraction() if mc.io is not None else 0.0
    lo, hi = mc.par(P_ANALOG_POS_MIN), mc.par(P_ANALOG_POS_MAX, 1_000_000)
    return round(lo + (hi - lo) * frac)


def _vai_analog(mc, c: CommandDef, f: dict, t: int) -> bool:
    """019xh; with MotionSettings.analog_target_follows each change of X4.4 re-targets the motion (from the
    demand position and velocity, like a new VAI command) until another motion replaces it."""
    limits = f["vmax"] * VEL_RAW, f["acc"] * ACC_RAW, f["dec"] * ACC_RAW
    _start_vai(mc, c, t, analog_position(mc), *limits)
    mc.events.follow = None
    if mc.s.analog_target_follows:
        plan = [mc.gen]

        def follow(te: int) -> None:
            if mc.gen is not plan[0] or mc.state != W.OPERATION_ENABLED:
                mc.events.follow = None             # another motion, a stop or an error ended it
                return
            target = analog_position(mc)
            if target != mc.gen.target:
                _start_vai(mc, c, te, target, *limits)
                plan[0] = mc.gen
                mc._record(te)
        mc.events.follow = follow
    return True


_TRIG_CONFIG = {C.VAI_START_TRIG_RISE_CONFIG: (P_TRIG_RISE_TARGET, P_TRIG_RISE_VMAX, P_TRIG_RISE_ACC, P_TRIG_RISE_DEC),
                C.VAI_START_TRIG_FALL_CONFIG: (P_TRIG_FALL_TARGET, P_TRIG_FALL_VMAX, P_TRIG_FALL_ACC, P_TRIG_FALL_DEC)}


def _vai_trig_config(mc, c: CommandDef, f: dict, t: int) -> bool:
    """0DExh/0DFxh: a VAI to the Trig Rise / Fall Config target with its limits, started at once ([MC] 4.3.128:
    "starts the VAI motion command defined with the parameters in Trig Rise Config")."""
    target, vmax, acc, dec = (mc.par(u) for u in _TRIG_CONFIG[c.cid])
    return _start_vai(mc, c, t, target, vmax * VEL_RAW, acc * ACC_RAW, dec * ACC_RAW)


HANDLERS[Kind.IO_OUTPUTS] = _io_outputs
HANDLERS[Kind.CLEAR_EVENTS] = _clear_events
HANDLERS[Kind.ON_TRIGGER] = _on_trigger
HANDLERS[Kind.VAI_CAPTURED] = _vai_captured
HANDLERS[Kind.VAI_ANALOG] = _vai_analog
HANDLERS[Kind.VAI_TRIG_CONFIG] = _vai_trig_config
