"""MotionControl: the MC software of the emulated E1100 (seed 004 chapters 3-5, [MC] chapters 3-6, 10).

It holds the main state machine (driven by the control word), the motion command interpreter (driven by the
motion command image that the PDOs fill), the setpoint generator in use, the axis, and the monitors (following
error, position limits, in target position). Sans-I/O like the drive: events come in with their time
(`set_control_word`, `command_image`), and the cycle runs from `on_timer` at `next_timer_ns()`, once per MC cycle
while anything moves and not at all while the axis rests. The drive reads the outputs (status word, state var,
logged error, warn word, positions) after each call and publishes them in its TxPDOs and variables.

Every behaviour that no source states is marked INFERRED here and listed in docs/emulator.md section 13.
"""

from __future__ import annotations

import math
import struct
from bisect import bisect_right
from operator import itemgetter
from typing import Callable

from ...protocol.upids import (  # noqa: F401 (re-exported for the MC's modules)
    P_LAG_ALWAYS_WARN, P_LAG_ALWAYS_ERROR, P_LAG_STANDING_WARN, P_LAG_STANDING_ERROR, P_PREDEF_VMAX,
    P_PREDEF_ACC, P_PREDEF_DEC, P_JOG_VELOCITY, P_JOG_INCREMENT, P_SCALE_POS, P_SCALE_VEL, P_SCALE_ACC,
    P_CURVE_OFFSET, P_CURVE_TIME_SCALE, P_CURVE_AMPLITUDE, P_HOMING_MODE, P_HOME_POSITION, P_INITIAL_POSITION,
    P_HOMING_VMAX, P_HOMING_ACC, P_GO_TO_POSITION, P_CLEARANCE_1, P_CLEARANCE_2, P_QUICK_STOP_DEC,
    P_LIMIT_POSITIVE, P_LIMIT_NEGATIVE, P_LIMITS_ENABLE, P_CW_COPY_MASK, P_CW_FORCE_MASK, P_CW_FORCE_VALUES,
    P_RANGE1_UPID, P_RANGE1_MIN, P_RANGE1_MAX, P_READY_TO_OPERATE_MODE, V_STATE_VAR, V_ACTUAL_POSITION,
    V_DEMAND_CURRENT, V_DEMAND_POSITION_16, V_ACTUAL_POSITION_16, V_STATUS_WORD, V_CONTROL_WORD, V_WARN_WORD,
    V_LOGGED_ERROR, V_DEMAND_POSITION, V_TARGET_POSITION, V_POSITION_DIFFERENCE, V_DEMAND_VELOCITY,
    V_ACTUAL_VELOCITY,
)
from ...protocol import commands as C
from ...protocol import words as W
from .axis import Axis
from .ct_runner import CtRunner
from .settings import MotionSettings
from .setpoints import CurvePlan, Hold, StopPlan, VaPlan
from .trajectory import Sample, Trajectory

# homing modes (1500h; the PVL example's "3: Mech Stop Negative Search"; the others INFERRED)
HOMING_SEARCH = {2: +1, 3: -1, 4: +1, 5: -1}       # mech stop / home switch, positive / negative search

# unit conversions: the interface's units to pu (0.1 um), pu/s, pu/s^2
VEL_RAW = 10.0       # 1E-6 m/s = 10 pu/s
ACC_RAW = 100.0      # 1E-5 m/s^2 = 100 pu/s^2

_PLAIN_STATES = frozenset({W.READY_TO_OPERATE, W.OPERATION_ENABLED, W.ABORTING, W.FREEZING})


_TXPDO2 = struct.Struct("<HHHH")
_CYCLE_TIME = itemgetter(0)     # the time of a cycle computed ahead (made once: _apply_ahead runs on every SYNC)


def _s16(v: float) -> int:
    x = round(v)                # an int for a float or an int
    return -32768 if x < -32768 else 32767 if x > 32767 else x


