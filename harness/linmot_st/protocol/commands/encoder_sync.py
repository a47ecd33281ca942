"""Position indexing, winding and force control (seed 004 TOC; [MC] 4.3.69..72, 4.3.213..222): the motions that
follow a signal from outside the axis, the master encoder or a force sensor.

- Position indexing 070xh..07Fxh ([MC] 4.3.69..72): the target follows the master-encoder counter through a VAI;
  07Exh/07Fxh end it with a VAI / predefined VAI go-to.
- Winding: 304h, 305h, 310h, 311h from [MC] 4.3.213..216 (headers and 310h/311h's fields only). 300h/301h
  (winding with the default parameters, no curve) are in the seed's TOC only (4.3.139/140), with no layout:
  INFERRED as 310h/311h without the curve ID (300h none, 301h the revolutions to start at), run by the same
  winding model with a triangular traverse (docs/emulator.md 13.10).
- Force control 380xh..385xh ([MC] 4.3.217..222, "F": the Force Control software key); 383xh/385xh switch to
  the command's target force at the limit, the others to the limit itself.
E1100 only (the B1100 column of [MC] 4.2 has none of them).
"""

from __future__ import annotations

from .row import CommandDef, Field, Kind, register

START_VAI_ENCODER_POSITION_INDEXING = 0x070
START_PREDEF_VAI_ENCODER_POSITION_INDEXING = 0x071
STOP_POSITION_INDEXING_VAI_GO_TO_POS = 0x07E
STOP_POSITION_INDEXING_PREDEF_VAI_GO_TO_POS = 0x07F
WINDING_START = 0x300
WINDING_START_AT_REVOLUTIONS = 0x301
WINDING_STOP_ADAPTATION = 0x304
WINDING_RESTART_ADAPTATION = 0x305
CURVE_WINDING_START = 0x310
CURVE_WINDING_START_AT_REVOLUTIONS = 0x311
FORCE_VAI_HIGHER_LIMIT = 0x380
FORCE_VAI_FROM_ACT_POS_RESET = 0x381
FORCE_CHANGE_TARGET_FORCE = 0x382
FORCE_VAI_LOWER_LIMIT = 0x384
FORCE_VAI_HIGHER_LIMIT_TARGET_FORCE = 0x383
FORCE_VAI_LOWER_LIMIT_TARGET_FORCE = 0x385

_V32 = (Field("target", "DINT", "0.1 um"), Field("vmax", "UDINT", "1E-6 m/s"), Field("acc", "UDINT", "1E-5 m/s^2"),
        Field("dec", "UDINT", "1E-5 m/s^2"))
_P32 = (Field("target", "DINT", "0.1 um"),)
_REVS = Field("revolutions", "DINT", "revolutions")
_ID = Field("curve_id", "UINT")


def _row(cid, name, fields, kind, source, homing=True):
    return CommandDef(cid, name, fields, kind, needs_homing=homing, source=source)


_I, _W, _F = Kind.POSITION_INDEXING, Kind.WINDING, Kind.FORCE_CONTROL
register(
    _row(START_VAI_ENCODER_POSITION_INDEXING, "Start VAI Encoder Position Indexing", _V32, _I, "[MC] 4.3.69"),
    _row(START_PREDEF_VAI_ENCODER_POSITION_INDEXING, "Start Predef VAI Encoder Position Indexing", _P32, _I,
         "[MC] 4.3.70"),
    _row(STOP_POSITION_INDEXING_VAI_GO_TO_POS, "Stop Position Indexing and VAI Go To Pos", _V32, _I, "[MC] 4.3.71"),
    _row(STOP_POSITION_INDEXING_PREDEF_VAI_GO_TO_POS, "Stop Position Indexing and Predef VAI Go To Pos", _P32, _I,
         "[MC] 4.3.72"),
    _row(WINDING_STOP_ADAPTATION, "Encoder Winding Stop Adaptation Of Left/Right Position and Disturbance", (), _W,
         "[MC] 4.3.213", homing=False),
    _row(WINDING_RESTART_ADAPTATION, "Encoder Winding Restart Adaptation Of Left/Right Position and Disturbance",
         (), _W, "[MC] 4.3.214", homing=False),
    _row(WINDING_START, "Encoder Winding Start With Default Parameters", (), _W,
         "seed 004 4.3.139 (TOC only; layout INFERRED: 310h without the curve)"),
    _row(WINDING_START_AT_REVOLUTIONS, "Encoder Winding Start With Default Parameters At Revolutions", (_REVS,), _W,
         "seed 004 4.3.140 (TOC only; layout INFERRED: 311h without the curve)"),
    _row(CURVE_WINDING_START, "Encoder Curve Winding Start With Default Parameters", (_ID,), _W, "[MC] 4.3.215"),
    _row(CURVE_WINDING_START_AT_REVOLUTIONS, "Encoder Curve Winding Start With Default Parameters At Revolutions",
         (_ID, _REVS), _W, "[MC] 4.3.216"),
    _row(FORCE_VAI_HIGHER_LIMIT, "VAI Go To Pos With Higher Force Ctrl Limit",
         _V32[:3] + (Field("force_limit", "UINT", "0.1 N"),), _F, "[MC] 4.3.217"),
    _row(FORCE_VAI_FROM_ACT_POS_RESET, "VAI Go To Pos From Act Pos And Reset Force Control", _V32, _F,
         "[MC] 4.3.218"),
    _row(FORCE_CHANGE_TARGET_FORCE, "Force Ctrl Change Target Force", (Field("target_force", "INT", "0.1 N"),), _F,
         "[MC] 4.3.219", homing=False),
    _row(FORCE_VAI_LOWER_LIMIT, "VAI Go To Pos With Lower Force Ctrl Limit",
         _V32[:3] + (Field("force_limit", "INT", "0.1 N"),), _F, "[MC] 4.3.221"),
    _row(FORCE_VAI_HIGHER_LIMIT_TARGET_FORCE, "VAI Go To Pos With Higher Force Ctrl Limit and Target Force",
         _V32[:3] + (Field("force_limit", "INT", "0.1 N"), Field("target_force", "INT", "0.1 N")), _F,
         "[MC] 4.3.220"),
    _row(FORCE_VAI_LOWER_LIMIT_TARGET_FORCE, "VAI Go To Pos With Lower Force Ctrl Limit and Target Force",
         _V32[:3] + (Field("force_limit", "INT", "0.1 N"), Field("target_force", "INT", "0.1 N")), _F,
         "[MC] 4.3.222"),
)
