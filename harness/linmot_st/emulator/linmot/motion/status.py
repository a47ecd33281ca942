"""The MC software's outputs: status word, state var, warn word, the variables it publishes and TxPDO2's
default content (seed 004 chapter 3, [MC] chapter 3 and 10; [CO1100] 5.1). A part of MotionControl
(control.py).
"""

from __future__ import annotations

import struct

from ....protocol import words as W
from ....protocol.upids import (
    P_RANGE1_MAX,
    P_RANGE1_MIN,
    P_SCALE_POS,
    V_ACTUAL_POSITION,
    V_ACTUAL_POSITION_16,
    V_ACTUAL_VELOCITY,
    V_ANALOG_X4_4,
    V_CAPTURED_POSITION,
    V_CONTROL_WORD,
    V_CT_VAR1,
    V_CT_VAR2,
    V_DEMAND_CURRENT,
    V_DEMAND_POSITION,
    V_DEMAND_POSITION_16,
    V_DEMAND_VELOCITY,
    V_LOGGED_ERROR,
    V_POSITION_DIFFERENCE,
    V_STATE_VAR,
    V_STATUS_WORD,
    V_TARGET_POSITION,
    V_WARN_WORD,
    V_X4_INPUTS,
    V_X4_OUTPUTS,
    V_X6_OUTPUTS,
)
from .sync_variables import sync_variable
from .trajectory import Sample
from .units import VEL_RAW

_TXPDO2 = struct.Struct("<HHHH")


def _s16(v: float) -> int:
    x = round(v)                # an int for a float or an int
    return -32768 if x < -32768 else 32767 if x > 32767 else x


