"""VAI commands (seed 004 4.2 master IDs 01h, 02h, 09h; [MC] 4.3.9..16, 25..30, 73..80): a trapezoidal
(velocity, acceleration, deceleration) motion to a target. 32 bit: every value in the command in the drive's
units; 16 bit: in the 16-bit interface scaling; predefined: the target in the command, vmax/acc/dec from the
predefined VAI parameters. Seed 004 4.2 marks E1100 and B1100 for 01xh/02xh; 09xh is past the seed's cut-off
(E1100 from the TOC, spec/linmot-motion-commands.md; B1100 unknown)."""

from __future__ import annotations

from .row import B1100, E1100, CommandDef, Field, Kind, Start, Target, register

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
VAI16_GO_TO_POS = 0x090
VAI16_INCREMENT_DEM_POS = 0x091
VAI16_INCREMENT_TARGET_POS = 0x092
VAI16_STOP = 0x097

_BOTH = frozenset({E1100, B1100})
_V32 = (Field("target", "DINT", "0.1 um"), Field("vmax", "UDINT", "1E-6 m/s"), Field("acc", "UDINT", "1E-5 m/s^2"),
        Field("dec", "UDINT", "1E-5 m/s^2"))
_V16 = (Field("target", "INT", "16-bit position scaling"), Field("vmax", "UINT", "16-bit velocity scaling"),
        Field("acc", "UINT", "16-bit acceleration scaling"), Field("dec", "UINT", "16-bit acceleration scaling"))
_P32 = (Field("target", "DINT", "0.1 um"),)


def _vai(cid, name, start, target, mc):
    return CommandDef(cid, name, _V32, Kind.VAI, needs_homing=True, drives=_BOTH, start=start, target=target,
                      source=f"[MC] 4.3.{mc}")


def _vai16(cid, name, start, target, mc):
    return CommandDef(cid, name, _V16, Kind.VAI_16BIT, needs_homing=True, start=start, target=target,
                      source=f"[MC] 4.3.{mc}")


def _predef(cid, name, start, target, mc):
    return CommandDef(cid, name, _P32, Kind.PREDEF_VAI, needs_homing=True, drives=_BOTH, start=start,
                      target=target, source=f"[MC] 4.3.{mc}")


_D, _A, _R = Start.DEMAND, Start.ACTUAL, Start.ACTUAL_AT_REST
register(
    _vai(VAI_GO_TO_POS, "VAI Go To Pos", _D, Target.ABSOLUTE, 9),
    _vai(VAI_INCREMENT_DEM_POS, "VAI Increment Dem Pos", _D, Target.FROM_START, 10),
    _vai(VAI_INCREMENT_TARGET_POS, "VAI Increment Target Pos", _D, Target.FROM_LAST_TARGET, 11),
    _vai(VAI_GO_TO_POS_FROM_ACT_POS_AND_VEL, "VAI Go To Pos From Act Pos And Act Vel", _A, Target.ABSOLUTE, 12),
    _vai(VAI_GO_TO_POS_FROM_ACT_POS_VEL_0, "VAI Go To Pos From Act Pos Starting With Dem Vel = 0", _R,
         Target.ABSOLUTE, 13),
    # INFERRED (docs/emulator.md): the increment on the actual position starts at rest like 016xh
    _vai(VAI_INCREMENT_ACT_POS, "VAI Increment Act Pos", _R, Target.FROM_START, 14),
    _vai(VAI_INCREMENT_ACT_POS_VEL_0, "VAI Increment Act Pos Starting With Dem Vel = 0", _R, Target.FROM_START, 15),
    CommandDef(VAI_STOP, "VAI Stop", (Field("dec", "UDINT", "1E-5 m/s^2"),), Kind.VAI, drives=_BOTH,
               target=Target.STOP, source="[MC] 4.3.16"),
    _predef(PREDEF_VAI_GO_TO_POS, "Predef VAI Go To Pos", _D, Target.ABSOLUTE, 25),
    _predef(PREDEF_VAI_INCREMENT_DEM_POS, "Predef VAI Increment Dem Pos", _D, Target.FROM_START, 26),
    _predef(PREDEF_VAI_INCREMENT_TARGET_POS, "Predef VAI Increment Target Pos", _D, Target.FROM_LAST_TARGET, 27),
    # decelerates with the quick-stop deceleration
    CommandDef(PREDEF_VAI_STOP, "Predef VAI Stop", (), Kind.PREDEF_VAI, drives=_BOTH, target=Target.STOP,
               source="[MC] 4.3.30"),
    _vai16(VAI16_GO_TO_POS, "VAI 16 Bit Go To Pos", _D, Target.ABSOLUTE, 73),
    _vai16(VAI16_INCREMENT_DEM_POS, "VAI 16 Bit Increment Dem Pos", _D, Target.FROM_START, 74),
    _vai16(VAI16_INCREMENT_TARGET_POS, "VAI 16 Bit Increment Target Pos", _D, Target.FROM_LAST_TARGET, 75),
    CommandDef(VAI16_STOP, "VAI 16 Bit Stop", (Field("dec", "UINT", "16-bit acceleration scaling"),),
               Kind.VAI_16BIT, target=Target.STOP, source="[MC] 4.3.80"),
)
