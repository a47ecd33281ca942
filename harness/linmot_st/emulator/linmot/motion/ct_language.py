"""The command-table language of the MC ([MC] 4.3.124..127, 166..211, [MC] 6): the handlers of the kinds
CT_MODIFY, CT_VARIABLE, CT_IF and VAI_CT_VAR (registered in interpreter.HANDLERS), the conditions of the waits and
the IFs that ct_runner.py evaluates, and the two command-table variables.

Signals and units: positions in 0.1 um (demand, actual, difference = demand - actual, as the variable 1B91h),
velocities in 1E-6 m/s, current in mA (the demand current 1B93h: [MC] 4.3.185 calls the level "Dem Curr"), the
analog input X4.4 in mV, the masked IFs on the X4 inputs, the X6 levels, the status and warn word as they are now. INFERRED (docs/emulator.md 13.6): "Greater/Less Than" are
strict; "Unsigned" compares |difference|; the IFs' values are in the unit of the same signal's wait.

A wait or IF of another group registers its condition in WAITS / IF_CONDITIONS here (as the trigger waits
213xh/214xh of the event handler do); the runner needs no change for it.
"""

from __future__ import annotations

import operator
import struct
from collections.abc import Callable

from ....protocol import commands as C
from ....protocol import words as W
from ....protocol.commands import CommandDef, Start
from ....protocol.upids import V_DEMAND_CURRENT
from .units import ACC_RAW, VEL_RAW

Signal = Callable[[object], float]
WaitFactory = Callable[[object, dict, int], Callable[[int], bool]]   # (mc, fields, t) -> holds(t)


def _demand_pos(mc) -> float:
    return mc.dem_p


def _actual_pos(mc) -> float:
    return mc.axis.position


def _diff_pos(mc) -> float:
    return mc.dem_p - mc.axis.position


def _diff_pos_unsigned(mc) -> float:
    return abs(mc.dem_p - mc.axis.position)


def _demand_vel(mc) -> float:
    return mc.dem_v / VEL_RAW


def _actual_vel(mc) -> float:
    return mc.axis.velocity / VEL_RAW


def _current(mc) -> float:
    return mc.variable(V_DEMAND_CURRENT)


def _var1(mc) -> float:
    return mc.ct_runner.variables[1]


def _var2(mc) -> float:
    return mc.ct_runner.variables[2]


def _level(signal: Signal, op) -> WaitFactory:
    return lambda mc, f, t: (lambda now: op(signal(mc), f["level"]))


def _wait_time(mc, f: dict, t: int) -> Callable[[int], bool]:
    until = t + f["time"] * 100_000                 # 100 us ([MC] 4.3.168)
    return lambda now: now >= until


GT, LT = operator.gt, operator.lt

# wait ID -> its condition, built when the wait entry runs (at t) and checked every MC cycle after
WAITS: dict[int, WaitFactory] = {
    C.WAIT_TIME: _wait_time,
    C.WAIT_MOTION_FINISHED: lambda mc, f, t: (lambda now: mc.gen.done(now)),
    C.WAIT_IN_TARGET_POSITION: lambda mc, f, t: (lambda now: mc.in_target),
    # the next trigger edge at or after the wait's start ([MC] 4.3.171/172; the edges: events.py)
    C.WAIT_RISING_TRIGGER: lambda mc, f, t: (lambda now: mc.events.edge_since(True, t)),
    C.WAIT_FALLING_TRIGGER: lambda mc, f, t: (lambda now: mc.events.edge_since(False, t)),
    C.WAIT_DEMAND_POS_GREATER: _level(_demand_pos, GT),
    C.WAIT_DEMAND_POS_LESS: _level(_demand_pos, LT),
    C.WAIT_ACTUAL_POS_GREATER: _level(_actual_pos, GT),
    C.WAIT_ACTUAL_POS_LESS: _level(_actual_pos, LT),
    C.WAIT_DIFF_POS_GREATER: _level(_diff_pos, GT),
    C.WAIT_DIFF_POS_LESS: _level(_diff_pos, LT),
    C.WAIT_DIFF_POS_UNSIGNED_GREATER: _level(_diff_pos_unsigned, GT),
    C.WAIT_DIFF_POS_UNSIGNED_LESS: _level(_diff_pos_unsigned, LT),
    C.WAIT_DEMAND_VEL_GREATER: _level(_demand_vel, GT),
    C.WAIT_DEMAND_VEL_LESS: _level(_demand_vel, LT),
    C.WAIT_ACTUAL_VEL_GREATER: _level(_actual_vel, GT),
    C.WAIT_ACTUAL_VEL_LESS: _level(_actual_vel, LT),
    C.WAIT_CURRENT_GREATER: _level(_current, GT),
    C.WAIT_CURRENT_LESS: _level(_current, LT),
}
# waits whose condition reads nothing a quiet MC cycle changes (the time, the plan's end, the in-target bit; not
# the positions, velocities or current): the quiet cycles (fast_path.py) check them in their loop, so a sequence
# waiting on one runs no generic cycle until the wait holds (test_motion_equivalence.py compares both paths)
QUIET_WAITS = frozenset({C.WAIT_TIME, C.WAIT_MOTION_FINISHED, C.WAIT_IN_TARGET_POSITION})


