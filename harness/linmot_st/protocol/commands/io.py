"""I/O and event-handler commands (seed 004 4.2 master ID 00h: 003xh, 004xh, 008xh; [MC] 4.3.4, 4.3.6): write
the interface outputs with a mask, clear the event handler. Accepted in every state of the running MC like the
other system commands (INFERRED: seed 004 4.2 lists them in the system group). The B1100 has 003xh ("X4/X14":
its X14) and 008xh by the seed's overview, not 004xh (no X6): row.seed_drives."""

from __future__ import annotations

from .row import IN_ANY_STATE, CommandDef, Field, Kind, register, seed_drives

WRITE_X4_OUTPUTS = 0x003
WRITE_X6_OUTPUTS = 0x004
CLEAR_EVENT_EVALUATION = 0x008

_MASK = (Field("mask", "UINT"), Field("value", "UINT"))

register(
    CommandDef(WRITE_X4_OUTPUTS, "Write X4 Intf Outputs with Mask", _MASK, Kind.IO_OUTPUTS, states=IN_ANY_STATE,
               drives=seed_drives(WRITE_X4_OUTPUTS), source="[MC] 4.3.4 (bit 0 = X4.3)"),
    # the seed's TOC only; layout INFERRED as 003xh's (spec/linmot-motion-commands.md 2.18)
    CommandDef(WRITE_X6_OUTPUTS, "Write X6 Intf Outputs with Mask", _MASK, Kind.IO_OUTPUTS, states=IN_ANY_STATE,
               source="seed 004 4.3.5 (TOC); layout INFERRED"),
    CommandDef(CLEAR_EVENT_EVALUATION, "Clear Event Evaluation", (), Kind.CLEAR_EVENTS, states=IN_ANY_STATE,
               drives=seed_drives(CLEAR_EVENT_EVALUATION), source="[MC] 4.3.6"),
)
