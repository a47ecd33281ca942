"""The event handler's VAI part ([MC] 4.3.6, 4.3.17, 4.3.23/24; spec/linmot-motion-commands.md 2.3, 2.4): a
motion queued by a "Go To Pos After Actual Command" and a position transition armed by "Change Motion
Parameters On Positive/Negative Position Transition". A part of MotionControl (control.py): `step` runs in
every MC cycle while anything is armed (the cycle keeps running and the fast path steps aside), and status word
bit 8 / state var bit 4 show the handler active.

- The queued motion starts in the first MC cycle after a status word showed Motion Active 0 ([MC] 4.3.134/144:
  the handler starts it "as soon as" bit 13 is 0, then switches itself off: one shot); it starts from the
  demand position, at rest.
- A transition fires in the first cycle whose demand position has passed the transition position in its
  direction: the running VA motion continues to its target with the new vmax/acc/dec (one shot, INFERRED). A
  transition while no VA motion runs fires without effect (INFERRED).
- Both are dropped when the drive leaves Operation Enabled, and by Clear Event Evaluation (008xh: `clear`).
"""

from __future__ import annotations

from dataclasses import dataclass

from ....protocol import words as W
from .setpoints import VaPlan


@dataclass
class _Queued:
    target: float
    vmax: float
    acc: float
    dec: float


@dataclass
class _Transition:
    position: float
    upwards: bool
    vmax: float
    acc: float
    dec: float
    last_p: float


class PendingMotions:
    def __init__(self) -> None:
        self.queued: _Queued | None = None
        self.transition: _Transition | None = None

    @property
    def armed(self) -> bool:
        return self.queued is not None or self.transition is not None

    def clear(self) -> None:
        self.queued = self.transition = None

    def queue(self, target: float, vmax: float, acc: float, dec: float) -> None:
        self.queued = _Queued(float(target), vmax, acc, dec)

    def arm_transition(self, position: float, upwards: bool, vmax: float, acc: float, dec: float,
                       demand: float) -> None:
        self.transition = _Transition(float(position), upwards, vmax, acc, dec, float(demand))

    def step(self, mc, t: int) -> None:
        """One MC cycle at t, after the demand (mc.dem_p, mc.dem_v) of t is computed."""
        if mc.state != W.OPERATION_ENABLED or not mc.controlled:
            self.clear()
            return
        tr = self.transition
        if tr is not None:
            p = mc.dem_p
            crossed = tr.last_p < tr.position <= p if tr.upwards else tr.last_p > tr.position >= p
            tr.last_p = p
            if crossed:
                self.transition = None
                if isinstance(mc.gen, VaPlan) and mc.gen.kind == "vai" and not mc.gen.done(t):
                    mc._vai(t, p, mc.dem_v, mc.gen.target, tr.vmax, tr.acc, tr.dec)
        q = self.queued
        # the status word last shown (the previous cycle's or event's: this cycle's is not made yet)
        if q is not None and not mc.words[0] & W.SW_MOTION_ACTIVE:
            self.queued = None
            mc._vai(t, mc.dem_p, 0.0, q.target, q.vmax, q.acc, q.dec)
