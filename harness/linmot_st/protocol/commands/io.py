"""I/O and event-handler commands (seed 004 4.2 master ID 00h: 003xh, 004xh, 008xh; [MC] 4.3.4, 4.3.6): write
the interface outputs with a mask, clear the event handler. Accepted in every state of the running MC like the
other system commands (INFERRED: seed 004 4.2 lists them in the system group). The B1100 has no X4 (docs/
emulator.md 14.1): E1100 only."""

from __future__ import annotations

from .row import E1100, IN_ANY_STATE, CommandDef, Field, Kind, register

WRITE_X4_OUTPUTS = 0x003
WRITE_X6_OUTPUTS = 0x004
CLEAR_EVENT_EVALUATION = 0x008

_MASK = (Field("mask", "UINT"), Field("value", "UINT"))

register(
    CommandDef(WRITE_X4_OUTPUTS, "Write X4 Intf Outputs with Mask", _MASK, Kind.IO_OUTPUTS, states=IN_ANY_STATE,
               source="[MC] 4.3.4 (bit 0 = X4.3)"),
    # the seed's TOC only; layout INFERRED as 003xh's (spec/linmot-motion-commands.md 2.18)
    CommandDef(WRITE_X6_OUTPUTS, "Write X6 Intf Outputs with Mask", _MASK, Kind.IO_OUTPUTS, states=IN_ANY_STATE,
               source="seed 004 4.3.5 (TOC); layout INFERRED"),
    CommandDef(CLEAR_EVENT_EVALUATION, "Clear Event Evaluation", (), Kind.CLEAR_EVENTS, states=IN_ANY_STATE,
               drives=frozenset({E1100}), source="[MC] 4.3.6"),
)