class MotionControl:
    def __init__(self, settings: MotionSettings, hw_test_ns: int, params, curves, ct,
                 log_error: Callable[[int, int], None]):
        self.s = settings
        self.hw_test_ns = hw_test_ns
        self.params, self.curves, self.ct = params, curves, ct
        self._pars = params.by_upid
        self.words = (0, 0, 0, 0)          # status word, state var, logged error, warn word: set by _record
        self._log_error = log_error
        self.axis = Axis(settings)
        self.trajectory = Trajectory()
        self.executed: list[tuple[int, int, bytes]] = []   # (t_ns, header, parameters) of every command run
        self.ct_runner = CtRunner(self)
        self.running = False
        self.power_on_reset()
        self._reset_state()

    def power_on_reset(self) -> None:
        """The interface's registers at power-on: control word and the last motion command count are 0. They
        survive an MC restart (35h/36h): the interface keeps them, so a repeated RxPDO does not run its command
        again (INFERRED)."""
        self.interface_cw = 0
        self.last_count = 0
        self.last_header = 0

    def _reset_state(self) -> None:
        self.state = W.NOT_READY_TO_SWITCH_ON
        self.sub = 0
        self.error_code = 0
        self.fatal = False
        self.homed = False
        self.control_word = 0
        self.controlled = False
        self.gen = Hold(self.axis.position)
        self.dem_p, self.dem_v = self.axis.position, 0.0
        self.last_vai: tuple | None = None       # (target, vmax, acc, dec) of the last VAI motion
        self.frozen: tuple | None = None
        self.after_stop: str | None = None       # what the running stop ramp ends in: "error", "off3", None
        self.warn_bits = 0
        self.in_target = False
        self._in_window_since: int | None = None
        self._hw_test_end: int | None = None
        self._special_phase = 0
        self._next_tick: int | None = None
        self._ahead: list[tuple] = []
        self._ahead_samples: list[Sample] = []     # their trajectory samples (a list of its own: no copying)
        self._last_tick = 0
        self._prev_vd = 0.0
        self._now = getattr(self, "_now", 0)
        self.ct_runner.stop()

    # ------------------------------------------------------------------ parameters
    def par(self, upid: int, default: int = 0) -> int:
        """The RAM value of a parameter (default where the drive has no such UPID)."""
        p = self._pars.get(upid)
        return default if p is None else p.ram

    # ------------------------------------------------------------------ MC software start / stop
    def start(self, t: int, motor_defined: bool) -> int | None:
        """MC start (boot, 36h): returns an error code to log when the configuration is unusable."""
        self.sync(t)
        self._now = t
        self.running = True
        self._reset_state()
        self.axis.forget_reference()
        self.gen = Hold(self.axis.position)
        self.dem_p = self.axis.position
        self.control_word = self._effective_cw()
        if not motor_defined:
            self.state, self.error_code, self.fatal = W.SETUP_ERROR, W.ERR_NO_MOTOR_DEFINED, True
            self._record(t)
            return W.ERR_NO_MOTOR_DEFINED
        self._evaluate(t, 0)
        self._record(t)
        return None

    def stop(self, t: int | None = None) -> None:
        """MC stopped (35h, reset, power off): the power stage is off, the slider coasts."""
        t = self._now if t is None else t
        self.sync(t)
        self.running = False
        self._reset_state()
        if self.axis.velocity:
            self._wake(t)
        self._record(t)

    # ------------------------------------------------------------------ inputs
    def _effective_cw(self) -> int:
        """[MC] 3.21: bits forced by parameter win; the interface's bits pass through the copy mask."""
        force = self.par(P_CW_FORCE_MASK)
        cw = (self.interface_cw & self.par(P_CW_COPY_MASK, 0xFFFF) & ~force) | (self.par(P_CW_FORCE_VALUES) & force)
        return cw & 0xFFFF

    def set_control_word(self, interface_cw: int, t: int) -> None:
        """A new control word from the interface (RxPDO1, 001xh); bits forced by parameter win ([MC] 3.21).
        The same word again changes nothing (the state machine rests where the word left it)."""
        if interface_cw & 0xFFFF == self.interface_cw and self._effective_cw() == self.control_word:
            return
        self.sync(t)
        self.interface_cw = interface_cw & 0xFFFF
        old, self.control_word = self.control_word, self._effective_cw()
        if self.running:
            self._evaluate(t, old)
            self._record(t)

    def command_image(self, header: int, params: bytes, t: int) -> None:
        """The motion command interface holds a complete command (the PDO layer checked the slave header). It
        executes when its count differs from the last one interpreted (seed 004 4.1.1.3)."""
        count = header & 0x000F
        if count == self.last_count:
            return
        self.sync(t)
        self.last_count = count
        if not self.running:
            return
        self.last_header = header & 0xFFFF
        c = C.COMMANDS.get(C.command_id(header))
        if self.state not in (c.states if c is not None else C.IN_OPERATION_ENABLED):
            if self.state == W.READY_TO_OPERATE or (self.state >= W.HOMING and self.state != W.ERROR_QUICK_STOP):
                self._fail(W.ERR_MOTION_CMD_WRONG_STATE, t)     # seed 004 3.7: error, state 4
                self._record(t)
            return      # INFERRED: in states 0..5 (and 14) a new count is taken but not executed
        self.ct_runner.stop()   # a command from the interface ends a running command-table sequence
        self.execute(header, params, t)
        self._record(t)

    # ------------------------------------------------------------------ the interpreter
    def execute(self, header: int, params: bytes, t: int, from_table: bool = False) -> bool:
        """Run one motion command at t; False when it raised an error."""
        c, f = C.decode(header, params)
        self.executed.append((t, header, bytes(params[:16])))
        if c is None:
            return self._fail(W.ERR_UNKNOWN_MOTION_CMD, t)
        cid = c.cid
        if c.needs_homing and self.s.motion_requires_homing and not self.homed:
            return self._fail(W.ERR_NOT_HOMED, t)
        if cid == C.NOP or cid in (C.WAIT_TIME, C.WAIT_MOTION_FINISHED, C.WAIT_IN_TARGET_POSITION):
            return True         # waits act only inside a command-table sequence (ct_runner.py)
        if cid == C.WRITE_CONTROL_WORD:
            self.set_control_word(f["control_word"], t)
            return True
        if cid == C.WRITE_LIVE_PARAMETER:
            self._write_live(f["upid"], f["value"])
            return True
        if cid == C.MASTER_HOMING:
            if P_HOME_POSITION in self.params:
                self.params[P_HOME_POSITION].ram = self.params[P_HOME_POSITION].d.type.from_raw(f["home_position"])
            self._reference(f["home_position"], t)
            return True
        if cid == C.START_COMMAND_TABLE:
            return self.ct_runner.start(f["entry"], t)
        p, v, _ = self.gen.at(t)
        if cid in (C.VAI_STOP, C.VAI16_STOP, C.PREDEF_VAI_STOP):
            dec = {C.VAI_STOP: lambda: f["dec"] * ACC_RAW, C.VAI16_STOP: lambda: f["dec"] * self._acc16(),
                   C.PREDEF_VAI_STOP: lambda: self.par(P_QUICK_STOP_DEC, 5_000_000) * ACC_RAW}[cid]()
            self._start(StopPlan(t, p, v, dec))
            return True
        if C.VAI_GO_TO_POS <= cid <= C.VAI_INCREMENT_ACT_POS_VEL_0 or C.VAI16_GO_TO_POS <= cid <= C.VAI16_INCREMENT_TARGET_POS:
            if cid >= C.VAI16_GO_TO_POS:
                pos, vmax = f["target"] * self.par(P_SCALE_POS, 1000), f["vmax"] * self.par(P_SCALE_VEL, 1000) * VEL_RAW
                acc, dec = f["acc"] * self._acc16(), f["dec"] * self._acc16()
                kind = cid - C.VAI16_GO_TO_POS + C.VAI_GO_TO_POS
            else:
                pos, vmax, acc, dec = f["target"], f["vmax"] * VEL_RAW, f["acc"] * ACC_RAW, f["dec"] * ACC_RAW
                kind = cid
            if kind in (C.VAI_GO_TO_POS_FROM_ACT_POS_AND_VEL, C.VAI_GO_TO_POS_FROM_ACT_POS_VEL_0,
                        C.VAI_INCREMENT_ACT_POS, C.VAI_INCREMENT_ACT_POS_VEL_0):
                p = self.axis.position
                v = self.axis.velocity if kind == C.VAI_GO_TO_POS_FROM_ACT_POS_AND_VEL else 0.0
            target = {C.VAI_INCREMENT_DEM_POS: p + pos, C.VAI_INCREMENT_TARGET_POS: self._last_target() + pos,
                      C.VAI_INCREMENT_ACT_POS: p + pos, C.VAI_INCREMENT_ACT_POS_VEL_0: p + pos}.get(kind, pos)
            self._vai(t, p, v, target, vmax, acc, dec)
            return True
        if cid in (C.PREDEF_VAI_GO_TO_POS, C.PREDEF_VAI_INCREMENT_DEM_POS, C.PREDEF_VAI_INCREMENT_TARGET_POS):
            pos = f["target"]
            target = {C.PREDEF_VAI_INCREMENT_DEM_POS: p + pos,
                      C.PREDEF_VAI_INCREMENT_TARGET_POS: self._last_target() + pos}.get(cid, pos)
            self._vai(t, p, v, target, *self._predef())
            return True
        if C.TIME_CURVE <= cid <= C.TIME_CURVE_OFFSET_TIME_AMP:
            return self._curve(cid, f, p, t)
        return self._fail(W.ERR_UNKNOWN_MOTION_CMD, t)

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

    def _curve(self, cid: int, f: dict, demand: float, t: int) -> bool:
        curve = self.curves.ram.get(f["curve_id"])
        if curve is None or curve.object_type != 0x0003:
            # not in RAM; a cam (0103h) has no time axis: INFERRED the same error as an undefined curve
            return self._fail(W.ERR_CURVE_NOT_DEFINED, t)
        y = curve.setpoints
        nominal_ns = curve.x_length * 10_000                  # x-length in 10 us
        offset = self.par(P_CURVE_OFFSET)
        time_scale = self.par(P_CURVE_TIME_SCALE, 10000)     # 0.01 %: stretches the time axis (INFERRED)
        amp = self.par(P_CURVE_AMPLITUDE, 1000) / 1000.0      # 0.1 %
        duration = nominal_ns * time_scale // 10000
        if cid == C.TIME_CURVE_FROM_ACT_POS:
            offset = demand
        elif cid in (C.TIME_CURVE_TO_POS, C.TIME_CURVE_TO_POS_TIME):
            offset = demand
            if y[-1] == 0:
                return self._fail(W.ERR_CURVE_AMP_SCALE, t)
            amp = (f["target"] - offset) / y[-1]
            if cid == C.TIME_CURVE_TO_POS_TIME:
                duration = f["curve_time"] * 10_000
        elif cid == C.TIME_CURVE_OFFSET_TIME_SCALE_AMP:
            offset, amp = f["offset"], f["amplitude"] / 1000.0
            duration = nominal_ns * f["time_scale"] // 10000
        elif cid == C.TIME_CURVE_OFFSET_TIME_AMP:
            offset, amp, duration = f["offset"], f["amplitude"] / 1000.0, f["curve_time"] * 10_000
        if not -20.0 <= amp <= 20.0:                           # -2000 % .. 2000 %
            return self._fail(W.ERR_CURVE_AMP_SCALE, t)
        self._start(CurvePlan(t, curve.curve_id, y, max(duration, 0), offset, amp))
        return True

    def _write_live(self, upid: int, raw: int) -> None:
        """002xh: the RAM value of a live parameter, masked to its width (INFERRED: anything else is ignored)."""
        p = self.params
        if upid in p:
            d = p[upid].d
            if d.kind == "par" and d.live and d.access == "rw":
                value = d.type.from_raw(raw & 0xFFFFFFFF)
                if d.min <= value <= d.max:
                    p[upid].ram = value

    # ------------------------------------------------------------------ the state machine
    def _evaluate(self, t: int, old_cw: int) -> None:
        cw = self.control_word
        rising = cw & ~old_cw
        for _ in range(8):                  # a control word can pass several states at once
            s = self.state
            if s == W.SETUP_ERROR or s == W.ERROR_QUICK_STOP:
                return
            if s == W.ERROR:
                if rising & W.CW_ERROR_ACK and not self.fatal:
                    rising &= ~W.CW_ERROR_ACK
                    self.error_code = 0       # INFERRED: the logged error code clears with the acknowledge
                    self.state = W.NOT_READY_TO_SWITCH_ON      # INFERRED: then the anti-restart rule of state 0
                    continue
                return
            on = cw & W.CW_SWITCH_ON
            if s == W.NOT_READY_TO_SWITCH_ON:
                if on:
                    return
                self.state = W.SWITCH_ON_DISABLED
                continue
            if s == W.SWITCH_ON_DISABLED:
                if cw & (W.CW_VOLTAGE_ENABLE | W.CW_QUICK_STOP_N | W.CW_SWITCH_ON) != W.CW_VOLTAGE_ENABLE | W.CW_QUICK_STOP_N:
                    return                    # the transition is "xxxx x110": bit 0 must be 0 too
                self.state = W.READY_TO_SWITCH_ON
                continue
            if self.after_stop == "off3":
                return                        # a quick stop runs to its end, then the power stage goes off
            if not cw & W.CW_VOLTAGE_ENABLE:
                self._power_off(t, W.SWITCH_ON_DISABLED)          # OFF2: at once
                return
            if not cw & W.CW_QUICK_STOP_N:
                if self.controlled and self._moving(t):
                    self._quick_stop(t, "off3")                   # OFF3: quick stop, then current 0
                else:
                    self._power_off(t, W.SWITCH_ON_DISABLED)
                return
            if not on:
                self._power_off(t, W.READY_TO_SWITCH_ON)          # OFF1: current 0 at once
                return
            if s == W.READY_TO_SWITCH_ON:
                self.state = W.HW_TESTS
                self._hw_test_end = t + self.hw_test_ns
                return
            if s == W.HW_TESTS:
                return
            if s == W.READY_TO_OPERATE:
                if not cw & W.CW_ENABLE_OPERATION:
                    return
                self._take_control(t)
                self.state = W.OPERATION_ENABLED
                continue
            # states 8 and above
            if not cw & W.CW_ENABLE_OPERATION:
                # seed 004 3.7: the setpoint generation stops at once (a following error may result)
                self.ct_runner.stop()
                self.gen = Hold(self.gen.at(t)[0])
                self.after_stop = None
                self.state, self.sub = W.READY_TO_OPERATE, 0
                if self.par(P_READY_TO_OPERATE_MODE, 1) == 0:
                    self.controlled = False
                return
            if s == W.OPERATION_ENABLED:
                self._state8(t, cw, rising)
                return
            if s == W.ABORTING:
                if cw & W.CW_ABORT_N:
                    self.state = W.OPERATION_ENABLED      # rests where it stopped until a new command
                return
            if s == W.FREEZING:
                if cw & W.CW_FREEZE_N:
                    self.state = W.OPERATION_ENABLED
                    self._resume_frozen(t)
                return
            if s in W.SPECIAL_STATES:
                if not cw & _SPECIAL_BIT[s]:
                    self._leave_special(t)
                return
            return

    def _state8(self, t: int, cw: int, rising: int) -> None:
        if not cw & W.CW_ABORT_N:
            self.ct_runner.stop()
            self._quick_stop(t, None)
            self.state = W.ABORTING
            return
        if not cw & W.CW_FREEZE_N:
            self.frozen = (self.gen.target, self.gen.vmax, self.gen.acc, self.gen.dec) \
                if self.gen.kind == "vai" and not self.gen.done(t) else None
            self.ct_runner.stop()
            self._quick_stop(t, None)
            self.state = W.FREEZING
            return
        if cw & (W.CW_SPECIAL_MODE | W.CW_PHASE_SEARCH):
            self._fail(W.ERR_MOTION_CMD_WRONG_STATE, t)      # states 19/20 are not on the E1100 (INFERRED code)
            return
        if cw & W.CW_HOME:
            self._enter_special(t, W.HOMING)
        elif cw & W.CW_CLEARANCE_CHECK:
            self._enter_special(t, W.CLEARANCE_CHECK)
        elif rising & W.CW_GO_TO_INITIAL_POSITION:
            self._enter_special(t, W.GOING_TO_INITIAL_POSITION)
        elif cw & W.CW_GO_TO_POSITION:
            self._enter_special(t, W.GOING_TO_POSITION)
        elif cw & W.CW_JOG_PLUS:
            self._enter_special(t, W.JOGGING_PLUS)
        elif cw & W.CW_JOG_MINUS:
            self._enter_special(t, W.JOGGING_MINUS)

    def _take_control(self, t: int) -> None:
        if not self.controlled:
            self.controlled = True
            self.gen = Hold(self.axis.position)           # no jump: the demand starts where the slider is
            self._prev_vd = 0.0
            self._wake(t)

    def _power_off(self, t: int, state: int) -> None:
        self.ct_runner.stop()
        self.controlled = False
        self.after_stop = None
        self.gen = Hold(self.axis.position)
        self._prev_vd = 0.0
        self.state, self.sub = state, 0
        self._hw_test_end = None
        if self.axis.velocity:
            self._wake(t)               # the slider coasts

    def _moving(self, t: int) -> bool:
        return not self.gen.done(t) or abs(self.axis.velocity) > 0

    def _quick_stop(self, t: int, then: str | None) -> None:
        p, v, _ = self.gen.at(t)
        self._start(StopPlan(t, p, v, self.par(P_QUICK_STOP_DEC, 5_000_000) * ACC_RAW))
        self.after_stop = then

    def _start(self, gen) -> None:
        self.gen = gen
        self._in_window_since = None
        self._wake(gen.origin_ns)

    def _resume_frozen(self, t: int) -> None:
        """[MC] 3.13: a frozen VAI motion is finished; after a frozen curve the axis goes to the last VAI target,
        or to the initial position if there was none."""
        p, v, _ = self.gen.at(t)
        if self.frozen is not None:
            self._start(VaPlan(t, p, v, *self.frozen))
        elif self.last_vai is not None:
            self._start(VaPlan(t, p, v, *self.last_vai))
        else:
            self._start(VaPlan(t, p, v, self.par(P_INITIAL_POSITION), *self._predef()))
        self.frozen = None

    # ---- the special states 9, 10, 11, 15, 16, 17 ----
    def _enter_special(self, t: int, state: int) -> None:
        if state != W.HOMING and self.s.motion_requires_homing and not self.homed:
            self._fail(W.ERR_NOT_HOMED, t)
            return
        self.ct_runner.stop()
        self.state, self.sub, self._special_phase = state, 0x01, 1
        p, v, _ = self.gen.at(t)
        hv, ha = self.par(P_HOMING_VMAX) * VEL_RAW, self.par(P_HOMING_ACC) * ACC_RAW
        if state == W.HOMING:
            self.homed = False
            direction = HOMING_SEARCH.get(self.par(P_HOMING_MODE))
            if direction is None:                          # mode 0 and the others: home at the actual position
                self._reference(self.par(P_HOME_POSITION), t)
                self.sub = W.SUB_FINISHED
                return
            far = 4 * (self.s.stop_positive_pu - self.s.stop_negative_pu)
            self._start(VaPlan(t, p, v, p + direction * far, hv, ha, ha))
        elif state == W.CLEARANCE_CHECK:
            self._start(VaPlan(t, p, v, self.par(P_CLEARANCE_1), hv, ha, ha))
        elif state == W.GOING_TO_INITIAL_POSITION:
            self._start(VaPlan(t, p, v, self.par(P_INITIAL_POSITION), hv, ha, ha))
        elif state == W.GOING_TO_POSITION:
            self._start(VaPlan(t, p, v, self.par(P_GO_TO_POSITION), *self._predef()))
        else:
            sign = 1 if state == W.JOGGING_PLUS else -1
            inc = self.par(P_JOG_INCREMENT)
            target = p + sign * abs(inc) if inc else self.par(P_LIMIT_POSITIVE if sign > 0 else P_LIMIT_NEGATIVE)
            _, acc, dec = self._predef()
            self._start(VaPlan(t, p, v, target, self.par(P_JOG_VELOCITY) * VEL_RAW, acc, dec))

    def _progress_special(self, t: int) -> None:
        """Called each cycle in a special state: the next phase once the present one is done."""
        s = self.state
        if self.sub == W.SUB_FINISHED:
            return
        if s == W.HOMING and self._special_phase == 1:
            if abs(self.dem_p - self.axis.position) > self.s.homing_stop_error_pu:
                # on the mechanical stop: the slider's position is the home position from now on
                self._reference(self.par(P_HOME_POSITION), t)
                self.homed = True
                hv, ha = self.par(P_HOMING_VMAX) * VEL_RAW, self.par(P_HOMING_ACC) * ACC_RAW
                self._start(VaPlan(t, self.gen.target, 0.0, self.par(P_INITIAL_POSITION), hv, ha, ha))
                self._special_phase, self.sub = 2, 0x02
            return
        if not self.gen.done(t):
            return
        if s == W.CLEARANCE_CHECK and self._special_phase == 1:
            hv, ha = self.par(P_HOMING_VMAX) * VEL_RAW, self.par(P_HOMING_ACC) * ACC_RAW
            self._start(VaPlan(t, self.gen.target, 0.0, self.par(P_CLEARANCE_2), hv, ha, ha))
            self._special_phase, self.sub = 2, 0x02
            return
        self.sub = W.SUB_FINISHED

    def _leave_special(self, t: int) -> None:
        if self.state == W.HOMING and self.sub != W.SUB_FINISHED:
            self.homed = False                             # homing aborted
        if self._moving(t):
            p, v, _ = self.gen.at(t)
            self._start(StopPlan(t, p, v, self._predef()[2]))
        self.state, self.sub = W.OPERATION_ENABLED, 0

    def _reference(self, home: int, t: int) -> None:
        """Homing: the actual position becomes `home`; the demand jumps with it (no motion)."""
        self.axis.reference(float(home))
        self.gen = Hold(self.axis.position)
        self.dem_p, self.dem_v = self.axis.position, 0.0
        self.homed = True
        self.last_vai = None

    # ---- errors ----
    def _fail(self, code: int, t: int) -> bool:
        """An error: logged; during a motion a quick stop first (state 14), then state 4, power stage off."""
        self._log_error(code, t)
        self.ct_runner.stop()
        self.error_code = code
        self.fatal = code in W.FATAL_ERRORS
        if self.controlled and self._moving(t):
            self._quick_stop(t, "error")
            self.state, self.sub = W.ERROR_QUICK_STOP, 0
        else:
            self._power_off(t, W.ERROR)
        return False

    def block(self, on: bool, t: int) -> None:
        """Test hook: an obstacle holds the slider where it is from t (False: released)."""
        self.sync(t)
        self.axis.block(on)
        self._wake(t)
        self._record(t)

    def push(self, delta_pu: float, t: int) -> None:
        """Test hook: a disturbance moves the slider by delta_pu at t."""
        self.sync(t)
        self.axis.push(delta_pu)
        self._wake(t)
        self._record(t)

    def inject_error(self, code: int, t: int) -> None:
        """Test hook: the drive detects an error now (e.g. a fatal 000Dh over current)."""
        self.sync(t)
        if self.running and self.state not in (W.ERROR, W.SETUP_ERROR):
            self._fail(code, t)
            self._record(t)

    # ------------------------------------------------------------------ the cycle
    def next_timer_ns(self, cycle_sensitive: bool = True) -> int | None:
        """The next cycle, or, where no output needs every cycle (cycle_sensitive False), the first cycle
        after the quiet ones computed ahead."""
        t = self._next_tick
        if t is not None and not cycle_sensitive:
            ahead = self._ahead[-1][0] + self.s.cycle_ns if self._ahead else self.compute_ahead()
            if ahead is not None:
                t = ahead
        if self._hw_test_end is not None and (t is None or self._hw_test_end < t):
            t = self._hw_test_end
        return t

    def on_timer(self, t: int) -> None:
        self._catch_up(t)
        if self._hw_test_end is not None and t >= self._hw_test_end:
            self._hw_test_end = None
            if self.running and self.state == W.HW_TESTS:
                self.state = W.READY_TO_OPERATE
                if self.par(P_READY_TO_OPERATE_MODE, 1) != 0:
                    self._take_control(t)
                self._evaluate(t, self.control_word)
                self._record(t)

    def _wake(self, t: int) -> None:
        """Something will move: run the cycle from the cycle boundary at or before t."""
        if self._next_tick is None:
            cyc = self.s.cycle_ns
            self._last_tick = t // cyc * cyc
            self._next_tick = self._last_tick + cyc
            self._prev_vd = self.gen.at(self._last_tick)[1] if self.controlled else 0.0

    def _catch_up(self, t: int) -> None:
        """Run the cycles up to t: the quiet ones computed ahead or in a tight loop, the others one by one."""
        while self._next_tick is not None and self._next_tick <= t:
            if self._ahead:
                self._apply_ahead(t)
                continue
            if self._plain() and self._quiet_run(t, None):
                continue
            self._cycle(self._next_tick)
        if t > self._now:
            self._now = t

    def observe(self, t: int) -> None:
        """Bring the inspectable state to time t (cycles computed ahead are taken over; nothing changes what
        happens later)."""
        self._catch_up(t)

    def sync(self, t: int) -> None:
        """An input is about to arrive at t (a frame for this drive, a test hook): run to t, forget what was
        computed ahead of it."""
        self._catch_up(t)
        if self._ahead:
            self._ahead, self._ahead_samples = [], []
            self._horizon = 8           # disturbed: look less far ahead next time

    # ---- quiet cycles: plain motion, nothing for the state machine to do ----------------------------
    # A cycle is quiet when the generic _cycle would only move the setpoint and the axis and find every
    # output word (status, state var, warn, error) unchanged. Such cycles run in a tight loop, and, where
    # no event-driven TxPDO depends on them (pdo.cycle_sensitive), ahead of the bus: the drive then asks
    # to be woken only at the first cycle that is not quiet. tests/test_motion_equivalence.py checks that
    # frames and trajectory are the same as with every cycle run one by one.
    lookahead = True
    AHEAD_MAX = 2000                # cycles computed ahead at most; the horizon doubles while undisturbed
    _horizon = 8

    def _plain(self) -> bool:
        return (self.running and self.controlled and self.state in _PLAIN_STATES and self.after_stop is None
                and not self.ct_runner.running and not self.axis.blocked and not self.par(P_RANGE1_UPID)
                and self._next_tick is not None and self.s.quiet_cycles)

    def _quiet_run(self, t_limit: int, entries: list | None = None, samples: list | None = None) -> bool:
        """Commit quiet cycles from the next tick up to t_limit; True when any ran. It stops before the first
        cycle that is not quiet: the generic cycle runs that one. `entries` collects each cycle's state and
        `samples` its trajectory sample (computing ahead); without them the samples go to the trajectory.

        The hottest loop of the model: the demand comes from the plan's `demands` walk, Axis.follow's
        arithmetic is inlined term for term (so every value is bit-identical to the generic cycle's; the
        equivalence tests compare them exactly), the state lives in locals and is written back once."""
        gen, axis, par = self.gen, self.axis, self.par
        cyc, t = self.s.cycle_ns, self._next_tick
        lag_warn, lag_err = par(P_LAG_ALWAYS_WARN, 1 << 31), par(P_LAG_ALWAYS_ERROR, 1 << 31)
        st_warn, st_err = par(P_LAG_STANDING_WARN, 1 << 31), par(P_LAG_STANDING_ERROR, 1 << 31)
        limits = self.homed and par(P_LIMITS_ENABLE)
        lim_neg, lim_pos = par(P_LIMIT_NEGATIVE, -(1 << 31)), par(P_LIMIT_POSITIVE, 1 << 31)
        target_ok = self.state >= W.OPERATION_ENABLED
        window, hold = self.s.in_target_window_pu, self.s.in_target_hold_ns
        gen_target = gen.target
        # `active` (the setpoint generation runs) is the same in every quiet cycle of a run: the first cycle
        # where it changes is not quiet. It is the status word's Motion Active bit as last recorded (_plain
        # excludes a running command table), not the plan at _now: _now may be a later observation time, and
        # a plan that ended between the last cycle and it has not cleared the bit yet (the next cycle does).
        active = bool(self.words[0] & W.SW_MOTION_ACTIVE)
        if active:
            t_limit = min(t_limit, gen.end_ns - 1)      # a run while active ends before the plan's end
        elif t < gen.end_ns:
            return False                                # the plan runs again: the bit comes back
        warn_bits, in_target, since, prev_vd = self.warn_bits, self.in_target, self._in_window_since, self._prev_vd
        if not limits:
            lim_neg, lim_pos = -math.inf, math.inf
        # while active: the warn word has no standing bit, the axis is never in the target window
        if active and (in_target or warn_bits & ~W.WARN_POS_LAG_ALWAYS):
            return False
        # while active, a cycle is quiet when lag_lo < err <= lag_hi (the always-warn bit and error unchanged)
        lag_lo = lag_warn if warn_bits & W.WARN_POS_LAG_ALWAYS else -1.0
        lag_hi = lag_err if warn_bits & W.WARN_POS_LAG_ALWAYS else min(lag_warn, lag_err)
        sw, sv = self.words[0], self.words[1]
        record = self.s.record_trajectory
        to_trajectory = samples is None
        if to_trajectory:
            samples = []
        new_sample = tuple.__new__          # Sample(...) without its Python-level __new__
        add_sample, add_entry = samples.append, entries.append if entries is not None else None
        # Axis.follow, inlined (its constants, then its state in locals)
        h, offset = axis.h, axis.offset
        p00, p01, p10, p11 = axis._phi
        g0, g1 = axis._gam
        one_kff = 1.0 - axis._kff
        stop_neg, stop_pos = axis.s.stop_negative_pu, axis.s.stop_positive_pu
        settle = axis.s.settle_pu
        physical, velocity, acceleration = axis.physical, axis.velocity, axis.acceleration
        p = 0.0
        t0 = t
        for p1, v1 in gen.demands(t, cyc):
            if t > t_limit:
                break
            dv = v1 - prev_vd                           # the same float in both terms: computed once
            e = p1 - dv * h / 2 - prev_vd * h - (physical + offset)
            ed = prev_vd - velocity
            u = one_kff * dv / h
            ph1 = p1 - (p00 * e + p01 * ed + g0 * u) - offset
            if stop_neg <= ph1 <= stop_pos:
                va1 = v1 - (p10 * e + p11 * ed + g1 * u)
                ac1 = (va1 - velocity) / h
            else:                                   # on a mechanical stop: Axis.follow's own path
                axis.physical, axis.velocity, axis.acceleration = physical, velocity, acceleration
                axis.follow(p1, prev_vd, v1)
                ph1, va1, ac1 = axis.physical, axis.velocity, axis.acceleration
            pos = ph1 + offset
            err = p1 - pos                              # abs() without the builtin call (exact for floats)
            if err < 0:
                err = -err
            if active:
                if err <= lag_lo or err > lag_hi or not lim_neg <= pos <= lim_pos:
                    break
                since = None
            else:
                warn = (W.WARN_POS_LAG_ALWAYS if err > lag_warn else 0) | \
                       (W.WARN_POS_LAG_STANDING if err > st_warn else 0)
                in_window = target_ok and abs(gen_target - pos) <= window
                new_since = (t if since is None else since) if in_window else None
                now_in_target = in_window and t - new_since >= hold
                if (warn != warn_bits or err > lag_err or err > st_err or not lim_neg <= pos <= lim_pos
                        or now_in_target != in_target
                        or (not (new_since is not None and not now_in_target)
                            and err < settle and abs(va1) * 1e-3 < settle)):      # Axis.at_rest
                    break
                since = new_since
            physical, velocity, acceleration = ph1, va1, ac1
            p = p1
            prev_vd = v1
            if record:
                add_sample(new_sample(Sample, (t, p1, pos, v1, va1, sv, sw)))
            if entries is not None:
                add_entry((t, ph1, va1, ac1, v1, p1, v1, since))
            t += cyc
        axis.physical, axis.velocity, axis.acceleration = physical, velocity, acceleration
        if to_trajectory:
            self.trajectory.extend(samples)
        if t > t0:
            self.dem_p, self.dem_v, self._last_tick, self._now = p, prev_vd, t - cyc, t - cyc
        self._prev_vd, self._in_window_since, self._next_tick = prev_vd, since, t
        return t > t0

    def compute_ahead(self) -> int | None:
        """With quiet cycles ahead, the first cycle the generic path has to run (the drive's next timer)."""
        if not self._ahead and self.lookahead and self._plain():
            axis = self.axis
            saved = (axis.physical, axis.velocity, axis.acceleration, self._prev_vd, self.dem_p, self.dem_v,
                     self._last_tick, self._next_tick, self._in_window_since, self._now)
            entries: list[tuple] = []
            samples: list[Sample] = []
            self._quiet_run(self._next_tick + (self._horizon - 1) * self.s.cycle_ns, entries, samples)
            self._horizon = min(self._horizon * 2, self.AHEAD_MAX)
            (axis.physical, axis.velocity, axis.acceleration, self._prev_vd, self.dem_p, self.dem_v,
             self._last_tick, self._next_tick, self._in_window_since, self._now) = saved
            self._ahead, self._ahead_samples = entries, samples
        if self._ahead:
            return self._ahead[-1][0] + self.s.cycle_ns
        return None

    def _apply_ahead(self, t: int) -> None:
        """Take over the cycles computed ahead up to t."""
        ahead = self._ahead
        k = bisect_right(ahead, t, key=_CYCLE_TIME)
        if k:
            samples = self._ahead_samples
            if samples:
                self.trajectory.extend(samples[:k])
                del samples[:k]
            (tk, self.axis.physical, self.axis.velocity, self.axis.acceleration, self._prev_vd, self.dem_p,
             self.dem_v, self._in_window_since) = ahead[k - 1]
            self._last_tick, self._next_tick, self._now = tk, tk + self.s.cycle_ns, tk
        del ahead[:k]

    def _cycle(self, t: int) -> None:
        self._now = t
        gen = self.gen
        axis = self.axis
        if self.controlled:
            p, v, _ = gen.at(t)
            axis.follow(p, self._prev_vd, v)
            self._prev_vd = v
        else:
            axis.coast()
            p, v = axis.position, axis.velocity
            self.gen = gen = Hold(p)
            self._prev_vd = 0.0
        self.dem_p, self.dem_v = p, v
        self._last_tick = t
        if self.running:
            if self.controlled:
                self._monitor(t)
            if self.state in W.SPECIAL_STATES:
                self._progress_special(t)
            if self.ct_runner.running:
                self.ct_runner.step(t)
            if self.after_stop is not None and self.gen.done(t):
                then, self.after_stop = self.after_stop, None
                if then == "error":
                    self._power_off(t, W.ERROR)
                elif then == "off3":
                    self._power_off(t, W.SWITCH_ON_DISABLED)
        # keep cycling while anything can still change
        self._update_in_target(t)
        busy = (not self.gen.done(t) or self.ct_runner.running or axis.blocked
                or (self.state in W.SPECIAL_STATES and self.sub != W.SUB_FINISHED)
                or (self._in_window_since is not None and not self.in_target))
        if self.controlled:
            if not busy and axis.at_rest(self.dem_p):
                axis.settle(self.dem_p)
                self._next_tick = None
            else:
                self._next_tick = t + self.s.cycle_ns
        elif axis.velocity != 0 or busy:
            self._next_tick = t + self.s.cycle_ns
        else:
            self._next_tick = None
        self._record(t)

    def _monitor(self, t: int) -> None:
        if self.state == W.ERROR_QUICK_STOP:
            return
        err = abs(self.dem_p - self.axis.position)
        active = not self.gen.done(t)
        homing_search = self.state == W.HOMING and self._special_phase == 1
        warn = 0
        if not homing_search:
            if err > self.par(P_LAG_ALWAYS_WARN, 1 << 31):
                warn |= W.WARN_POS_LAG_ALWAYS
            if not active and err > self.par(P_LAG_STANDING_WARN, 1 << 31):
                warn |= W.WARN_POS_LAG_STANDING
        self.warn_bits = warn
        if homing_search:
            return
        if err > self.par(P_LAG_ALWAYS_ERROR, 1 << 31):
            self._fail(W.ERR_POS_LAG_ALWAYS, t)
        elif not active and err > self.par(P_LAG_STANDING_ERROR, 1 << 31):
            self._fail(W.ERR_POS_LAG_STANDING, t)
        elif self.homed and self.par(P_LIMITS_ENABLE) and self.state != W.HOMING:
            x = self.axis.position
            if x < self.par(P_LIMIT_NEGATIVE, -(1 << 31)):
                self._fail(W.ERR_MIN_POS_UNDERSHOT, t)
            elif x > self.par(P_LIMIT_POSITIVE, 1 << 31):
                self._fail(W.ERR_MAX_POS_OVERSHOT, t)

    def _update_in_target(self, t: int) -> None:
        if not (self.running and self.controlled and self.state >= W.OPERATION_ENABLED
                and self.state != W.ERROR_QUICK_STOP and self.gen.done(t)
                and abs(self.gen.target - self.axis.position) <= self.s.in_target_window_pu):
            self._in_window_since = None
            self.in_target = False
            return
        if self._in_window_since is None:
            self._in_window_since = t
        self.in_target = t - self._in_window_since >= self.s.in_target_hold_ns

    # ------------------------------------------------------------------ outputs
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
        if s in W.SPECIAL_STATES and self.sub != W.SUB_FINISHED:
            bits |= W.SW_SPECIAL_MOTION
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
        upid = self.par(P_RANGE1_UPID)
        lo, hi = self.par(P_RANGE1_MIN), self.par(P_RANGE1_MAX)
        if not upid or lo > hi:
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
        p = self._pars.get(P_SCALE_POS)
        scale = 1000 if p is None else p.ram
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
        return None

    def _record(self, t: int) -> None:
        """After an event or a cycle: the outputs are brought up to date, the trajectory gets a sample."""
        self._update_in_target(t)
        warn = self._warn_word()
        sw, sv = self._status_word(warn), self._state_var()
        self.words = (sw, sv, self.error_code if self.running else 0, warn)
        if self.s.record_trajectory:
            self.trajectory.add(Sample(t, self.dem_p, self.axis.position, self.dem_v, self.axis.velocity, sv, sw))


_SPECIAL_BIT = {W.HOMING: W.CW_HOME, W.CLEARANCE_CHECK: W.CW_CLEARANCE_CHECK,
                W.GOING_TO_INITIAL_POSITION: W.CW_GO_TO_INITIAL_POSITION, W.GOING_TO_POSITION: W.CW_GO_TO_POSITION,
                W.JOGGING_PLUS: W.CW_JOG_PLUS, W.JOGGING_MINUS: W.CW_JOG_MINUS}
