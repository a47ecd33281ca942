"""Time curves (seed 004 4.2 master ID 04h; [MC] 4.3.45..50): a position/time curve from the curve RAM. The
fields name what the command sets (offset, curve_time, time_scale, amplitude, target); what it leaves out comes
from the curve parameters. Seed 004 4.2 marks the E1100; the B1100 column is garbled (the library treats
curves as unsupported on the B1100, ErrorID NotSupported)."""

from __future__ import annotations

from .row import CommandDef, Field, Kind, Target, register

TIME_CURVE = 0x040
TIME_CURVE_FROM_ACT_POS = 0x041
TIME_CURVE_TO_POS = 0x042
TIME_CURVE_TO_POS_TIME = 0x043
TIME_CURVE_OFFSET_TIME_SCALE_AMP = 0x044
TIME_CURVE_OFFSET_TIME_AMP = 0x045

_ID = Field("curve_id", "UINT")
_TARGET = Field("target", "DINT", "0.1 um")
_OFFSET = Field("offset", "DINT", "0.1 um")
_TIME = Field("curve_time", "DINT", "10 us")
_AMPLITUDE = Field("amplitude", "INT", "0.1 %")


def _curve(cid, name, fields, target, mc):
    return CommandDef(cid, name, fields, Kind.TIME_CURVE, needs_homing=True, target=target,
                      source=f"[MC] 4.3.{mc}")


register(
    _curve(TIME_CURVE, "Time Curve With Default Parameters", (_ID,), Target.ABSOLUTE, 45),
    _curve(TIME_CURVE_FROM_ACT_POS, "Time Curve With Default Parameters From Act Pos", (_ID,), Target.FROM_START, 46),
    _curve(TIME_CURVE_TO_POS, "Time Curve To Pos With Default Speed", (_ID, _TARGET), Target.FROM_START, 47),
    _curve(TIME_CURVE_TO_POS_TIME, "Time Curve To Pos With Adjustable Time", (_ID, _TARGET, _TIME),
           Target.FROM_START, 48),
    _curve(TIME_CURVE_OFFSET_TIME_SCALE_AMP, "Time Curve With Adj. Offset, Time Scale & Amplitude Scale",
           (_ID, _OFFSET, Field("time_scale", "UINT", "0.01 %"), _AMPLITUDE), Target.ABSOLUTE, 49),
    _curve(TIME_CURVE_OFFSET_TIME_AMP, "Time Curve With Adj. Offset, Time & Amplitude Scale",
           (_ID, _OFFSET, _TIME, _AMPLITUDE), Target.ABSOLUTE, 50),
)
