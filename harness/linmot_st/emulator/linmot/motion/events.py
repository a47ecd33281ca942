"""The MC's event handler ([MC] 4.3.6; seed 004 3.8, 3.23) and its reactions to the drive's inputs
(emulator/linmot/io.py): a part of MotionControl (control.py), reached as `mc.events`.

- A command "On Rising/Falling Trigger Event" arms the handler (status word bit 8, state var bit 4 in state 8)
  with an action; every matching edge of the conditioned trigger signal runs it again ([MC] 4.3.6: "restarted
  each time the event condition is fulfilled") until 008xh clears the handler. A newer triggered command
  replaces the armed one (INFERRED: the handler holds one command).
- The MC samples the trigger in its cycle: an edge at t runs the action in the first MC cycle after t (within
  one cycle, never before the edge).
- The command table's waits for an edge (213xh/214xh) see the edges too (`edge_since`).
- The limit switches X4.8/X4.9 ([MC] 7.2.3): on a powered, homed motor an active switch raises 0087h / 0088h
  with the behaviour 121Bh says (0 none, 1 power off, 2 quick stop) and clears the homed bit.

INFERRED (docs/emulator.md, 'The drive's I/O'): edges outside state 8 run nothing; an error, leaving state 8
with the MC stopped, and an MC restart clear the handler; a limit switch acts on its rising edge only.
"""

from __future__ import annotations

from collections.abc import Callable

from ....protocol import words as W
from ....protocol.upids import P_LIMIT_SWITCH_ERROR

LIMIT_ERRORS = {"X4.8": 0x0087, "X4.9": 0x0088}     # [MC] 10: Limit Switch In / Out High
Action = Callable[[int], bool]                       # run at t: False when it raised an error


class EventHandler:
    def __init__(self, mc):
        self.mc = mc
        self.armed: tuple[bool, Action] | None = None    # (rising, action)
        self.pending: list[tuple[bool, int]] = []         # edges not yet seen by an MC cycle: (rising, t)
        self.last_edge: dict[bool, int] = {}              # rising -> time of the last edge
        self.fired: list[int] = []                        # times the armed action ran (tests, reports)
        self.follow: Callable[[int], None] | None = None  # 019xh following X4.4 (MotionSettings)

    @property
    def active(self) -> bool:
        return self.armed is not None

    def arm(self, rising: bool, action: Action) -> None:
        self.armed = (rising, action)

    def clear(self) -> None:
        self.armed = None
        self.pending.clear()
        self.follow = None

    def on_analog(self, t: int) -> None:
        if self.follow is not None:
            self.follow(t)

    def edge_since(self, rising: bool, t: int) -> bool:
        """An edge of this direction at or after t (command-table waits)."""
        return self.last_edge.get(rising, -1) >= t

    # ------------------------------------------------------------------ from the I/O (after mc.sync(t))
    def on_trigger(self, rising: bool, t: int) -> None:
        self.last_edge[rising] = t
        if self.armed is not None and self.armed[0] == rising:
            self.pending.append((rising, t))
            self.mc._wake(t)

    def on_limit_switch(self, pin: str, level: int, t: int) -> None:
        mc = self.mc
        code = LIMIT_ERRORS.get(pin)
        mode = mc.par(P_LIMIT_SWITCH_ERROR, 0)
        if (code is None or not level or not mode or not mc.running or not mc.controlled or not mc.homed
                or mc.state in (W.ERROR, W.SETUP_ERROR, W.ERROR_QUICK_STOP)):
            return
        mc.homed = False                     # [MC] 7.2.3: the homed bit is cleared
        if mode == 1:                        # power off at once
            mc._log_error(code, t)
            mc.ct_runner.stop()
            self.clear()
            mc.error_code, mc.fatal = code, False
            mc._power_off(t, W.ERROR)
        else:                                # quick stop, then error
            mc._fail(code, t)
        mc._record(t)

    # ------------------------------------------------------------------ in the MC cycle
    def step(self, t: int) -> None:
        """The edges up to t run the armed action (once per edge), in state 8 only."""
        edges, self.pending = self.pending, []
        for rising, te in edges:
            if te > t:
                self.pending.append((rising, te))
                continue
            if self.armed is None:
                continue
            if self.mc.state != W.OPERATION_ENABLED:
                continue
            if self.armed[0] == rising:
                self.fired.append(t)
                if not self.armed[1](t):
                    return
