"""Encoder position indexing (070xh..07Fxh, [MC] 4.3.69..72): "the actual encoder count is [linked] to the target
position" ([MC]'s wording is garbled). INFERRED: from the command on, the target is the command's target plus
MotionSettings.position_indexing_pu_per_count per master-encoder count counted since; the demand follows it
through a VA limiter with the command's (070xh) or the predefined (071xh) vmax/acc/dec. 07Exh/07Fxh (and any
other motion command) end it; 07Exh/07Fxh then go to their target with a VAI / predefined VAI.
"""

from __future__ import annotations

from ....protocol import commands as C
from ....protocol.commands import CommandDef
from .stepwise import StepwisePlan, track
from .units import ACC_RAW, VEL_RAW


class IndexingPlan(StepwisePlan):
    kind = "indexing"

    def __init__(self, mc, t: int, target: float, vmax: float, acc: float, dec: float):
        p, v, _ = mc.gen.at(t)
        super().__init__(t, p, v, mc.s.cycle_ns)
        self.encoder, self.scale = mc.encoder, mc.s.position_indexing_pu_per_count
        self.base, self.count0 = float(target), mc.encoder.counts(t)
        self.vmax, self.acc, self.dec = max(vmax, 1e-9), max(acc, 1e-9), max(dec, 1e-9)

    def index_target(self, t_ns: int) -> float:
        return self.base + self.scale * (self.encoder.counts(t_ns) - self.count0)

    def step(self, t_ns, p, v, dt):
        self.target = self.index_target(t_ns)
        return track(p, v, self.target, self.scale * self.encoder.rate(t_ns), dt, self.vmax, self.acc, self.dec)


def _values(mc, c: CommandDef, f: dict):
    if "vmax" in f:
        return f["target"], f["vmax"] * VEL_RAW, f["acc"] * ACC_RAW, f["dec"] * ACC_RAW
    return (f["target"], *mc._predef())


def _position_indexing(mc, c: CommandDef, f: dict, t: int) -> bool:
    target, vmax, acc, dec = _values(mc, c, f)
    if c.cid in (C.START_VAI_ENCODER_POSITION_INDEXING, C.START_PREDEF_VAI_ENCODER_POSITION_INDEXING):
        mc._start(IndexingPlan(mc, t, target, vmax, acc, dec))
        return True
    p, v, _ = mc.gen.at(t)            # 07Exh/07Fxh: stop indexing, go to the target
    mc._vai(t, p, v, target, vmax, acc, dec)
    return True


HANDLERS = {C.Kind.POSITION_INDEXING: _position_indexing}
