"""Command-table execution ([MC] chapter 6, 4.3.163..170; seed 000 6.1): Start Command Table Command (200xh)
runs an entry's motion command and follows its links (entry bytes 02h..03h, FFFFh = end).

INFERRED (docs/emulator.md section 13): one entry per MC cycle, the first at once; the waits 210xh (time,
100 us), 211xh (motion finished) and 212xh (in target position) hold the sequence; 200xh inside the table
jumps; an entry's own count nibble is ignored; a command from the interface, an error, abort, freeze or
leaving state 8 ends the sequence; a missing entry raises 008Ah.
"""

from __future__ import annotations

import struct

from ...protocol import commands as C
from ...protocol import words as W

END = 0xFFFF
_TRIGGER_WAITS = (C.WAIT_RISING_TRIGGER, C.WAIT_FALLING_TRIGGER)


class CtRunner:
    def __init__(self, mc):
        self.mc = mc
        self.running = False
        self.entry: int | None = None       # the entry to run next
        self.executed: list[int] = []       # entries run by the present sequence, in order (tests, reports)
        self._wait: tuple | None = None

    def stop(self) -> None:
        self.running = False
        self.entry = None
        self._wait = None

    def start(self, entry: int, t: int) -> bool:
        if entry not in self.mc.ct.ram:
            return self.mc._fail(W.ERR_CMD_TAB_ENTRY_NOT_DEFINED, t)
        self.running, self.entry, self._wait = True, entry, None
        self.executed = []
        self.step(t)
        return True

    def step(self, t: int) -> None:
        """Run the sequence at t: finish a wait if its condition holds, then run at most one entry."""
        if self._wait is not None:
            kind, until = self._wait
            mc = self.mc
            if kind == C.WAIT_TIME and t < until:
                return
            if kind == C.WAIT_MOTION_FINISHED and not mc.gen.done(t):
                return
            if kind == C.WAIT_IN_TARGET_POSITION and not mc.in_target:
                return
            if kind in _TRIGGER_WAITS and not mc.events.edge_since(kind == C.WAIT_RISING_TRIGGER, until):
                return
            self._wait = None
            self._advance(self._link)
        if not self.running or self.entry is None:
            return
        block = self.mc.ct.ram.get(self.entry)
        if block is None:
            self.stop()
            self.mc._fail(W.ERR_CMD_TAB_ENTRY_NOT_DEFINED, t)
            return
        self.executed.append(self.entry)
        link, header = struct.unpack_from("<HH", block, 2)
        params = block[6:38]
        cid = C.command_id(header)
        self._link = link
        if cid == C.START_COMMAND_TABLE:
            self._advance(struct.unpack_from("<H", params, 0)[0])
            return
        if cid in (C.WAIT_TIME, C.WAIT_MOTION_FINISHED, C.WAIT_IN_TARGET_POSITION) or cid in _TRIGGER_WAITS:
            # Wait Time: until then; a trigger wait: the next edge at or after now (213xh/214xh, [MC] 4.3.171/172)
            until = t + struct.unpack_from("<I", params, 0)[0] * 100_000 if cid == C.WAIT_TIME else t
            self._wait = (cid, until)
            self.entry = None
            self.mc._wake(t)            # the wait is checked every cycle (also when it is the first entry)
            return
        if not self.mc.execute(header, params, t, from_table=True):
            self.stop()
            return
        self._advance(link)

    def _advance(self, link: int) -> None:
        if link == END:
            self.stop()
        else:
            self.entry = link