def _compare(signal: Signal, op) -> Callable[[object, dict], bool]:
    return lambda mc, f: op(signal(mc), f["value"])


def _masked(word: Callable[[object], int]) -> Callable[[object, dict], bool]:
    """(word AND mask) = value ([MC] 4.3.208..211)."""
    return lambda mc, f: word(mc) & f["mask"] == f["value"] & f["mask"]


def _analog_mv(mc) -> float:
    """X4.4 in mV (INFERRED unit: [MC] 4.3.207 gives none; the variable 1DA3h's)."""
    return round(mc.io.analog() * 1000) if mc.io is not None else 0


def _x4_inputs(mc) -> int:
    """The X4 input levels, bit 0 = X4.3 (the bit order of 003xh's outputs, INFERRED)."""
    return mc.io.input_word() if mc.io is not None else 0


def _x6_levels(mc) -> int:
    """X6 read back: the model's X6 pins are outputs (004xh), so their levels (INFERRED)."""
    return mc.io.outputs("X6") if mc.io is not None else 0


def _status_word_now(mc) -> int:
    return mc._status_word(mc._warn_word())


def _warn_word_now(mc) -> int:
    return mc._warn_word()


# IF ID -> whether its condition holds now (then the sequence continues at if_true, else at if_false)
IF_CONDITIONS: dict[int, Callable[[object, dict], bool]] = {
    C.IF_VAR1_LESS: _compare(_var1, LT),
    C.IF_VAR1_GREATER: _compare(_var1, GT),
    C.IF_VAR2_LESS: _compare(_var2, LT),
    C.IF_VAR2_GREATER: _compare(_var2, GT),
    C.IF_DEMAND_POS_LESS: _compare(_demand_pos, LT),
    C.IF_DEMAND_POS_GREATER: _compare(_demand_pos, GT),
    C.IF_ACTUAL_POS_LESS: _compare(_actual_pos, LT),
    C.IF_ACTUAL_POS_GREATER: _compare(_actual_pos, GT),
    C.IF_DIFF_POS_LESS: _compare(_diff_pos, LT),
    C.IF_DIFF_POS_GREATER: _compare(_diff_pos, GT),
    C.IF_CURRENT_LESS: _compare(_current, LT),
    C.IF_CURRENT_GREATER: _compare(_current, GT),
    C.IF_ANALOG_X4_4_LESS: _compare(_analog_mv, LT),
    C.IF_MASKED_X4_INPUTS: _masked(_x4_inputs),
    C.IF_MASKED_X6_INPUTS: _masked(_x6_levels),
    C.IF_MASKED_STATUS_WORD: _masked(_status_word_now),
    C.IF_MASKED_WARN_WORD: _masked(_warn_word_now),
}


def if_target(mc, cid: int, f: dict) -> int | None:
    """The entry an IF continues at; None for an IF whose condition this drive cannot evaluate."""
    holds = IF_CONDITIONS.get(cid)
    if holds is None:
        return None
    return f["if_true"] if holds(mc, f) else f["if_false"]


def _s32(v: int) -> int:
    """32-bit two's complement wrap (INFERRED: the variables are SInt32 and an add overflows as in C)."""
    return (v + (1 << 31)) % (1 << 32) - (1 << 31)


