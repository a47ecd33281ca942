"""The VAI families beyond the basic rows of vai.py (seed 004 4.2 master IDs 01h, 02h, 09h..0Dh; [MC] 4.3.17,
23, 24, 28, 29, 31, 36, 37, 76..79, 81, 86..94, 99..104, 109..117, 123; spec/linmot-motion-commands.md
section 1 and 2.3..2.7): the queued "Go To Pos After Actual Command" of every family, the position
transitions, infinite motion, the From Act Pos variants of the 16-bit and predefined families, the predefined
16-bit family, VAI Predef Acc, VAI Dec=Acc (with max current) and VAI 16 Bit Dec=Acc. The triggered variants
belong to the trigger group, 0D0xh/0D4xh..0D7xh to the capture and command-table groups.

Drive types: seed 004 4.2 marks E1100 and B1100 for every ID of master IDs 01h and 02h; 09xh and later are past
the seed's cut-off (E1100 from the TOC; B1100 unknown, left out). [MC] 4.3.36/37 and 0CExh/0CFxh: see
docs/emulator.md (0CExh/0CFxh are left out: no source gives their layout).
"""

from __future__ import annotations

from .row import B1100, E1100, CommandDef, Field, Kind, Start, Target, register
from .vai import _P32, _V16, _V32

VAI_GO_TO_POS_AFTER_ACTUAL = 0x018
VAI_CHANGE_ON_POSITIVE_TRANSITION = 0x01E
VAI_CHANGE_ON_NEGATIVE_TRANSITION = 0x01F
PREDEF_VAI_GO_TO_POS_FROM_ACT_POS_AND_VEL = 0x023
PREDEF_VAI_GO_TO_POS_FROM_ACT_POS_VEL_0 = 0x024
PREDEF_VAI_GO_TO_POS_AFTER_ACTUAL = 0x028
PREDEF_VAI_INFINITE_POSITIVE = 0x02E
PREDEF_VAI_INFINITE_NEGATIVE = 0x02F
VAI16_GO_TO_POS_FROM_ACT_POS_AND_VEL = 0x093
VAI16_GO_TO_POS_FROM_ACT_POS_VEL_0 = 0x094
VAI16_INCREMENT_ACT_POS = 0x095
VAI16_INCREMENT_ACT_POS_VEL_0 = 0x096
VAI16_GO_TO_POS_AFTER_ACTUAL = 0x098
VAI16_CHANGE_ON_POSITIVE_TRANSITION = 0x09E
VAI16_CHANGE_ON_NEGATIVE_TRANSITION = 0x09F
PREDEF_VAI16_GO_TO_POS = 0x0A0
PREDEF_VAI16_INCREMENT_DEM_POS = 0x0A1
PREDEF_VAI16_INCREMENT_TARGET_POS = 0x0A2
PREDEF_VAI16_GO_TO_POS_FROM_ACT_POS_AND_VEL = 0x0A3
PREDEF_VAI16_GO_TO_POS_FROM_ACT_POS_VEL_0 = 0x0A4
PREDEF_VAI16_STOP = 0x0A7
PREDEF_VAI16_GO_TO_POS_AFTER_ACTUAL = 0x0A8
VAI_PREDEF_ACC_GO_TO_POS = 0x0B0
VAI_PREDEF_ACC_INCREMENT_DEM_POS = 0x0B1
VAI_PREDEF_ACC_INCREMENT_TARGET_POS = 0x0B2
VAI_PREDEF_ACC_GO_TO_POS_FROM_ACT_POS_AND_VEL = 0x0B3
VAI_PREDEF_ACC_GO_TO_POS_FROM_ACT_POS_VEL_0 = 0x0B4
VAI_PREDEF_ACC_GO_TO_POS_AFTER_ACTUAL = 0x0B8
VAI_DEC_ACC_GO_TO_POS = 0x0C0
VAI_DEC_ACC_INCREMENT_DEM_POS = 0x0C1
VAI_DEC_ACC_INCREMENT_TARGET_POS = 0x0C2
VAI_DEC_ACC_GO_TO_POS_FROM_ACT_POS_AND_VEL = 0x0C3
VAI_DEC_ACC_GO_TO_POS_FROM_ACT_POS_VEL_0 = 0x0C4
VAI_DEC_ACC_GO_TO_POS_MAX_CURRENT = 0x0C5
VAI_DEC_ACC_GO_TO_POS_FROM_ACT_POS_AND_VEL_MAX_CURRENT = 0x0C6
VAI_DEC_ACC_GO_TO_POS_FROM_ACT_POS_VEL_0_MAX_CURRENT = 0x0C7
VAI_DEC_ACC_GO_TO_POS_AFTER_ACTUAL = 0x0C8
VAI16_DEC_ACC_GO_TO_POS = 0x0D1

