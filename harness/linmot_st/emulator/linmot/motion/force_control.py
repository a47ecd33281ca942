"""Force control (380xh..384xh, [MC] 4.3.217..221; the Force Control software key) and the force sensor it reads.

The sensor (INFERRED model, MotionSettings): a contact at force_contact_pu; beyond it (towards positive
positions) a spring of force_stiffness_n_per_mm; the measured force = spring force + Gaussian noise
(force_noise_n, seeded). It is published as the actual force 1BFFh (0.1 N).

380xh/384xh: a VAI motion to the target (deceleration = acceleration: the command has none, INFERRED); when the
measured force rises to (380xh, "higher") or falls to (384xh, "lower") the force limit, the drive changes to
force control with target force = the limit. In force control the demand moves by force_control_gain x (target
force - measured force) per second (an integrating regulator, INFERRED) until 381xh returns to position control
(a VAI from the actual position). 382xh changes the target force.
"""

from __future__ import annotations

import random

from ....protocol import commands as C
from ....protocol.commands import CommandDef
from .setpoints import VaPlan
from .stepwise import StepwisePlan
from .units import ACC_RAW, VEL_RAW

N_PER_MM_TO_N_PER_PU = 1e-4


class ForceSensor:
    def __init__(self, settings):
        self.contact = settings.force_contact_pu
        self.stiffness = settings.force_stiffness_n_per_mm * N_PER_MM_TO_N_PER_PU      # N per pu
        self.noise = settings.force_noise_n
        self._rng = random.Random(settings.force_noise_seed)
        self.last_n = 0.0

    def force(self, position: float) -> float:
        """The true force on the slider at `position` (N)."""
        if self.contact is None or position <= self.contact:
            return 0.0
        return (position - self.contact) * self.stiffness

    def measure(self, position: float) -> float:
        f = self.force(position)
        if self.noise:
            f += self._rng.gauss(0.0, self.noise)
        self.last_n = f
        return f


def sensor_of(mc) -> ForceSensor:
    s = getattr(mc, "_force_sensor", None)
    if s is None:
        s = mc._force_sensor = ForceSensor(mc.s)
    return s


class ForcePlan(StepwisePlan):
    """A VAI move watching the measured force, then force control."""

    kind = "force"

    def __init__(self, mc, t: int, target: float, vmax: float, acc: float, limit_n: float, higher: bool,
                 target_force_n: float | None = None):
        p, v, _ = mc.gen.at(t)
        super().__init__(t, p, v, mc.s.cycle_ns)
        self.mc, self.sensor = mc, sensor_of(mc)
        self.move = VaPlan(t, p, v, target, vmax, acc, acc)
        self.target = float(target)
        self.limit, self.higher = limit_n, higher
        self.force_after_limit = limit_n if target_force_n is None else target_force_n
        self.target_force: float | None = None          # None: still moving in position control
        self.gain = mc.s.force_control_gain_pu_per_n_s

    @property
    def force_control(self) -> bool:
        return self.target_force is not None

    def step(self, t_ns, p, v, dt):
        measured = self.sensor.measure(self.mc.axis.position)
        if self.target_force is None:
            if (measured >= self.limit) if self.higher else (measured <= self.limit):
                # [MC] 4.3.217/221: the target force is the limit; 4.3.220/222: the command's target force
                self.target_force = self.force_after_limit
            else:
                p1, v1, _ = self.move.at(t_ns)
                return p1, v1
        v1 = self.gain * (self.target_force - measured)
        self.target = p + v1 * dt
        return self.target, v1


def _force_control(mc, c: CommandDef, f: dict, t: int) -> bool:
    if c.cid == C.FORCE_CHANGE_TARGET_FORCE:
        if isinstance(mc.gen, ForcePlan) and mc.gen.force_control:
            mc.gen.target_force = f["target_force"] / 10.0
        return True                                       # INFERRED: outside force control it changes nothing
    if c.cid == C.FORCE_VAI_FROM_ACT_POS_RESET:
        mc._vai(t, mc.axis.position, mc.axis.velocity, f["target"], f["vmax"] * VEL_RAW, f["acc"] * ACC_RAW,
                f["dec"] * ACC_RAW)
        return True
    higher = c.cid in (C.FORCE_VAI_HIGHER_LIMIT, C.FORCE_VAI_HIGHER_LIMIT_TARGET_FORCE)
    target_force = f["target_force"] / 10.0 if "target_force" in f else None
    mc._start(ForcePlan(mc, t, f["target"], f["vmax"] * VEL_RAW, f["acc"] * ACC_RAW, f["force_limit"] / 10.0,
                        higher=higher, target_force_n=target_force))
    return True


def force_variable(mc) -> int:
    """1BFFh: the last measured force in 0.1 N."""
    return int(round(sensor_of(mc).last_n * 10))


HANDLERS = {C.Kind.FORCE_CONTROL: _force_control}