_VAR_OF = {C.SET_CT_VAR1: 1, C.ADD_CT_VAR1: 1, C.CT_VAR1_TO_UPID: 1, C.UPID_TO_CT_VAR1: 1,
           C.SET_CT_VAR2: 2, C.ADD_CT_VAR2: 2, C.CT_VAR2_TO_UPID: 2, C.UPID_TO_CT_VAR2: 2,
           C.VAI_GO_TO_CT_VAR1: 1, C.VAI_GO_TO_CT_VAR1_FROM_ACT: 1,
           C.VAI_GO_TO_CT_VAR2: 2, C.VAI_GO_TO_CT_VAR2_FROM_ACT: 2}


def _ram_value(mc, upid: int) -> int | None:
    """A UPID's RAM value as the drive reads it (a variable: its value now); None: no such number (or a string)."""
    p = mc.params.by_upid.get(upid)
    if p is None or p.d.kind == "string":
        return None
    if p.d.kind == "var":
        v = mc.variable(upid)
        if v is not None:
            return int(v)
    return int(p.ram)


# ---------------------------------------------------------------- the handlers, one per kind

def variable(mc, c: CommandDef, f: dict, t: int) -> bool:
    """240xh..24Dxh ([MC] 4.3.187..194): set, add, store into a UPID's RAM value (as 002xh: a live writable
    parameter, masked to its width, in range; else ignored, INFERRED), load from a UPID's RAM value (an unknown
    UPID leaves the variable, INFERRED). They act from the interface too (INFERRED: [MC] does not restrict them
    to a table, unlike the waits)."""
    variables = mc.ct_runner.variables
    n = _VAR_OF[c.cid]
    if c.cid in (C.SET_CT_VAR1, C.SET_CT_VAR2):
        variables[n] = f["value"]
    elif c.cid in (C.ADD_CT_VAR1, C.ADD_CT_VAR2):
        variables[n] = _s32(variables[n] + f["value"])
    elif c.cid in (C.CT_VAR1_TO_UPID, C.CT_VAR2_TO_UPID):
        mc._write_live(f["upid"], variables[n])
    else:
        v = _ram_value(mc, f["upid"])
        if v is not None:
            variables[n] = _s32(v)
    return True


def modify_entry(mc, c: CommandDef, f: dict, t: int) -> bool:
    """208xh/209xh ([MC] 4.3.166/167): a 16/32-bit value at a byte offset of an entry in RAM (2 = link, 4 = header,
    6 = first parameter). INFERRED: an entry not in RAM raises 008Ah as 200xh does; a value that would reach past
    the 64-byte entry is ignored."""
    block = mc.ct.ram.get(f["entry"])
    if block is None:
        return mc._fail(W.ERR_CMD_TAB_ENTRY_NOT_DEFINED, t)
    fmt = "<h" if c.cid == C.MODIFY_CT_16BIT else "<i"
    offset = f["offset"]
    if offset + struct.calcsize(fmt) <= len(block):
        patched = bytearray(block)
        struct.pack_into(fmt, patched, offset, f["value"])
        mc.ct.ram[f["entry"]] = bytes(patched)
    return True


def if_jump(mc, c: CommandDef, f: dict, t: int) -> bool:
    """An IF from the interface (in a table the runner jumps itself). INFERRED (no source): it starts the command
    table at the entry its condition selects, as a 200xh to that entry would."""
    entry = if_target(mc, c.cid, f)
    if entry is None:
        return mc._fail(W.ERR_UNKNOWN_MOTION_CMD, t)
    return mc.ct_runner.start(entry, t)


def vai_to_variable(mc, c: CommandDef, f: dict, t: int) -> bool:
    """0D4xh..0D7xh ([MC] 4.3.124..127): a VAI to the position in Var 1/2 (0.1 um), from the demand position and
    velocity, or (0D6xh/0D7xh) from the actual ones."""
    if c.start is Start.ACTUAL:
        p, v = mc.axis.position, mc.axis.velocity
    else:
        p, v, _ = mc.gen.at(t)
    mc._vai(t, p, v, mc.ct_runner.variables[_VAR_OF[c.cid]], f["vmax"] * VEL_RAW, f["acc"] * ACC_RAW,
            f["dec"] * ACC_RAW)
    return True
