"""System commands of [MC] 4.3 that the seed's TOC leaves out (spec/linmot-motion-commands.md 1b): Select
Position Controller Set (005xh, [MC] 4.3.5) and Reset (00Fxh, [MC] 4.3.8). [MC] 4.2 marks them for the E1200
and E1400; [MC] 7 says E1100/E1200/E1400 share the MC software's UPIDs, so the E1100 has them (INFERRED); the
B1100 is unknown (left out)."""

from __future__ import annotations

from .row import IN_ANY_STATE, CommandDef, Field, Kind, register

SELECT_POSITION_CONTROLLER_SET = 0x005
RESET = 0x00F

register(
    # a system command (master ID 00h): every state of the running MC, like 001xh/002xh (INFERRED)
    CommandDef(SELECT_POSITION_CONTROLLER_SET, "Select Position Controller Set", (Field("controller_set", "UINT"),),
               Kind.SELECT_CONTROLLER_SET, states=IN_ANY_STATE, source="[MC] 4.3.5"),
    CommandDef(RESET, "Reset", (), Kind.RESET, states=IN_ANY_STATE, source="[MC] 4.3.8"),
)
