"""MotionControl: the MC software of the emulated E1100 (seed 004 chapters 3-5, [MC] chapters 3-6, 10).

It holds the main state machine (driven by the control word; state_machine.py), the motion command
interpreter (driven by the motion command image that the PDOs fill; interpreter.py), the setpoint generator in
use, the axis, the monitors (following error, position limits, in target position) and the outputs
(status.py); quiet cycles run in the fast path (fast_path.py). This module holds the state, the inputs and the
cycle. Sans-I/O like the drive: events come in with their time (`set_control_word`, `command_image`), and the
cycle runs from `on_timer` at `next_timer_ns()`, once per MC cycle while anything moves and not at all while
the axis rests. The drive reads the outputs (status word, state var, logged error, warn word, positions) after
each call and publishes them in its TxPDOs and variables.

Every behaviour that no source states is marked INFERRED here and listed in docs/emulator.md section 13.
"""

from __future__ import annotations

from collections.abc import Callable

from ....protocol import commands as C
from ....protocol import words as W
from ....protocol.upids import (
    P_CW_COPY_MASK,
    P_CW_FORCE_MASK,
    P_CW_FORCE_VALUES,
    P_LAG_ALWAYS_ERROR,
    P_LAG_ALWAYS_WARN,
    P_LAG_STANDING_ERROR,
    P_LAG_STANDING_WARN,
    P_LIMIT_NEGATIVE,
    P_LIMIT_POSITIVE,
    P_LIMITS_ENABLE,
    P_RANGE1_UPID,
    P_READY_TO_OPERATE_MODE,
    P_SCALE_POS,
)
from ..master_encoder import MasterEncoder
from . import triggered  # noqa: F401 (registers the I/O and triggered commands' handlers)
from .axis import Axis
from .ct_runner import CtRunner
from .events import EventHandler
from .fast_path import FastPath
from .interpreter import Interpreter
from .pending import PendingMotions
from .setpoints import Hold
from .settings import MotionSettings
from .state_machine import StateMachine
from .status import StatusWords
from .stream import check as stream_check
from .trajectory import Sample, Trajectory


class _Absent:
    """A parameter the drive does not have, as MotionControl.ref gives it: par()'s default as its RAM value."""
    __slots__ = ("ram",)

    def __init__(self, ram: int):
        self.ram = ram


