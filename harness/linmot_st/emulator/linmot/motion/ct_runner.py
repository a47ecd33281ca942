"""Command-table execution ([MC] chapter 6, 4.3.163..211; seed 000 6.1): Start Command Table Command (200xh)
runs an entry's motion command and follows its links (entry bytes 02h..03h, FFFFh = end); an IF continues at
one of its two entries, a wait holds the sequence until its condition holds (ct_language.py has the conditions
and the two command-table variables).

INFERRED (docs/emulator.md section 13.6): one entry per MC cycle, the first at once; a wait's condition is
checked from the next cycle on, and the entry after it runs in the cycle it holds; 200xh inside the table jumps;
an IF ignores the entry's link; an entry's own count nibble is ignored; a command from the interface, an error,
abort, freeze or leaving state 8 ends the sequence; a missing entry raises 008Ah. The variables keep their values
when a sequence ends; an MC start clears them.
"""

from __future__ import annotations

import struct
from collections.abc import Callable

from ....protocol import commands as C
from ....protocol import words as W
from ....protocol.commands import Kind
from .ct_language import QUIET_WAITS, WAITS, if_target

END = 0xFFFF


class CtRunner:
    def __init__(self, mc):
        self.mc = mc
        self.running = False
        self.entry: int | None = None       # the entry to run next
        self.executed: list[int] = []       # entries run by the present sequence, in order (tests, reports)
        self.variables = {1: 0, 2: 0}       # Cmd Table Var 1 / Var 2 (UPIDs 1E72h / 1E73h), SInt32
        self._wait: Callable[[int], bool] | None = None
        self._wait_id = 0                   # the command ID of the wait that set _wait
        self._link = END

    def clear_variables(self) -> None:
        self.variables[1] = self.variables[2] = 0

    @property
    def quiet_wait(self) -> Callable[[int], bool] | None:
        """The condition of the wait the sequence is in, where a quiet MC cycle cannot change what it reads
        (ct_language.QUIET_WAITS); None otherwise. While it is False, the sequence's step changes nothing."""
        return self._wait if self._wait is not None and self._wait_id in QUIET_WAITS else None

    def stop(self) -> None:
        self.running = False
        self.entry = None
        self._wait = None

    def start(self, entry: int, t: int) -> bool:
        if entry not in self.mc.ct.ram:
            return self.mc._fail(W.ERR_CMD_TAB_ENTRY_NOT_DEFINED, t)
        self.running, self.entry, self._wait = True, entry, None
        self.executed = []
        self.mc._wake(t)            # the MC cycles while the sequence runs, even if its first entry moves nothing
        self.step(t)
        return True

    def step(self, t: int) -> None:
        """Run the sequence at t: finish a wait if its condition holds, then run at most one entry."""
        if self._wait is not None:
            if not self._wait(t):
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
        row, fields = C.decode(header, params)
        if cid in WAITS:
            self.mc.executed.append((t, header, bytes(params[:16])))
            self._wait, self._wait_id = WAITS[cid](self.mc, fields, t), cid
            self.entry = None
            self.mc._wake(t)            # the wait is checked every cycle (also when it is the first entry)
            return
        if row is not None and row.kind is Kind.CT_IF:
            target = if_target(self.mc, cid, fields)
            if target is not None:
                self.mc.executed.append((t, header, bytes(params[:16])))
                self._advance(target)
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
