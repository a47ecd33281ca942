"""Commands run on a trigger edge of X4.6 (the event handler, [MC] 4.3.6, 7.2.2; spec/linmot-motion-commands.md
2.1, 2.12, 2.14), and the VAI commands whose target comes from an input: the captured position (X4.5, 0D0xh)
and the analog input (X4.4, 019xh); the Trig Rise/Fall Config VAI commands (0DExh/0DFxh); the command-table
waits for a trigger edge (213xh/214xh).

An "On Rising/Falling Trigger Event" command does not move at once: it is armed in the event handler (status
word bit 8) and its plain counterpart runs on every such edge until 008xh clears the handler. `TRIGGERED` says
per ID which edge and what runs: a VAI of one family (the field values read as that family's units), a time
curve (the row of the plain command, whose fields it shares) or a command-table entry.
Layouts: [MC] 4.3 (section per row); the E1100 has them by the seed's TOC, the B1100 those of master IDs 01h/02h
(seed 004 4.2's overview, row.seed_drives).
"""

from __future__ import annotations

import enum
from dataclasses import dataclass

from .command_table import START_COMMAND_TABLE
from .curves import TIME_CURVE_OFFSET_TIME_AMP, TIME_CURVE_TO_POS, TIME_CURVE_TO_POS_TIME
from .row import CommandDef, Field, Kind, Start, Target, register, seed_drives


class Units(enum.Enum):
    """How a triggered VAI's fields read (the family of its plain counterpart)."""
    V32 = "target, vmax, acc, dec in the drive's units"
    V16 = "target, vmax, acc, dec in the 16-bit interface scaling"
    P32 = "target (0.1 um); vmax, acc, dec predefined (14BEh..14C0h)"
    P16 = "target in the 16-bit scaling; vmax, acc, dec predefined"
    PA = "target, vmax; acc and dec predefined (14BFh/14C0h, INFERRED)"
    DA = "target, vmax, acc = dec"


@dataclass(frozen=True)
class Trigger:
    rising: bool
    units: Units | None = None          # a VAI: how its fields read
    base: int | None = None             # else the plain command that runs (a time curve, 200xh)


TRIGGERED: dict[int, Trigger] = {}

_V32 = (Field("target", "DINT", "0.1 um"), Field("vmax", "UDINT", "1E-6 m/s"), Field("acc", "UDINT", "1E-5 m/s^2"),
        Field("dec", "UDINT", "1E-5 m/s^2"))
_V16 = (Field("target", "INT", "16-bit position scaling"), Field("vmax", "UINT", "16-bit velocity scaling"),
        Field("acc", "UINT", "16-bit acceleration scaling"), Field("dec", "UINT", "16-bit acceleration scaling"))
_FIELDS = {
    Units.V32: _V32,
    Units.V16: _V16,
    Units.P32: (Field("target", "DINT", "0.1 um"),),
    Units.P16: (Field("target", "INT", "16-bit position scaling"),),     # 0ACxh: [MC] prints SInt32 (a slip)
    Units.PA: (Field("target", "DINT", "0.1 um"), Field("vmax", "UDINT", "1E-6 m/s")),
    Units.DA: (Field("target", "DINT", "0.1 um"), Field("vmax", "UDINT", "1E-6 m/s"),
               Field("acc", "UDINT", "1E-5 m/s^2")),
}


def _vai(cid: int, name: str, units: Units, rising: bool, increment: bool, mc: int) -> CommandDef:
    TRIGGERED[cid] = Trigger(rising, units=units)
    return CommandDef(cid, name, _FIELDS[units], Kind.ON_TRIGGER, needs_homing=True, start=Start.DEMAND,
                      target=Target.FROM_LAST_TARGET if increment else Target.ABSOLUTE, drives=seed_drives(cid),
                      source=f"[MC] 4.3.{mc}")


def _family(first: int, prefix: str, units: Units, mc: int) -> list[CommandDef]:
    """The four trigger variants xAh..xDh of a VAI family: go to / increment target, rising / falling."""
    return [
        _vai(first, f"{prefix} Go To Pos On Rising Trigger Event", units, True, False, mc),
        _vai(first + 1, f"{prefix} Increment Target Pos On Rising Trigger Event", units, True, True, mc + 1),
        _vai(first + 2, f"{prefix} Go To Pos On Falling Trigger Event", units, False, False, mc + 2),
        _vai(first + 3, f"{prefix} Increment Target Pos On Falling Trigger Event", units, False, True, mc + 3),
    ]


def _based(cid: int, name: str, base: int, rising: bool, fields: tuple[Field, ...], mc: int,
           target: Target = Target.NONE) -> CommandDef:
    TRIGGERED[cid] = Trigger(rising, base=base)
    return CommandDef(cid, name, fields, Kind.ON_TRIGGER, needs_homing=True, target=target,
                      source=f"[MC] 4.3.{mc}")


