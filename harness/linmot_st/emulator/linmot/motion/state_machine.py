"""The MC software's main state machine (seed 004 chapter 3, [MC] chapter 3): the control word's transitions,
the special states (homing, clearance check, going to initial position / to position, jogging), the stops and
the error reaction. A part of MotionControl (control.py); INFERRED behaviour is listed in docs/emulator.md
section 13.
"""

from __future__ import annotations

from ....protocol import words as W
from ....protocol.upids import (
    P_CLEARANCE_1,
    P_CLEARANCE_2,
    P_GO_TO_POSITION,
    P_HOME_POSITION,
    P_HOMING_ACC,
    P_HOMING_MODE,
    P_HOMING_VMAX,
    P_INITIAL_POSITION,
    P_JOG_INCREMENT,
    P_JOG_VELOCITY,
    P_LIMIT_NEGATIVE,
    P_LIMIT_POSITIVE,
    P_QUICK_STOP_DEC,
    P_READY_TO_OPERATE_MODE,
)
from .setpoints import Hold, StopPlan, VaPlan
from .units import ACC_RAW, VEL_RAW

# homing modes (1500h; the PVL example's "3: Mech Stop Negative Search"; the others INFERRED)
HOMING_SEARCH = {2: +1, 3: -1, 4: +1, 5: -1}       # mech stop / home switch, positive / negative search


class StateMachine:
    """The main states and their transitions (a mixin of MotionControl: it reads and sets its state)."""

    special_mode = False        # state 20 on control word bit 10 (the B1100's; b1100.py sets it)

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
            if s == W.SPECIAL_MODE and not cw & W.CW_SPECIAL_MODE:
                self._take_control(t)
                self.state = W.OPERATION_ENABLED
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
        if cw & W.CW_SPECIAL_MODE and self.special_mode:
            # B1100 (seed 004 3.20, 3.22): current from the analog input, which the emulation has not: current 0,
            # the position uncontrolled (INFERRED, docs/emulator.md 14.3); back to 8 when bit 10 drops
            self.ct_runner.stop()
            self.gen = Hold(self.gen.at(t)[0])
            self.controlled = False
            self.state, self.sub = W.SPECIAL_MODE, 0
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
        self.events.clear()
        self.error_code = code
        self.fatal = code in W.FATAL_ERRORS
        if self.controlled and self._moving(t):
            self._quick_stop(t, "error")
            self.state, self.sub = W.ERROR_QUICK_STOP, 0
        else:
            self._power_off(t, W.ERROR)
        return False


_SPECIAL_BIT = {W.HOMING: W.CW_HOME, W.CLEARANCE_CHECK: W.CW_CLEARANCE_CHECK,
                W.GOING_TO_INITIAL_POSITION: W.CW_GO_TO_INITIAL_POSITION, W.GOING_TO_POSITION: W.CW_GO_TO_POSITION,
                W.JOGGING_PLUS: W.CW_JOG_PLUS, W.JOGGING_MINUS: W.CW_JOG_MINUS}