_BOTH = frozenset({E1100, B1100})
_TRANSITION32 = (Field("position", "DINT", "0.1 um"), Field("vmax", "UDINT", "1E-6 m/s"),
                 Field("acc", "UDINT", "1E-5 m/s^2"), Field("dec", "UDINT", "1E-5 m/s^2"))
_TRANSITION16 = (Field("position", "INT", "16-bit position scaling"),
                 Field("vmax", "UINT", "16-bit velocity scaling"), Field("acc", "UINT", "16-bit acceleration scaling"),
                 Field("dec", "UINT", "16-bit acceleration scaling"))
_P16 = (Field("target", "INT", "16-bit position scaling"),)
_PA = (Field("target", "DINT", "0.1 um"), Field("vmax", "UDINT", "1E-6 m/s"))
_DA = (Field("target", "DINT", "0.1 um"), Field("vmax", "UDINT", "1E-6 m/s"), Field("acc", "UDINT", "1E-5 m/s^2"))
_DA_CURRENT = _DA + (Field("max_current", "UINT", "1 mA"),)
_DA16 = (Field("target", "INT", "16-bit position scaling"), Field("vmax", "UINT", "16-bit velocity scaling"),
         Field("acc", "UINT", "16-bit acceleration scaling"))

_D, _A, _R, _Q = Start.DEMAND, Start.ACTUAL, Start.ACTUAL_AT_REST, Start.AFTER_ACTUAL_COMMAND
_ABS, _INC, _LAST = Target.ABSOLUTE, Target.FROM_START, Target.FROM_LAST_TARGET


def _row(cid, name, fields, kind, start, target, mc, drives=frozenset({E1100}), homing=True):
    return CommandDef(cid, name, fields, kind, needs_homing=homing, drives=drives, start=start, target=target,
                      source=f"[MC] 4.3.{mc}")