class StatusWords:
    """The output words and published variables (a mixin of MotionControl)."""

    @property
    def motion_active(self) -> bool:
        """Setpoint generation active (status word bit 13); INFERRED: also while a command-table sequence runs."""
        return self.running and self.controlled and (not self.gen.done(self._now) or self.ct_runner.running)

    @property
    def status_word(self) -> int:
        return self.words[0]

    @property
    def state_var(self) -> int:
        return self.words[1]

    @property
    def warn_word(self) -> int:
        return self.words[3]

    def outputs(self) -> tuple[int, int, int, int]:
        """Status word, state var, logged error code, warn word (TxPDO1), as of the last event or cycle."""
        return self.words

    def _warn_word(self) -> int:
        if not self.running or self.state == W.SETUP_ERROR:
            return 0
        return self.warn_bits | (0 if self.homed else W.WARN_MOTOR_NOT_HOMED)

    def _status_word(self, warn: int) -> int:
        if not self.running:
            return 0
        cw, s = self.control_word, self.state
        bits = 0
        if s >= W.OPERATION_ENABLED:
            bits |= W.SW_OPERATION_ENABLED
        if cw & W.CW_SWITCH_ON:
            bits |= W.SW_SWITCH_ON_ACTIVE
        if cw & W.CW_ENABLE_OPERATION:
            bits |= W.SW_ENABLE_OPERATION
        if s in (W.SETUP_ERROR, W.ERROR, W.ERROR_QUICK_STOP):
            bits |= W.SW_ERROR
        if cw & W.CW_VOLTAGE_ENABLE:
            bits |= W.SW_VOLTAGE_ENABLE
        if cw & W.CW_QUICK_STOP_N:
            bits |= W.SW_QUICK_STOP_N
        if s == W.NOT_READY_TO_SWITCH_ON:
            bits |= W.SW_SWITCH_ON_LOCKED
        if warn:
            bits |= W.SW_WARNING
        if self.events.armed is not None:
            bits |= W.SW_EVENT_HANDLER
        if s in W.SPECIAL_STATES and self.sub != W.SUB_FINISHED:
            bits |= W.SW_SPECIAL_MOTION
        if self.pending.armed:
            bits |= W.SW_EVENT_HANDLER
        if self.in_target:
            bits |= W.SW_IN_TARGET
        if self.homed:
            bits |= W.SW_HOMED
        if self.fatal and s in (W.SETUP_ERROR, W.ERROR, W.ERROR_QUICK_STOP):
            bits |= W.SW_FATAL
        if self.motion_active:
            bits |= W.SW_MOTION_ACTIVE
        if self._in_range_1():
            bits |= W.SW_RANGE_1
        return bits

    def _in_range_1(self) -> bool:
        upid = self._range1.ram                 # par(P_RANGE1_UPID), read at every record
        if not upid:                    # no range watched (the default): at every record, so checked first
            return False
        lo, hi = self.par(P_RANGE1_MIN), self.par(P_RANGE1_MAX)
        if lo > hi:
            return False
        v = self.variable(upid)
        if v is None:
            v = self.par(upid, None)
        return v is not None and lo <= v <= hi

    def _state_var(self) -> int:
        if not self.running:
            return 0
        s = self.state
        if s in (W.SETUP_ERROR, W.ERROR):
            low = self.error_code & 0xFF
        elif s == W.OPERATION_ENABLED:
            low = self.last_count
            if self.motion_active:
                low |= W.SV_MOTION_ACTIVE
            if self.in_target:
                low |= W.SV_IN_TARGET
            if self.homed:
                low |= W.SV_HOMED
            if self.pending.armed or self.events.armed is not None:
                low |= W.SV_EVENT_HANDLER
        elif s in W.SPECIAL_STATES:
            low = self.sub
        else:
            low = 0
        return s << 8 | low

    def position_16(self, pu: float) -> int:
        """A position in the 16-bit interface scaling (1B94h, 1B95h; INFERRED: saturated)."""
        return _s16(pu / max(self.par(P_SCALE_POS, 1000), 1))

    def txpdo2_payload(self) -> bytes:
        """TxPDO2's default content ([CO1100] 5.1): motion command status (the last header), actual position
        16 bit, demand current, demand position 16 bit; the same values as variable(), packed in one call with
        a precomputed struct, as TxPDO2 goes on every SYNC."""
        # par() and max() without their calls: the same scale as position_16's
        scale = self._scale_pos.ram
        if scale < 1:
            scale = 1
        axis = self.axis
        actual, demand = round((axis.physical + axis.offset) / scale), round(self.dem_p / scale)
        current = round(axis.demand_current_ma()) if self.running and self.controlled else 0
        # _s16 only where a value is out of range (saturated): three calls fewer on every SYNC
        if not (-32768 <= actual <= 32767 and -32768 <= demand <= 32767 and -32768 <= current <= 32767):
            actual, demand, current = _s16(actual), _s16(demand), _s16(current)
        return _TXPDO2.pack(self.last_header, actual & 0xFFFF, current & 0xFFFF, demand & 0xFFFF)

    def variable(self, upid: int) -> int | None:
        """The value of an MC variable now (SDO reads, TxPDOs by UPID); None: not a variable of the MC."""
        if upid == V_STATUS_WORD:
            return self.words[0]
        if upid == V_STATE_VAR:
            return self.words[1]
        if upid == V_ACTUAL_POSITION:
            return int(round(self.axis.position))
        if upid == V_ACTUAL_POSITION_16:
            return self.position_16(self.axis.position)
        if upid == V_DEMAND_POSITION_16:
            return self.position_16(self.dem_p)
        if upid == V_WARN_WORD:
            return self.words[3]
        if upid == V_LOGGED_ERROR:
            return self.words[2]
        if upid == V_CONTROL_WORD:
            return self.control_word
        if upid == V_DEMAND_CURRENT:
            return _s16(self.axis.demand_current_ma()) if self.running and self.controlled else 0
        if upid == V_DEMAND_POSITION:
            return int(round(self.dem_p))
        if upid == V_DEMAND_VELOCITY:
            return int(round(self.dem_v / VEL_RAW))
        if upid == V_ACTUAL_VELOCITY:
            return int(round(self.axis.velocity / VEL_RAW))
        if upid == V_TARGET_POSITION:
            return int(round(self.gen.target))
        if upid == V_POSITION_DIFFERENCE:
            return int(round(self.dem_p - self.axis.position))
        if upid in (V_CT_VAR1, V_CT_VAR2):
            return self.ct_runner.variables[1 if upid == V_CT_VAR1 else 2]
        io = self.io
        if io is not None:
            if upid == V_CAPTURED_POSITION:
                return io.captured_position
            if upid == V_X4_INPUTS:
                return io.input_word()
            if upid == V_X4_OUTPUTS:
                return io.outputs("X4")
            if upid == V_X6_OUTPUTS:
                return io.outputs("X6")
            if upid == V_ANALOG_X4_4:
                return _s16(io.analog() * 1000)
        return sync_variable(self, upid)        # master encoder, cams, force (sync_variables.py)

    def _record(self, t: int) -> None:
        """After an event or a cycle: the outputs are brought up to date, the trajectory gets a sample."""
        self._update_in_target(t)
        warn = self._warn_word()
        sw, sv = self._status_word(warn), self._state_var()
        self.words = (sw, sv, self.error_code if self.running else 0, warn)
        if self.s.record_trajectory:
            self.trajectory.add(Sample(t, self.dem_p, self.axis.position, self.dem_v, self.axis.velocity, sv, sw))
