"""Encoder cams (seed 004 TOC 5.3; [MC] 4.3.63..68, 4.3.150..162, 5.5): the axis follows a cam curve (object type
0103h: x in master-encoder increments) as the master encoder turns. Two cams (y = 1, 2: IDs 11xh, 12xh) are
defined from a curve ID and a start count, optionally scaled to a target, an amplitude and a length in counts;
100xh/101xh switch the cam operation on and off, 102xh moves to the synchronised position, 104xh sets the counter.
069xh..06Exh arm a one-shot cam on an edge of the trigger input, after a delay in counts.

No cam motions on the B1100 ([MC] 5.5 "Cam motions are not available in the B1100 drives"): E1100 only.
1y3xh (Define Curve From Pos To Pos In Counts) has five parameters: the ST encoder takes four, so it is not in
the catalogue yet (docs/emulator.md).
"""

from __future__ import annotations

from .row import CommandDef, Field, Kind, register

ENCODER_CAM_ENABLE = 0x100
ENCODER_CAM_DISABLE = 0x101
ENCODER_CAM_GO_TO_SYNC_POS = 0x102
ENCODER_CAM_SET_VALUE = 0x104
TRIG_CAM_RISE = 0x069
TRIG_CAM_RISE_TARGET_LENGTH = 0x06A
TRIG_CAM_FALL = 0x06B
TRIG_CAM_FALL_TARGET_LENGTH = 0x06C
TRIG_CAM_RISE_AMPLITUDE_LENGTH = 0x06D
TRIG_CAM_FALL_AMPLITUDE_LENGTH = 0x06E

# the cam-y commands: ID = 0x100 | y << 4 | sub ([MC] 4.3.154..162)
CAM_DEFINE_DEFAULT, CAM_DEFINE_FROM_ACT_POS, CAM_DEFINE_TO_POS = 0x0, 0x1, 0x2
CAM_DEFINE_TO_POS_IN_COUNTS, CAM_DEFINE_AMPLITUDE_IN_COUNTS = 0x4, 0x5
CAM_Y_ENABLE, CAM_Y_DISABLE, CAM_Y_CHANGE_AMPLITUDE_LENGTH = 0x6, 0x7, 0x8
CAMS = (1, 2)


def cam_command(y: int, sub: int) -> int:
    """The ID of a cam-y command (y = 1, 2)."""
    return 0x100 | y << 4 | sub


_ID = Field("curve_id", "UINT")
_START = Field("start_count", "DINT", "increments")
_TARGET = Field("target", "DINT", "0.1 um")
_AMPLITUDE = Field("amplitude", "INT", "0.1 %")
_LENGTH = Field("cam_length", "DINT", "increments")
_DELAY_U32 = Field("delay", "UDINT", "increments")
_DELAY = Field("delay", "DINT", "increments")


def _cam(cid, name, fields, mc, homing=False):
    return CommandDef(cid, name, fields, Kind.ENCODER_CAM, needs_homing=homing, source=f"[MC] 4.3.{mc}")


def _trig(cid, name, fields, mc):
    return CommandDef(cid, name, fields, Kind.TRIGGERED_CAM, needs_homing=True, source=f"[MC] 4.3.{mc}")


register(
    _trig(TRIG_CAM_RISE, "Setup Encoder Cam On Rising Trigger Event With Delay Counts", (_ID, _DELAY_U32), 63),
    _trig(TRIG_CAM_RISE_TARGET_LENGTH, "Setup Encoder Cam On Rising Trigger Event With Delay Counts, Target Pos "
          "and Length", (_ID, _DELAY, _TARGET, _LENGTH), 64),
    _trig(TRIG_CAM_FALL, "Setup Encoder Cam On Falling Trigger Event With Delay Counts", (_ID, _DELAY_U32), 65),
    _trig(TRIG_CAM_FALL_TARGET_LENGTH, "Setup Encoder Cam On Falling Trigger Event With Delay Counts, Target Pos "
          "and Length", (_ID, _DELAY, _TARGET, _LENGTH), 66),
    _trig(TRIG_CAM_RISE_AMPLITUDE_LENGTH, "Setup Encoder Cam On Rising Trigger Event With Delay Counts, Amplitude "
          "scale and Length", (_ID, _DELAY, _AMPLITUDE, _LENGTH), 67),
    _trig(TRIG_CAM_FALL_AMPLITUDE_LENGTH, "Setup Encoder Cam On Falling Trigger Event With Delay Counts, Amplitude "
          "scale and Length", (_ID, _DELAY, _AMPLITUDE, _LENGTH), 68),
    _cam(ENCODER_CAM_ENABLE, "Encoder Cam Enable", (), 150, homing=True),
    _cam(ENCODER_CAM_DISABLE, "Encoder Cam Disable", (), 151),
    _cam(ENCODER_CAM_GO_TO_SYNC_POS, "Encoder Cam Go To Sync Pos", (), 152, homing=True),
    _cam(ENCODER_CAM_SET_VALUE, "Encoder Cam Set Value", (Field("counter_value", "DINT", "increments"),), 153),
)
for _y in CAMS:
    register(
        _cam(cam_command(_y, CAM_DEFINE_DEFAULT), f"Encoder Cam {_y} Define Curve With Default Parameters",
             (_ID, _START), 154),
        _cam(cam_command(_y, CAM_DEFINE_FROM_ACT_POS), f"Encoder Cam {_y} Define Curve From Act Pos",
             (_ID, _START), 155),
        _cam(cam_command(_y, CAM_DEFINE_TO_POS), f"Encoder Cam {_y} Define Curve To Pos", (_ID, _START, _TARGET),
             156),
        _cam(cam_command(_y, CAM_DEFINE_TO_POS_IN_COUNTS), f"Encoder Cam {_y} Define Curve To Pos In Counts",
             (_ID, _START, _TARGET, _LENGTH), 158),
        _cam(cam_command(_y, CAM_DEFINE_AMPLITUDE_IN_COUNTS),
             f"Encoder Cam {_y} Define Curve With Amplitude Scale In Counts", (_ID, _START, _AMPLITUDE, _LENGTH), 159),
        _cam(cam_command(_y, CAM_Y_ENABLE), f"Encoder Cam {_y} Enable", (), 160),
        _cam(cam_command(_y, CAM_Y_DISABLE), f"Encoder Cam {_y} Disable", (), 161),
        _cam(cam_command(_y, CAM_Y_CHANGE_AMPLITUDE_LENGTH), f"Encoder Cam {_y} Change Amplitude Scale and Length",
             (_AMPLITUDE, _LENGTH), 162),
    )