register(
    # 32 bit (master ID 01h: E1100 and B1100)
    _row(VAI_GO_TO_POS_AFTER_ACTUAL, "VAI Go To Pos After Actual Command", _V32, Kind.VAI, _Q, _ABS, 17, _BOTH),
    # a transition changes a running motion's limits: it sets no position, so it needs no homing (INFERRED)
    _row(VAI_CHANGE_ON_POSITIVE_TRANSITION, "VAI Change Motion Parameters On Positive Position Transition",
         _TRANSITION32, Kind.VAI, _D, Target.TRANSITION_POSITIVE, 23, _BOTH, homing=False),
    _row(VAI_CHANGE_ON_NEGATIVE_TRANSITION, "VAI Change Motion Parameters On Negative Position Transition",
         _TRANSITION32, Kind.VAI, _D, Target.TRANSITION_NEGATIVE, 24, _BOTH, homing=False),
    # predefined (master ID 02h: E1100 and B1100)
    _row(PREDEF_VAI_GO_TO_POS_FROM_ACT_POS_AND_VEL, "Predef VAI Go To Pos From Act Pos and Act Vel", _P32,
         Kind.PREDEF_VAI, _A, _ABS, 28, _BOTH),
    _row(PREDEF_VAI_GO_TO_POS_FROM_ACT_POS_VEL_0, "Predef VAI Go To Pos From Act Pos Starting With Dem Vel = 0",
         _P32, Kind.PREDEF_VAI, _R, _ABS, 29, _BOTH),
    _row(PREDEF_VAI_GO_TO_POS_AFTER_ACTUAL, "Predef VAI Go To Pos After Actual Command", _P32, Kind.PREDEF_VAI, _Q,
         _ABS, 31, _BOTH),
    _row(PREDEF_VAI_INFINITE_POSITIVE, "Predef VAI Infinite Motion Positive Direction", (), Kind.PREDEF_VAI, _D,
         Target.INFINITE_POSITIVE, 36, _BOTH),
    _row(PREDEF_VAI_INFINITE_NEGATIVE, "Predef VAI Infinite Motion Negative Direction", (), Kind.PREDEF_VAI, _D,
         Target.INFINITE_NEGATIVE, 37, _BOTH),
    # 16 bit (09xh)
    _row(VAI16_GO_TO_POS_FROM_ACT_POS_AND_VEL, "VAI 16 Bit Go To Pos From Act Pos And Act Vel", _V16,
         Kind.VAI_16BIT, _A, _ABS, 76),
    _row(VAI16_GO_TO_POS_FROM_ACT_POS_VEL_0, "VAI 16 Bit Go To Pos From Act Pos Starting With Dem Vel = 0", _V16,
         Kind.VAI_16BIT, _R, _ABS, 77),
    # INFERRED like 015xh (docs/emulator.md): the increment on the actual position starts at rest
    _row(VAI16_INCREMENT_ACT_POS, "VAI 16 Bit Increment Act Pos", _V16, Kind.VAI_16BIT, _R, _INC, 78),
    _row(VAI16_INCREMENT_ACT_POS_VEL_0, "VAI 16 Bit Increment Act Pos Starting With Dem Vel = 0", _V16,
         Kind.VAI_16BIT, _R, _INC, 79),
    _row(VAI16_GO_TO_POS_AFTER_ACTUAL, "VAI 16 Bit Go To Pos After Actual Command", _V16, Kind.VAI_16BIT, _Q, _ABS,
         81),
    _row(VAI16_CHANGE_ON_POSITIVE_TRANSITION, "VAI 16 Bit Change Motion Parameters On Positive Position Transition",
         _TRANSITION16, Kind.VAI_16BIT, _D, Target.TRANSITION_POSITIVE, 86, homing=False),
    _row(VAI16_CHANGE_ON_NEGATIVE_TRANSITION, "VAI 16 Bit Change Motion Parameters On Negative Position Transition",
         _TRANSITION16, Kind.VAI_16BIT, _D, Target.TRANSITION_NEGATIVE, 87, homing=False),
    # predefined 16 bit (0Axh)
    _row(PREDEF_VAI16_GO_TO_POS, "Predef VAI 16 Bit Go To Pos", _P16, Kind.PREDEF_VAI_16BIT, _D, _ABS, 88),
    _row(PREDEF_VAI16_INCREMENT_DEM_POS, "Predef VAI 16 Bit Increment Dem Pos", _P16, Kind.PREDEF_VAI_16BIT, _D,
         _INC, 89),
    _row(PREDEF_VAI16_INCREMENT_TARGET_POS, "Predef VAI 16 Bit Increment Target Pos", _P16, Kind.PREDEF_VAI_16BIT,
         _D, _LAST, 90),
    _row(PREDEF_VAI16_GO_TO_POS_FROM_ACT_POS_AND_VEL, "Predef VAI 16 Bit Go To Pos From Act Pos And Act Vel", _P16,
         Kind.PREDEF_VAI_16BIT, _A, _ABS, 91),
    _row(PREDEF_VAI16_GO_TO_POS_FROM_ACT_POS_VEL_0,
         "Predef VAI 16 Bit Go To Pos From Act Pos Starting With Dem Vel = 0", _P16, Kind.PREDEF_VAI_16BIT, _R,
         _ABS, 92),
    # decelerates with the quick-stop deceleration, like 027xh
    _row(PREDEF_VAI16_STOP, "Predef VAI 16 Bit Stop", (), Kind.PREDEF_VAI_16BIT, _D, Target.STOP, 93, homing=False),
    _row(PREDEF_VAI16_GO_TO_POS_AFTER_ACTUAL, "Predef VAI 16 Bit Go To Pos After Actual Command", _P16,
         Kind.PREDEF_VAI_16BIT, _Q, _ABS, 94),
    # VAI predef acc (0Bxh)
    _row(VAI_PREDEF_ACC_GO_TO_POS, "VAI Predef Acc Go To Pos", _PA, Kind.VAI_PREDEF_ACC, _D, _ABS, 99),
    _row(VAI_PREDEF_ACC_INCREMENT_DEM_POS, "VAI Predef Acc Increment Dem Pos", _PA, Kind.VAI_PREDEF_ACC, _D, _INC,
         100),
    _row(VAI_PREDEF_ACC_INCREMENT_TARGET_POS, "VAI Predef Acc Increment Target Pos", _PA, Kind.VAI_PREDEF_ACC, _D,
         _LAST, 101),
    _row(VAI_PREDEF_ACC_GO_TO_POS_FROM_ACT_POS_AND_VEL, "VAI Predef Acc Go To Pos From Act Pos And Act Vel", _PA,
         Kind.VAI_PREDEF_ACC, _A, _ABS, 102),
    _row(VAI_PREDEF_ACC_GO_TO_POS_FROM_ACT_POS_VEL_0, "VAI Predef Acc Go To Pos From Act Pos Starting With Dem Vel = 0",
         _PA, Kind.VAI_PREDEF_ACC, _R, _ABS, 103),
    _row(VAI_PREDEF_ACC_GO_TO_POS_AFTER_ACTUAL, "VAI Predef Acc Go To Pos After Actual Command", _PA,
         Kind.VAI_PREDEF_ACC, _Q, _ABS, 104),
    # VAI dec=acc (0Cxh)
    _row(VAI_DEC_ACC_GO_TO_POS, "VAI Dec=Acc Go To Pos", _DA, Kind.VAI_DEC_ACC, _D, _ABS, 109),
    _row(VAI_DEC_ACC_INCREMENT_DEM_POS, "VAI Dec=Acc Increment Dem Pos", _DA, Kind.VAI_DEC_ACC, _D, _INC, 110),
    _row(VAI_DEC_ACC_INCREMENT_TARGET_POS, "VAI Dec=Acc Increment Target Pos", _DA, Kind.VAI_DEC_ACC, _D, _LAST, 111),
    _row(VAI_DEC_ACC_GO_TO_POS_FROM_ACT_POS_AND_VEL, "VAI Dec=Acc Go To Pos From Act Pos And Act Vel", _DA,
         Kind.VAI_DEC_ACC, _A, _ABS, 112),
    _row(VAI_DEC_ACC_GO_TO_POS_FROM_ACT_POS_VEL_0, "VAI Dec=Acc Go To Pos From Act Pos Starting With Dem Vel = 0",
         _DA, Kind.VAI_DEC_ACC, _R, _ABS, 113),
    _row(VAI_DEC_ACC_GO_TO_POS_MAX_CURRENT, "VAI Dec=Acc Go To Pos With Max Curr", _DA_CURRENT, Kind.VAI_DEC_ACC,
         _D, _ABS, 114),
    _row(VAI_DEC_ACC_GO_TO_POS_FROM_ACT_POS_AND_VEL_MAX_CURRENT,
         "VAI Dec=Acc Go To Pos From Act Pos And Vel With Max Curr", _DA_CURRENT, Kind.VAI_DEC_ACC, _A, _ABS, 115),
    _row(VAI_DEC_ACC_GO_TO_POS_FROM_ACT_POS_VEL_0_MAX_CURRENT,
         "VAI Dec=Acc Go To Pos From Act Pos And Vel = 0 With Max Curr", _DA_CURRENT, Kind.VAI_DEC_ACC, _R, _ABS,
         116),
    _row(VAI_DEC_ACC_GO_TO_POS_AFTER_ACTUAL, "VAI Dec=Acc Go To Pos After Actual Command", _DA, Kind.VAI_DEC_ACC, _Q,
         _ABS, 117),
    # VAI 16 bit dec=acc (0D1xh)
    _row(VAI16_DEC_ACC_GO_TO_POS, "VAI 16 Bit Dec=Acc Go To Pos", _DA16, Kind.VAI_16BIT_DEC_ACC, _D, _ABS, 123),
)
