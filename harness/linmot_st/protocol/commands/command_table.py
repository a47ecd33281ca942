"""Command-table control and waits (seed 004 4.2 master IDs 20h, 21h; [MC] 4.3.163, 168..170; past the seed's
cut-off: E1100 from the TOC, B1100 unknown). The waits act only inside a command-table sequence
(emulator/linmot/motion/ct_runner.py); from the interface they do nothing."""

from __future__ import annotations

from .row import CommandDef, Field, Kind, register

START_COMMAND_TABLE = 0x200
WAIT_TIME = 0x210
WAIT_MOTION_FINISHED = 0x211
WAIT_IN_TARGET_POSITION = 0x212

register(
    CommandDef(START_COMMAND_TABLE, "Start Command Table Command", (Field("entry", "UINT"),), Kind.COMMAND_TABLE,
               needs_homing=True, source="[MC] 4.3.163"),
    CommandDef(WAIT_TIME, "Wait Time", (Field("time", "UDINT", "100 us"),), Kind.WAIT, source="[MC] 4.3.168"),
    CommandDef(WAIT_MOTION_FINISHED, "Wait Until Motion Finished", (), Kind.WAIT, source="[MC] 4.3.169"),
    CommandDef(WAIT_IN_TARGET_POSITION, "Wait Until In Target Position", (), Kind.WAIT, source="[MC] 4.3.170"),
)