class MotionControl(Interpreter, StateMachine, FastPath, StatusWords):
    def __init__(self, settings: MotionSettings, hw_test_ns: int, params, curves, ct,
                 log_error: Callable[[int, int], None]):
        self.s = settings
        self.hw_test_ns = hw_test_ns
        self.params, self.curves, self.ct = params, curves, ct
        self._pars = params.by_upid
        # the parameters read in every cycle and record (_monitor, _quiet_run, _plain, the status word, TxPDO2):
        # lag warn/error always and standing, limits enable/negative/positive, range 1's UPID, position scale
        self._lag = (self.ref(P_LAG_ALWAYS_WARN, 1 << 31), self.ref(P_LAG_ALWAYS_ERROR, 1 << 31),
                     self.ref(P_LAG_STANDING_WARN, 1 << 31), self.ref(P_LAG_STANDING_ERROR, 1 << 31))
        self._limits = (self.ref(P_LIMITS_ENABLE), self.ref(P_LIMIT_NEGATIVE, -(1 << 31)),
                        self.ref(P_LIMIT_POSITIVE, 1 << 31))
        self._range1, self._scale_pos = self.ref(P_RANGE1_UPID), self.ref(P_SCALE_POS, 1000)
        self.words = (0, 0, 0, 0)          # status word, state var, logged error, warn word: set by _record
        self._log_error = log_error
        self.axis = Axis(settings)
        self.trajectory = Trajectory()
        self.executed: list[tuple[int, int, bytes]] = []   # (t_ns, header, parameters) of every command run
        self.ct_runner = CtRunner(self)
        self.encoder = MasterEncoder(self.par, self.sync)      # the master encoder input ([MC] 7.3)
        self.trajectory.master_encoder = self.encoder
        self.events = EventHandler(self)
        self.io = None                      # the drive's I/O (emulator/linmot/io.py), set by the drive
        self.pending = PendingMotions()           # the queued motion and position transition (pending.py)
        self.on_reset: Callable[[int], None] | None = None   # 00Fxh: the drive restarts (set by the drive)
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
        self._encoder_cams = None                # cam definitions (encoder_cams.py): RAM, lost here (INFERRED)
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
        self.events.clear()
        self.pending.clear()
        self.current_limited = False             # a With Max Curr command ran: the axis limits its current
        self.axis.current_limit_ma = None

    # ------------------------------------------------------------------ parameters
    def par(self, upid: int, default: int = 0) -> int:
        """The RAM value of a parameter (default where the drive has no such UPID)."""
        p = self._pars.get(upid)
        return default if p is None else p.ram

    def ref(self, upid: int, default: int = 0):
        """The parameter itself: its `.ram` is par(upid, default) at any later time, read without par()'s call
        where it is read every cycle. The store keeps one Parameter object per UPID for the drive's life (writes
        change its `ram`); a UPID the drive does not have gives a stand-in that holds the default."""
        p = self._pars.get(upid)
        return _Absent(default) if p is None else p

    # ------------------------------------------------------------------ MC software start / stop
    def start(self, t: int, motor_defined: bool) -> int | None:
        """MC start (boot, 36h): returns an error code to log when the configuration is unusable."""
        self.sync(t)
        self._now = t
        self.running = True
        self._reset_state()
        self.ct_runner.clear_variables()          # RAM of the MC: 0 at every MC start (INFERRED)
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
        if self.s.interface_command_ends_sequence:
            self.ct_runner.stop()   # a command from the interface ends a running command-table sequence
        self.execute(header, params, t)
        self._record(t)


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
        # the bus calls this for every drive after each of its runs, and mostly no cycle is due: then
        # _catch_up would only move _now, done here without its call
        tick = self._next_tick
        if tick is not None and tick <= t:
            self._catch_up(t)
        elif t > self._now:
            self._now = t

    def sync(self, t: int) -> None:
        """An input is about to arrive at t (a frame for this drive, a test hook): run to t, forget what was
        computed ahead of it."""
        self._catch_up(t)
        if self._ahead:
            self._ahead, self._ahead_samples = [], []
            self._horizon = 8           # disturbed: look less far ahead next time

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
        if self.pending.armed:
            self.pending.step(self, t)
        if self.running:
            if self.controlled:
                self._monitor(t)
            if self.state in W.SPECIAL_STATES:
                self._progress_special(t)
            if self.events.pending:
                self.events.step(t)
            if self.ct_runner.running:
                self.ct_runner.step(t)
            if self.controlled and self.gen.kind == "stream":
                stream_check(self, t)      # underflow, a master too slow
            if self.after_stop is not None and self.gen.done(t):
                then, self.after_stop = self.after_stop, None
                if then == "error":
                    self._power_off(t, W.ERROR)
                elif then == "off3":
                    self._power_off(t, W.SWITCH_ON_DISABLED)
        # keep cycling while anything can still change
        self._update_in_target(t)
        busy = (not self.gen.done(t) or self.ct_runner.running or axis.blocked or self.events.pending
                or self.pending.armed
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
        lag_warn, lag_err, standing_warn, standing_err = self._lag
        warn = 0
        if not homing_search:
            if err > lag_warn.ram:
                warn |= W.WARN_POS_LAG_ALWAYS
            if not active and err > standing_warn.ram:
                warn |= W.WARN_POS_LAG_STANDING
        self.warn_bits = warn
        if homing_search:
            return
        enabled, negative, positive = self._limits
        if err > lag_err.ram:
            self._fail(W.ERR_POS_LAG_ALWAYS, t)
        elif not active and err > standing_err.ram:
            self._fail(W.ERR_POS_LAG_STANDING, t)
        elif self.homed and enabled.ram and self.state != W.HOMING:
            x = self.axis.position
            if x < negative.ram:
                self._fail(W.ERR_MIN_POS_UNDERSHOT, t)
            elif x > positive.ram:
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
