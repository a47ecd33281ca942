"""Modify Curve in RAM (seed 004 4.2 master ID 05h; [MC] 4.3.57..62): patch a curve's start address, its
70-byte info block or its data block in the drive's curve RAM, bypassing the curve service. The byte offset
counts from the start of the block; values are little endian as the curve service writes them.
056xh (three SInt32 values, 16 parameter bytes) travels on CANopen only as a command-table entry
(docs/motion.md); its five parameters are the ST encoder's A..E."""

from __future__ import annotations

from .row import CommandDef, Field, Kind, register

MODIFY_CURVE_START_ADDRESS = 0x050
MODIFY_CURVE_INFO_16 = 0x051
MODIFY_CURVE_INFO_32 = 0x052
MODIFY_CURVE_DATA_32 = 0x054
MODIFY_CURVE_DATA_64 = 0x055
MODIFY_CURVE_DATA_96 = 0x056

_ID = Field("curve_id", "UINT")
_OFFSET = Field("offset", "UINT", "byte")

# which block each command writes ([MC] 4.3.59's title says info block, its text data block: the title is
# taken, as 051h's and the TOC's "Info Block" agree with it; spec/linmot-motion-commands.md 1c)
CURVE_MODIFY_BLOCK = {MODIFY_CURVE_INFO_16: "info", MODIFY_CURVE_INFO_32: "info", MODIFY_CURVE_DATA_32: "data",
         MODIFY_CURVE_DATA_64: "data", MODIFY_CURVE_DATA_96: "data"}


def _modify(cid, name, fields, mc):
    return CommandDef(cid, name, fields, Kind.CURVE_MODIFY, source=f"[MC] 4.3.{mc}")


register(
    _modify(MODIFY_CURVE_START_ADDRESS, "Modify Curve Start Address in RAM",
            (_ID, Field("start_address", "UINT")), 57),
    _modify(MODIFY_CURVE_INFO_16, "Modify Curve Info Block 16 Bit Value in RAM",
            (_ID, _OFFSET, Field("value", "INT")), 58),
    _modify(MODIFY_CURVE_INFO_32, "Modify Curve Info Block 32 Bit Value in RAM",
            (_ID, _OFFSET, Field("value", "DINT")), 59),
    _modify(MODIFY_CURVE_DATA_32, "Modify Curve Data Block 32 Bit Value in RAM",
            (_ID, _OFFSET, Field("value", "DINT")), 60),
    _modify(MODIFY_CURVE_DATA_64, "Modify Curve Data Block 64 Bit Value in RAM",
            (_ID, _OFFSET, Field("value", "DINT"), Field("value2", "DINT")), 61),
    _modify(MODIFY_CURVE_DATA_96, "Modify Curve Data Block 96 Bit Value in RAM",
            (_ID, _OFFSET, Field("value", "DINT"), Field("value2", "DINT"), Field("value3", "DINT")), 62),
)
