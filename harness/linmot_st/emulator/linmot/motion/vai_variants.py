"""The drive's side of the VAI families of protocol/commands/vai_variants.py and system_mc.py: the units of the
new VAI kinds (what the interpreter's VAI handler reads from a command), the queued and transition variants
(pending.py holds them), infinite motion (velocity_plan.py), the maximal current of the With Max Curr commands,
Select Position Controller Set (005xh) and Reset (00Fxh). A part of the interpreter (interpreter.py)."""

from __future__ import annotations

from collections.abc import Callable

from ....protocol.commands import CommandDef, Kind, Target
from ....protocol.upids import (
    P_ACTIVE_CONTROLLER_SET,
    P_MAX_CURRENT_SET_A,
    P_MAX_CURRENT_SET_B,
    P_SCALE_POS,
    P_SCALE_VEL,
)
from .units import ACC_RAW, VEL_RAW
from .velocity_plan import VelocityPlan

Values = tuple[float, float, float, float]      # position (or increment), vmax, acc, dec in pu, pu/s, pu/s^2


def _predef_16bit(mc, f: dict) -> Values:
    return (f["target"] * mc.par(P_SCALE_POS, 1000), *mc._predef())


def _predef_acc(mc, f: dict) -> Values:
    _, acc, dec = mc._predef()
    return f["target"], f["vmax"] * VEL_RAW, acc, dec


def _dec_acc(mc, f: dict) -> Values:
    acc = f["acc"] * ACC_RAW
    return f["target"], f["vmax"] * VEL_RAW, acc, acc


def _dec_acc_16bit(mc, f: dict) -> Values:
    acc = f["acc"] * mc._acc16()
    return f["target"] * mc.par(P_SCALE_POS, 1000), f["vmax"] * mc.par(P_SCALE_VEL, 1000) * VEL_RAW, acc, acc


# the units of each new VAI kind (the interpreter's _vai_values reads the basic kinds itself)
UNITS: dict[Kind, Callable[[object, dict], Values]] = {
    Kind.PREDEF_VAI_16BIT: _predef_16bit,
    Kind.VAI_PREDEF_ACC: _predef_acc,
    Kind.VAI_DEC_ACC: _dec_acc,
    Kind.VAI_16BIT_DEC_ACC: _dec_acc_16bit,
}

# stops of these kinds carry no deceleration: they use the quick-stop deceleration ([MC] 4.3.30, 4.3.93)
QUICK_STOP_KINDS = frozenset({Kind.PREDEF_VAI, Kind.PREDEF_VAI_16BIT})
INFINITE = {Target.INFINITE_POSITIVE: 1.0, Target.INFINITE_NEGATIVE: -1.0}
TRANSITIONS = {Target.TRANSITION_POSITIVE: True, Target.TRANSITION_NEGATIVE: False}


def no_position(mc, c: CommandDef, f: dict, t: int, values: Callable[[object, CommandDef, dict], Values]) -> bool:
    """The VAI rows whose position field is no target: infinite motion and position transitions (`values`: the
    interpreter's units of a VAI command). True when the row is one of them (and has been run)."""
    if c.target in INFINITE:
        p, v, _ = mc.gen.at(t)
        vmax, acc, dec = mc._predef() if "vmax" not in f else values(mc, c, {"target": 0, **f})[1:]
        mc.last_vai = None
        mc._start(VelocityPlan(t, p, v, INFINITE[c.target] * vmax, acc, dec))
        return True
    if c.target in TRANSITIONS:
        position, vmax, acc, dec = values(mc, c, {"target": f["position"], **f})
        mc.pending.arm_transition(position, TRANSITIONS[c.target], vmax, acc, dec, mc.gen.at(t)[0])
        mc._wake(t)
        return True
    return False


def max_current_upid(mc) -> int:
    """The maximal current of the active position-controller set (1393h: 0 = A, 1 = B; [MC] 4.3.5, 4.3.114)."""
    return P_MAX_CURRENT_SET_B if mc.par(P_ACTIVE_CONTROLLER_SET) == 1 else P_MAX_CURRENT_SET_A


def set_max_current(mc, ma: int) -> None:
    """0C5xh..0C7xh: the command's current goes into the active set's maximal current ([MC] 4.3.114..116), and
    from then on the axis model limits its current to the active set's value (INFERRED: before the first such
    command the limit is not modelled; docs/emulator.md)."""
    upid = max_current_upid(mc)
    if upid in mc.params:
        d = mc.params[upid].d
        mc.params[upid].ram = min(max(ma, d.min), d.max)
    mc.current_limited = True
    apply_current_limit(mc)


def apply_current_limit(mc) -> None:
    mc.axis.current_limit_ma = float(mc.par(max_current_upid(mc))) if mc.current_limited else None


def select_controller_set(mc, c: CommandDef, f: dict, t: int) -> bool:
    """005xh: 1393h := 0 (set A) or 1 (set B); other values are ignored (INFERRED)."""
    if f["controller_set"] in (0, 1) and P_ACTIVE_CONTROLLER_SET in mc.params:
        mc.params[P_ACTIVE_CONTROLLER_SET].ram = f["controller_set"]
        apply_current_limit(mc)
    return True


def reset(mc, c: CommandDef, f: dict, t: int) -> bool:
    """00Fxh: the drive restarts its firmware ([MC] 4.3.8) as on a software reset; without a drive around the
    MC (a bare MotionControl) nothing happens."""
    if mc.on_reset is not None:
        mc.on_reset(t)
    return True
