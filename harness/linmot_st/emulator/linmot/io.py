"""The drive's I/O as a machine wires it: the X4 digital inputs and outputs, the analog input X4.4, the X6
outputs ([MC] 7.2; seed 004 7.2). Sans-I/O like the drive: a level changes at a virtual time.

    io = drive.io
    io.set_input("X4.6", 1, t_ns)              # the trigger input rises at t_ns (now or later)
    io.pulse_train("X4.6", t0, period_ns, width_ns, count)
    io.analog_ramp(t0, t1, 0.0, 10.0, steps)   # volts on X4.4
    io.input("X4.6"); io.analog(); io.output("X4.3"); io.outputs("X4")

Pins ([MC] 7.2 table): X4.3 brake / output, X4.4 analog in, X4.5 capture input, X4.6 trigger input, X4.7 home
switch, X4.8 limit switch IN (negative), X4.9 limit switch OUT (positive), X4.10/X4.11 PTC, X4.12 SVE. Outputs
X4.3..X4.11 are written by 003xh (bit 0 = X4.3, [MC] 4.3.4); X6.0..X6.15 by 004xh (seed 004 TOC; layout
INFERRED as 003xh's). X6.0..X6.15 are also inputs (the IF commands compare "X6 inputs"; 16 bits INFERRED).

The trigger input is conditioned as [MC] 7.2.2 says (mode 170Ch: none, direct, inhibited 170Dh/170Eh,
delayed 170Fh/1710h, inhibited & delayed); the conditioned edges ("trigger out") go to the listeners (the MC's
event handler). A rising edge on X4.5 captures the actual position (variable 1E62h; INFERRED edge).
Every level change is recorded in `changes`: on a drive, the MC's trajectory record (`trajectory.io`,
`trajectory.io_at(name, t_ns)`).
"""

from __future__ import annotations

import heapq
import itertools
from collections.abc import Callable
from dataclasses import dataclass, replace
from typing import NamedTuple

from ...protocol.upids import (
    P_TRIG_FALL_DELAY,
    P_TRIG_FALL_INHIBIT,
    P_TRIG_RISE_DELAY,
    P_TRIG_RISE_INHIBIT,
    P_TRIGGER_MODE,
)

X4_INPUTS = tuple(f"X4.{n}" for n in range(3, 13))       # any X4 pin can be read (general purpose IO)
X4_OUTPUTS = tuple(f"X4.{n}" for n in range(3, 12))      # 003xh: bit 0 = X4.3 .. bit 8 = X4.11
X6_OUTPUTS = tuple(f"X6.{n}" for n in range(16))         # 004xh: bit n = X6.n (INFERRED)
X6_INPUTS = X6_OUTPUTS                                   # the X6 inputs the IF commands read (INFERRED: 16 bits)
TRIGGER, CAPTURE, ANALOG = "X4.6", "X4.5", "X4.4"
LIMIT_IN, LIMIT_OUT = "X4.8", "X4.9"

# trigger modes, 170Ch ([MC] 7.2.2)
MODE_NONE, MODE_DIRECT, MODE_INHIBITED, MODE_DELAYED, MODE_INHIBITED_DELAYED = range(5)


@dataclass(frozen=True)
class IoSettings:
    """The I/O choices no source fixes (docs/emulator.md, 'The drive's I/O'); every default INFERRED."""
    # unit of the trigger inhibit and delay times 170Dh..1710h ([MC] 7.2.2 gives none): 100 us, the time base
    # of the command table's Wait Time (210xh)
    trigger_time_unit_ns: int = 100_000
    # X4.8/X4.9 as limit switches ([MC] 7.2.3: "if ... a limit switch is defined"; no UPID names the
    # definition): active (1) = the switch is reached
    limit_switches: bool = True
    # X4.5 captures the actual position on this edge of its input: "rise" or "fall"
    capture_edge: str = "rise"
    # the analog input's range in volts (X4.4: 0..10 V)
    analog_min_v: float = 0.0
    analog_max_v: float = 10.0

    def with_(self, **changes) -> IoSettings:
        return replace(self, **changes)


class IoChange(NamedTuple):
    t_ns: int
    name: str           # a pin ("X4.6"), "X4.4" for the analog value, "trigger" for the conditioned trigger
    value: float


