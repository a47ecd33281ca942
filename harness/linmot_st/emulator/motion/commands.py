"""Motion commands: the header and the parameter layout of every command the model interprets (seed 004 4.1,
[MC] 4.3; spec/linmot-motion.md section 2).

Header word = master ID << 8 | sub ID << 4 | count; the command ID is header >> 4 (e.g. 090xh -> 0x090).
Parameters follow the header, little endian; offsets here are from the first parameter byte (CANopen
"Par Byte n", = [MC]'s byte offset - 2). tests/vectors/motion_commands.json holds encoded examples that the
ST library's encoders are checked against too.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

NOP = 0x000
WRITE_CONTROL_WORD = 0x001
WRITE_LIVE_PARAMETER = 0x002
MASTER_HOMING = 0x009
VAI_GO_TO_POS = 0x010
VAI_INCREMENT_DEM_POS = 0x011
VAI_INCREMENT_TARGET_POS = 0x012
VAI_GO_TO_POS_FROM_ACT_POS_AND_VEL = 0x013
VAI_GO_TO_POS_FROM_ACT_POS_VEL_0 = 0x014
VAI_INCREMENT_ACT_POS = 0x015
VAI_INCREMENT_ACT_POS_VEL_0 = 0x016
VAI_STOP = 0x017
PREDEF_VAI_GO_TO_POS = 0x020
PREDEF_VAI_INCREMENT_DEM_POS = 0x021
PREDEF_VAI_INCREMENT_TARGET_POS = 0x022
PREDEF_VAI_STOP = 0x027
TIME_CURVE = 0x040
TIME_CURVE_FROM_ACT_POS = 0x041
TIME_CURVE_TO_POS = 0x042
TIME_CURVE_TO_POS_TIME = 0x043
TIME_CURVE_OFFSET_TIME_SCALE_AMP = 0x044
TIME_CURVE_OFFSET_TIME_AMP = 0x045
VAI16_GO_TO_POS = 0x090
VAI16_INCREMENT_DEM_POS = 0x091
VAI16_INCREMENT_TARGET_POS = 0x092
VAI16_STOP = 0x097
START_COMMAND_TABLE = 0x200
WAIT_TIME = 0x210
WAIT_MOTION_FINISHED = 0x211
WAIT_IN_TARGET_POSITION = 0x212

_VAI32 = (("target", "i"), ("vmax", "I"), ("acc", "I"), ("dec", "I"))
_VAI16 = (("target", "h"), ("vmax", "H"), ("acc", "H"), ("dec", "H"))


@dataclass(frozen=True)
class CommandDef:
    cid: int
    name: str
    fields: tuple[tuple[str, str], ...]     # (name, struct code), packed in order after the header

    @property
    def size(self) -> int:
        """Parameter bytes."""
        return struct.calcsize("<" + "".join(c for _, c in self.fields))


COMMANDS: dict[int, CommandDef] = {c.cid: c for c in (
    CommandDef(NOP, "No Operation", ()),
    CommandDef(WRITE_CONTROL_WORD, "Write Interface Control Word", (("control_word", "H"),)),
    CommandDef(WRITE_LIVE_PARAMETER, "Write Live Parameter", (("upid", "H"), ("value", "I"))),
    CommandDef(MASTER_HOMING, "Master Homing", (("home_position", "i"),)),
    CommandDef(VAI_GO_TO_POS, "VAI Go To Pos", _VAI32),
    CommandDef(VAI_INCREMENT_DEM_POS, "VAI Increment Dem Pos", _VAI32),
    CommandDef(VAI_INCREMENT_TARGET_POS, "VAI Increment Target Pos", _VAI32),
    CommandDef(VAI_GO_TO_POS_FROM_ACT_POS_AND_VEL, "VAI Go To Pos From Act Pos And Act Vel", _VAI32),
    CommandDef(VAI_GO_TO_POS_FROM_ACT_POS_VEL_0, "VAI Go To Pos From Act Pos Starting With Dem Vel = 0", _VAI32),
    CommandDef(VAI_INCREMENT_ACT_POS, "VAI Increment Act Pos", _VAI32),
    CommandDef(VAI_INCREMENT_ACT_POS_VEL_0, "VAI Increment Act Pos Starting With Dem Vel = 0", _VAI32),
    CommandDef(VAI_STOP, "VAI Stop", (("dec", "I"),)),
    CommandDef(PREDEF_VAI_GO_TO_POS, "Predef VAI Go To Pos", (("target", "i"),)),
    CommandDef(PREDEF_VAI_INCREMENT_DEM_POS, "Predef VAI Increment Dem Pos", (("target", "i"),)),
    CommandDef(PREDEF_VAI_INCREMENT_TARGET_POS, "Predef VAI Increment Target Pos", (("target", "i"),)),
    CommandDef(PREDEF_VAI_STOP, "Predef VAI Stop", ()),
    CommandDef(TIME_CURVE, "Time Curve With Default Parameters", (("curve_id", "H"),)),
    CommandDef(TIME_CURVE_FROM_ACT_POS, "Time Curve With Default Parameters From Act Pos", (("curve_id", "H"),)),
    CommandDef(TIME_CURVE_TO_POS, "Time Curve To Pos With Default Speed", (("curve_id", "H"), ("target", "i"))),
    CommandDef(TIME_CURVE_TO_POS_TIME, "Time Curve To Pos With Adjustable Time",
               (("curve_id", "H"), ("target", "i"), ("curve_time", "i"))),
    CommandDef(TIME_CURVE_OFFSET_TIME_SCALE_AMP, "Time Curve With Adj. Offset, Time Scale & Amplitude Scale",
               (("curve_id", "H"), ("offset", "i"), ("time_scale", "H"), ("amplitude", "h"))),
    CommandDef(TIME_CURVE_OFFSET_TIME_AMP, "Time Curve With Adj. Offset, Time & Amplitude Scale",
               (("curve_id", "H"), ("offset", "i"), ("curve_time", "i"), ("amplitude", "h"))),
    CommandDef(VAI16_GO_TO_POS, "VAI 16 Bit Go To Pos", _VAI16),
    CommandDef(VAI16_INCREMENT_DEM_POS, "VAI 16 Bit Increment Dem Pos", _VAI16),
    CommandDef(VAI16_INCREMENT_TARGET_POS, "VAI 16 Bit Increment Target Pos", _VAI16),
    CommandDef(VAI16_STOP, "VAI 16 Bit Stop", (("dec", "H"),)),
    CommandDef(START_COMMAND_TABLE, "Start Command Table Command", (("entry", "H"),)),
    CommandDef(WAIT_TIME, "Wait Time", (("time", "I"),)),
    CommandDef(WAIT_MOTION_FINISHED, "Wait Until Motion Finished", ()),
    CommandDef(WAIT_IN_TARGET_POSITION, "Wait Until In Target Position", ()),
)}


def command_id(header: int) -> int:
    return (header >> 4) & 0xFFF


def decode(header: int, params: bytes) -> tuple[CommandDef | None, dict]:
    """The command and its parameter values (missing bytes read as 0); (None, {}) for an unknown command."""
    c = COMMANDS.get(command_id(header))
    if c is None:
        return None, {}
    raw = bytes(params[:c.size]).ljust(c.size, b"\0")
    values = struct.unpack("<" + "".join(code for _, code in c.fields), raw) if c.fields else ()
    return c, dict(zip((n for n, _ in c.fields), values))


def encode(cid: int, count: int = 0, **values) -> bytes:
    """Header and parameters of a command, little endian (tests, tools). An ID the model does not know gets
    its header alone (to provoke 0081h)."""
    header = struct.pack("<H", (cid << 4 | count & 0xF) & 0xFFFF)
    c = COMMANDS.get(cid)
    if c is None:
        return header
    return header + struct.pack("<" + "".join(code for _, code in c.fields), *(values[n] for n, _ in c.fields))
