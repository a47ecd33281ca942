"""The MC variables of the master encoder, the encoder cams and the force sensor (status.py asks here for the
UPIDs it does not know)."""

from __future__ import annotations

from ....protocol.upids import V_ACTUAL_FORCE, V_CAM_ENABLED, V_MASTER_ENCODER_COUNTS, V_MASTER_ENCODER_SPEED
from .encoder_cams import cam_operating
from .force_control import force_variable


def sync_variable(mc, upid: int) -> int | None:
    """The variables of the master encoder, the cams and the force sensor (None: not one of them)."""
    if upid == V_MASTER_ENCODER_COUNTS:
        return _s32(mc.encoder.counts(mc._now))
    if upid == V_MASTER_ENCODER_SPEED:
        return _s32(round(mc.encoder.speed(mc._now)))
    if upid == V_CAM_ENABLED:
        return int(cam_operating(mc))
    if upid == V_ACTUAL_FORCE:
        return force_variable(mc)
    return None


def _s32(v: int) -> int:
    return (int(v) + (1 << 31)) % (1 << 32) - (1 << 31)