_ID = Field("curve_id", "UINT")
_TARGET = Field("target", "DINT", "0.1 um")
_TIME = Field("curve_time", "DINT", "10 us")
_CURVE_OTA = (_ID, Field("offset", "DINT", "0.1 um"), _TIME, Field("amplitude", "INT", "0.1 %"))

VAI_GO_TO_ANALOG_POS = 0x019
VAI_INCREMENT_CAPTURED_POS = 0x0D0
VAI_START_TRIG_RISE_CONFIG = 0x0DE
VAI_START_TRIG_FALL_CONFIG = 0x0DF
START_COMMAND_TABLE_ON_RISE = 0x201
START_COMMAND_TABLE_ON_FALL = 0x202
WAIT_RISING_TRIGGER = 0x213
WAIT_FALLING_TRIGGER = 0x214

register(
    *_family(0x01A, "VAI", Units.V32, 19),
    *_family(0x02A, "Predef VAI", Units.P32, 32),
    *_family(0x09A, "VAI 16 Bit", Units.V16, 82),
    *_family(0x0AA, "Predef VAI 16 Bit", Units.P16, 95),
    *_family(0x0BA, "VAI Predef Acc", Units.PA, 105),
    *_family(0x0CA, "VAI Dec=Acc", Units.DA, 118),
    _based(0x046, "Time Curve With Adj. Offset, Time & Amplitude Scale On Rising Trigger Event",
           TIME_CURVE_OFFSET_TIME_AMP, True, _CURVE_OTA, 51, Target.ABSOLUTE),
    _based(0x047, "Time Curve With Adj. Offset, Time & Amplitude Scale On Falling Trigger Event",
           TIME_CURVE_OFFSET_TIME_AMP, False, _CURVE_OTA, 52, Target.ABSOLUTE),
    _based(0x04A, "Time Curve To Pos With Default Speed On Rising Trigger Event", TIME_CURVE_TO_POS, True,
           (_ID, _TARGET), 53, Target.FROM_START),
    _based(0x04C, "Time Curve To Pos With Default Speed On Falling Trigger Event", TIME_CURVE_TO_POS, False,
           (_ID, _TARGET), 54, Target.FROM_START),
    _based(0x04E, "Time Curve To Pos With Adjustable Time On Rising Trigger Event", TIME_CURVE_TO_POS_TIME, True,
           (_ID, _TARGET, _TIME), 55, Target.FROM_START),
    _based(0x04F, "Time Curve To Pos With Adjustable Time On Falling Trigger Event", TIME_CURVE_TO_POS_TIME,
           False, (_ID, _TARGET, _TIME), 56, Target.FROM_START),
    _based(START_COMMAND_TABLE_ON_RISE, "Start Command Table Command On Rising Trigger Event",
           START_COMMAND_TABLE, True, (Field("entry", "UINT"),), 164),
    _based(START_COMMAND_TABLE_ON_FALL, "Start Command Table Command On Falling Trigger Event",
           START_COMMAND_TABLE, False, (Field("entry", "UINT"),), 165),
    CommandDef(VAI_GO_TO_ANALOG_POS, "VAI Go To Analog Pos",
               (Field("vmax", "UDINT", "1E-6 m/s"), Field("acc", "UDINT", "1E-5 m/s^2"),
                Field("dec", "UDINT", "1E-5 m/s^2")), Kind.VAI_ANALOG, needs_homing=True, target=Target.ABSOLUTE,
               drives=seed_drives(VAI_GO_TO_ANALOG_POS), source="[MC] 4.3.18"),
    CommandDef(VAI_INCREMENT_CAPTURED_POS, "VAI Increment Captured Pos", _V32, Kind.VAI_CAPTURED,
               needs_homing=True, target=Target.ABSOLUTE, source="[MC] 4.3.122 (capture variable 1E62h: 4.3.123's text)"),
    # [MC] 4.3.128/129: "starts the VAI motion command defined with the parameters in Trig Rise (Fall) Config"
    CommandDef(VAI_START_TRIG_RISE_CONFIG, "VAI Start Trig Rise Config VAI Command", (), Kind.VAI_TRIG_CONFIG,
               needs_homing=True, target=Target.ABSOLUTE, source="[MC] 4.3.128"),
    CommandDef(VAI_START_TRIG_FALL_CONFIG, "VAI Start Trig Fall Config VAI Command", (), Kind.VAI_TRIG_CONFIG,
               needs_homing=True, target=Target.ABSOLUTE, source="[MC] 4.3.129"),
    CommandDef(WAIT_RISING_TRIGGER, "Wait Until Rising Trigger Event", (), Kind.WAIT, source="[MC] 4.3.171"),
    CommandDef(WAIT_FALLING_TRIGGER, "Wait Until Falling Trigger Event", (), Kind.WAIT, source="[MC] 4.3.172"),
)