class DriveIO:
    def __init__(self, settings: IoSettings | None = None, par: Callable[[int, int], int] | None = None):
        self.s = settings or IoSettings()
        self.par = par or (lambda upid, default=0: default)
        self.levels: dict[str, int] = {n: 0 for n in X4_INPUTS + X6_INPUTS}
        self.out_x4 = 0                  # output bits, bit 0 = X4.3
        self.out_x6 = 0
        self.analog_v = 0.0
        self.trigger_out = 0             # the conditioned trigger signal [MC] 7.2.2 ("trigger out")
        self.changes: list[IoChange] = []
        # who reacts, each called with the time: (name, level, t) before a level changes (the MC syncs to t),
        # trigger edges (rising, t), captures (t) -> the position to hold
        self.before_change: Callable[[int], None] = lambda t: None
        self.on_trigger: Callable[[bool, int], None] = lambda rising, t: None
        self.on_capture: Callable[[int], int | None] = lambda t: None
        self.on_level: Callable[[str, int, int], None] = lambda name, level, t: None
        self.on_analog: Callable[[float, int], None] = lambda volts, t: None
        # X4.3 as brake output ([MC] 7.2.1.1, 1717h): its level from the MC, None when X4.3 is no brake
        self.brake: Callable[[], int | None] = lambda: None
        self.captured_position = 0
        self._inhibit_until = -1         # [MC] 7.2.2.2: further edges ignored until then
        self._inhibit_level = 0          # the inhibited signal
        self._events: list[tuple[int, int, Callable[[int], None]]] = []
        self._seq = itertools.count()
        self.now_ns = 0
        self.clock: Callable[[], int] = lambda: self.now_ns    # the drive's time (the drive sets it)

    # ------------------------------------------------------------------ reading
    def input(self, name: str) -> int:
        """The level (0/1) of a digital input now (as of the last event the drive processed)."""
        return self.levels[_pin(name, X4_INPUTS + X6_INPUTS)]

    def analog(self) -> float:
        """The voltage on X4.4."""
        return self.analog_v

    def analog_fraction(self) -> float:
        """X4.4 in its range, 0.0 .. 1.0 (clamped)."""
        lo, hi = self.s.analog_min_v, self.s.analog_max_v
        return min(max((self.analog_v - lo) / (hi - lo), 0.0), 1.0)

    def output(self, name: str) -> int:
        if name in X6_OUTPUTS:
            return self.out_x6 >> X6_OUTPUTS.index(name) & 1
        return self.outputs("X4") >> X4_OUTPUTS.index(_pin(name, X4_OUTPUTS)) & 1

    def outputs(self, connector: str = "X4") -> int:
        """The output word of a connector: X4 (bit 0 = X4.3) or X6 (bit n = X6.n). X4.3 configured as brake
        output follows the MC (1 = 24 V, released), not 003xh."""
        if connector == "X6":
            return self.out_x6
        if connector != "X4":
            raise KeyError(connector)
        brake = self.brake()
        return self.out_x4 if brake is None else (self.out_x4 & ~1) | brake

    def input_word(self, connector: str = "X4") -> int:
        """The input levels of a connector as a word: X4 bit 0 = X4.3 (the outputs' numbering), X6 bit n = X6.n
        (what the command table's masked IF commands compare)."""
        pins = {"X4": X4_INPUTS, "X6": X6_INPUTS}[connector]
        return sum(self.levels[n] << i for i, n in enumerate(pins))

    # ------------------------------------------------------------------ writing (tests, rig, CLI)
    def set_input(self, name: str, level: int, t_ns: int | None = None) -> None:
        """A digital input changes to `level` at t_ns (default: now); a time in the future is scheduled."""
        pin = _pin(name, X4_INPUTS + X6_INPUTS)
        if pin == ANALOG:
            raise ValueError("X4.4 is the analog input: use set_analog(volts, t_ns)")
        self._schedule(t_ns, lambda t: self._apply(pin, 1 if level else 0, t))

    def set_analog(self, volts: float, t_ns: int | None = None) -> None:
        self._schedule(t_ns, lambda t: self._apply_analog(float(volts), t))

    def play(self, name: str, signal: list[tuple[int, float]]) -> None:
        """A signal: (t_ns, level) pairs for a digital input, (t_ns, volts) for X4.4."""
        for t, v in signal:
            if name == ANALOG:
                self.set_analog(v, t)
            else:
                self.set_input(name, int(v), t)

    def pulse_train(self, name: str, t0_ns: int, period_ns: int, width_ns: int, count: int) -> None:
        """`count` pulses (high for width_ns) every period_ns from t0_ns."""
        if not 0 < width_ns < period_ns:
            raise ValueError("a pulse needs 0 < width < period")
        self.play(name, [e for k in range(count)
                         for e in ((t0_ns + k * period_ns, 1), (t0_ns + k * period_ns + width_ns, 0))])

    def analog_ramp(self, t0_ns: int, t1_ns: int, v0: float, v1: float, steps: int = 100) -> None:
        """A ramp on X4.4 from v0 at t0 to v1 at t1, in `steps` equal steps (the ADC samples a staircase)."""
        steps = max(int(steps), 1)
        self.play(ANALOG, [(t0_ns + (t1_ns - t0_ns) * k // steps, v0 + (v1 - v0) * k / steps)
                           for k in range(steps + 1)])

    def write_outputs(self, connector: str, mask: int, value: int, t_ns: int) -> None:
        """003xh (X4) / 004xh (X6): only the bits set in mask change ([MC] 4.3.4)."""
        width = len(X4_OUTPUTS) if connector == "X4" else len(X6_OUTPUTS)
        names = X4_OUTPUTS if connector == "X4" else X6_OUTPUTS
        mask &= (1 << width) - 1
        old = self.outputs(connector)
        new = (old & ~mask) | (value & mask)
        if connector == "X4":
            self.out_x4 = new
        else:
            self.out_x6 = new
        for i, n in enumerate(names):
            if (old ^ new) >> i & 1:
                self._record(t_ns, n, new >> i & 1)

    # ------------------------------------------------------------------ timers (the drive calls these)
    def next_timer_ns(self) -> int | None:
        return self._events[0][0] if self._events else None

    def on_timer(self, t_ns: int) -> None:
        while self._events and self._events[0][0] <= t_ns:
            t, _, fn = heapq.heappop(self._events)
            self.now_ns = max(self.now_ns, t)
            fn(t)

    # ------------------------------------------------------------------ internals
    def _schedule(self, t_ns: int | None, fn: Callable[[int], None]) -> None:
        now = max(self.clock(), self.now_ns)
        t = now if t_ns is None else int(t_ns)
        if t < now:
            raise ValueError(f"t_ns {t} is before the drive's time {now}")
        heapq.heappush(self._events, (t, next(self._seq), fn))

    def _record(self, t: int, name: str, value: float) -> None:
        self.changes.append(IoChange(t, name, value))

    def _apply(self, pin: str, level: int, t: int) -> None:
        old = self.levels[pin]
        if old == level:
            return
        self.before_change(t)
        self.levels[pin] = level
        self._record(t, pin, level)
        self.on_level(pin, level, t)
        if pin == TRIGGER:
            self._trigger_in(level, t)
        if pin == CAPTURE and level == (1 if self.s.capture_edge == "rise" else 0):
            pos = self.on_capture(t)
            if pos is not None:
                self.captured_position = pos

    def _apply_analog(self, volts: float, t: int) -> None:
        if volts == self.analog_v:
            return
        self.before_change(t)
        self.analog_v = volts
        self._record(t, ANALOG, volts)
        self.on_analog(volts, t)

    def _time(self, upid: int) -> int:
        return self.par(upid, 0) * self.s.trigger_time_unit_ns

    def _trigger_in(self, level: int, t: int) -> None:
        """A raw edge on X4.6 through the trigger mode ([MC] 7.2.2.1..4)."""
        mode = self.par(P_TRIGGER_MODE, MODE_NONE)
        if mode == MODE_NONE:
            return
        if mode in (MODE_INHIBITED, MODE_INHIBITED_DELAYED):
            if t < self._inhibit_until:
                return                       # the signal is taken again when the inhibit time ends
            self._inhibited(level, t, mode)
        else:
            self._delay(level, t, mode)

    def _inhibited(self, level: int, t: int, mode: int) -> None:
        """The debounced signal changes at t; for the inhibit time after it further edges are ignored, then the
        input's level then is taken (INFERRED: a level that changed meanwhile is not lost)."""
        if level == self._inhibit_level:
            return
        self._inhibit_level = level
        self._inhibit_until = t + self._time(P_TRIG_RISE_INHIBIT if level else P_TRIG_FALL_INHIBIT)
        self._delay(level, t, mode)
        if self._inhibit_until > t:
            self._schedule(self._inhibit_until, lambda te: self._inhibit_end(te, mode))

    def _inhibit_end(self, t: int, mode: int) -> None:
        if self.par(P_TRIGGER_MODE, MODE_NONE) == mode and self.levels[TRIGGER] != self._inhibit_level:
            self._inhibited(self.levels[TRIGGER], t, mode)

    def _delay(self, level: int, t: int, mode: int) -> None:
        delay = 0
        if mode in (MODE_DELAYED, MODE_INHIBITED_DELAYED):
            delay = self._time(P_TRIG_RISE_DELAY if level else P_TRIG_FALL_DELAY)
        if delay:
            self._schedule(t + delay, lambda te: self._trigger_out(level, te))
        else:
            self._trigger_out(level, t)

    def _trigger_out(self, level: int, t: int) -> None:
        if level == self.trigger_out:
            return
        self.before_change(t)
        self.trigger_out = level
        self._record(t, "trigger", level)
        self.on_trigger(bool(level), t)


def _pin(name: str, known: tuple[str, ...]) -> str:
    if name not in known:
        raise KeyError(f"{name!r}: not a pin here ({known[0]} .. {known[-1]})")
    return name
