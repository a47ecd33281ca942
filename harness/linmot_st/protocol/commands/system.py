"""System commands (seed 004 4.2 master ID 00h; [MC] 4.3.1..7): accepted in every state of the running MC
except Master Homing. Seed 004 4.2 marks the E1100 and the B1100 column for each."""

from __future__ import annotations

from .row import B1100, E1100, IN_ANY_STATE, CommandDef, Field, Kind, register

NOP = 0x000
WRITE_CONTROL_WORD = 0x001
WRITE_LIVE_PARAMETER = 0x002
MASTER_HOMING = 0x009

_BOTH = frozenset({E1100, B1100})

register(
    CommandDef(NOP, "No Operation", (), Kind.NOP, states=IN_ANY_STATE, drives=_BOTH, source="[MC] 4.3.1"),
    CommandDef(WRITE_CONTROL_WORD, "Write Interface Control Word", (Field("control_word", "UINT"),),
               Kind.CONTROL_WORD, states=IN_ANY_STATE, drives=_BOTH, source="[MC] 4.3.2"),
    CommandDef(WRITE_LIVE_PARAMETER, "Write Live Parameter",
               (Field("upid", "UINT"), Field("value", "UDINT", "the parameter's unit")),
               Kind.LIVE_PARAMETER, states=IN_ANY_STATE, drives=_BOTH, source="[MC] 4.3.3"),
    CommandDef(MASTER_HOMING, "Master Homing", (Field("home_position", "DINT", "0.1 um"),), Kind.MASTER_HOMING,
               drives=_BOTH, source="[MC] 4.3.7"),
)
