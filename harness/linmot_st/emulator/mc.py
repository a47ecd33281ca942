"""A minimal model of the motion control (MC) software: running or stopped, and its main state machine driven
by the control word (seeds 004 chapter 3), enough for status word, state var and warn word to behave like a
drive's. No motion: the position stays 0 and motion commands are not interpreted.
"""

from __future__ import annotations

# main states (state var high byte)
NOT_READY_TO_SWITCH_ON, SWITCH_ON_DISABLED, READY_TO_SWITCH_ON, SETUP_ERROR, ERROR, HW_TESTS = 0, 1, 2, 3, 4, 5
READY_TO_OPERATE, OPERATION_ENABLED = 6, 8

ERR_NO_MOTOR_DEFINED = 0x64     # "Cfg Err: No Motor Defined" ([CO1100] 11.4)

CW_SWITCH_ON, CW_VOLTAGE_ENABLE, CW_QUICK_STOP_N, CW_ENABLE_OPERATION = 0x0001, 0x0002, 0x0004, 0x0008
CW_ERROR_ACK = 0x0080

WARN_MOTOR_NOT_HOMED = 0x0080


class MotionControl:
    def __init__(self, hw_test_ns: int = 300_000_000):
        self.hw_test_ns = hw_test_ns
        self.running = False
        self.state = NOT_READY_TO_SWITCH_ON
        self.control_word = 0
        self.error_code = 0
        self._hw_test_end: int | None = None

    def start(self, t_ns: int, motor_defined: bool) -> int | None:
        """MC software start; returns an error code to log when the configuration is not usable."""
        self.running = True
        self._hw_test_end = None
        if not motor_defined:
            self.state, self.error_code = SETUP_ERROR, ERR_NO_MOTOR_DEFINED
            return ERR_NO_MOTOR_DEFINED
        self.state = NOT_READY_TO_SWITCH_ON
        self._evaluate(t_ns, 0)
        return None

    def stop(self) -> None:
        self.running = False
        self.state = NOT_READY_TO_SWITCH_ON
        self._hw_test_end = None

    def set_control_word(self, cw: int, t_ns: int) -> bool:
        """A new control word (RxPDO1); returns True when status or state changed."""
        before = self.outputs()
        old, self.control_word = self.control_word, cw & 0xFFFF
        if self.running:
            self._evaluate(t_ns, old)
        return self.outputs() != before

    def next_timer_ns(self) -> int | None:
        return self._hw_test_end

    def on_timer(self, t_ns: int) -> bool:
        if self._hw_test_end is not None and t_ns >= self._hw_test_end and self.state == HW_TESTS:
            self._hw_test_end = None
            self.state = READY_TO_OPERATE
            self._evaluate(t_ns, self.control_word)
            return True
        return False

    def _evaluate(self, t_ns: int, old_cw: int) -> None:
        cw = self.control_word
        power = cw & (CW_VOLTAGE_ENABLE | CW_QUICK_STOP_N) == CW_VOLTAGE_ENABLE | CW_QUICK_STOP_N
        on = bool(cw & CW_SWITCH_ON)
        for _ in range(6):              # settle: a control word can pass several states at once
            s = self.state
            if s == SETUP_ERROR:
                return
            if s == ERROR:
                if cw & CW_ERROR_ACK and not old_cw & CW_ERROR_ACK:
                    self.state = NOT_READY_TO_SWITCH_ON
                else:
                    return
            elif s == NOT_READY_TO_SWITCH_ON:
                if on:
                    return
                self.state = SWITCH_ON_DISABLED
            elif s == SWITCH_ON_DISABLED:
                if not power or on:
                    return
                self.state = READY_TO_SWITCH_ON
            elif not power:
                self.state, self._hw_test_end = SWITCH_ON_DISABLED, None
            elif s == READY_TO_SWITCH_ON:
                if not on:
                    return
                self.state, self._hw_test_end = HW_TESTS, t_ns + self.hw_test_ns
                return
            elif not on:
                self.state, self._hw_test_end = READY_TO_SWITCH_ON, None
            elif s == HW_TESTS:
                return
            elif s == READY_TO_OPERATE:
                if not cw & CW_ENABLE_OPERATION:
                    return
                self.state = OPERATION_ENABLED
            elif s == OPERATION_ENABLED:
                if cw & CW_ENABLE_OPERATION:
                    return
                self.state = READY_TO_OPERATE
            if self.state == s:
                return

    # ---- the words the drive publishes (TxPDO1, variables 1D51h 1B62h 1D8Eh 1D96h) ----
    @property
    def warn_word(self) -> int:
        return WARN_MOTOR_NOT_HOMED if self.running and self.state != SETUP_ERROR else 0

    @property
    def status_word(self) -> int:
        if not self.running:
            return 0
        cw, s = self.control_word, self.state
        bits = 0
        bits |= 0x0001 if s >= OPERATION_ENABLED else 0
        bits |= 0x0002 if cw & CW_SWITCH_ON else 0
        bits |= 0x0004 if cw & CW_ENABLE_OPERATION else 0
        bits |= 0x0008 if s in (SETUP_ERROR, ERROR) else 0
        bits |= 0x0010 if cw & CW_VOLTAGE_ENABLE else 0
        bits |= 0x0020 if cw & CW_QUICK_STOP_N else 0
        bits |= 0x0040 if s == NOT_READY_TO_SWITCH_ON else 0
        bits |= 0x0080 if self.warn_word else 0
        return bits

    @property
    def state_var(self) -> int:
        if not self.running:
            return 0
        low = self.error_code if self.state in (SETUP_ERROR, ERROR) else 0
        return self.state << 8 | low

    def outputs(self) -> tuple[int, int, int, int]:
        return self.status_word, self.state_var, self.error_code, self.warn_word
