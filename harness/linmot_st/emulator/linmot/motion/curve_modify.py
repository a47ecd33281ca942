"""Modify Curve in RAM (050xh..056xh; [MC] 4.3.57..62): the handler of the catalogue's kind CURVE_MODIFY. It
patches a curve of the drive's curve RAM (linmot/curves.py) in place, as the real drive writes into its curve
memory; the curve service (SDO) remains the checked way.

INFERRED (docs/emulator.md, "Modify Curve in RAM"): the emulated curve RAM is a store per curve ID, not one
memory with addresses, so 050xh with 0FFFh deletes the curve and any other start address leaves it as it is;
a patch of a curve that is not in RAM is error 0062h (Curve Not Defined); a patch that reaches beyond its block
changes nothing (the real drive would overwrite its neighbour: "unpredictable behavior").
"""

from __future__ import annotations

import struct

from ....protocol import commands as C
from ....protocol import words as W
from ....protocol.commands import CommandDef
from ..curves import Curve

NO_CURVE = 0x0FFF


def modify_curve(mc, c: CommandDef, f: dict, t: int) -> bool:
    ram = mc.curves.ram
    curve = ram.get(f["curve_id"])
    if c.cid == C.MODIFY_CURVE_START_ADDRESS:
        if f["start_address"] == NO_CURVE:
            ram.pop(f["curve_id"], None)
        return True
    if curve is None:
        return mc._fail(W.ERR_CURVE_NOT_DEFINED, t)
    if c.fields[-1].type == "INT":
        patch = struct.pack("<h", f["value"])
    else:                               # one, two or three SInt32 (054xh, 055xh; 056xh once it has a row)
        values = [f[n] for n in ("value", "value2", "value3") if n in f]
        patch = struct.pack(f"<{len(values)}i", *values)
    block = C.CURVE_MODIFY_BLOCK[c.cid]
    old = curve.info if block == "info" else curve.data
    at = f["offset"]
    if at + len(patch) > len(old):
        return True
    new = old[:at] + patch + old[at + len(patch):]
    ram[curve.curve_id] = (Curve(curve.curve_id, new, curve.data) if block == "info"
                           else Curve(curve.curve_id, curve.info, new))
    return True
