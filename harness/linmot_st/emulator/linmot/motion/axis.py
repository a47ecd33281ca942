"""The axis: the slider that follows the demand position (INFERRED model, docs/emulator.md section 13).

Position controlled, the slider follows the demand as a second-order loop with velocity feedforward: the
following error e = demand - actual obeys e'' = (1 - kff) a_demand - w^2 e - 2 zeta w e', so it grows while the
demand accelerates (about a / w^2) and dies out at constant velocity and at rest. The loop is integrated exactly
over each MC cycle (the demand's acceleration taken as constant within it). Not controlled (power stage off),
the slider coasts to rest by friction. Two mechanical stops bound it. Tests can disturb it: `block()` holds it
where it is (an obstacle), `push(delta)` moves it.

Positions in pu (0.1 um) in the drive's frame; `offset` maps the slider's own frame to it (homing moves it).
"""

from __future__ import annotations

import math

from .settings import MotionSettings


def _expm(m: list[list[float]]) -> list[list[float]]:
    """exp(M) for a small matrix: scaling and squaring with a Taylor series (exact enough for 2x2/3x3)."""
    n = len(m)
    norm = max(sum(abs(x) for x in row) for row in m)
    k = max(0, int(math.ceil(math.log2(norm))) + 1) if norm > 0.5 else 0
    a = [[x / 2 ** k for x in row] for row in m]
    result = [[float(i == j) for j in range(n)] for i in range(n)]
    term = [row[:] for row in result]
    for i in range(1, 20):
        term = [[sum(term[r][q] * a[q][c] for q in range(n)) / i for c in range(n)] for r in range(n)]
        result = [[result[r][c] + term[r][c] for c in range(n)] for r in range(n)]
    for _ in range(k):
        result = [[sum(result[r][q] * result[q][c] for q in range(n)) for c in range(n)] for r in range(n)]
    return result


class Axis:
    def __init__(self, settings: MotionSettings):
        self.s = settings
        self.h = settings.cycle_ns * 1e-9
        w = 2 * math.pi * settings.bandwidth_hz
        z = settings.damping
        # error state [e, e'] with input u (constant over a cycle): exp of the augmented matrix gives Phi, Gamma
        ex = _expm([[0.0, self.h, 0.0], [-w * w * self.h, -2 * z * w * self.h, self.h], [0.0, 0.0, 0.0]])
        self._phi = (ex[0][0], ex[0][1], ex[1][0], ex[1][1])
        self._gam = (ex[0][2], ex[1][2])
        self._kff = settings.acc_feedforward
        # follow()'s constants as the quiet cycles inline it (fast_path.py), unpacked once per run
        self.follow_constants = (self.h, *self._phi, *self._gam, 1.0 - self._kff, settings.stop_negative_pu,
                                 settings.stop_positive_pu, settings.settle_pu)
        self.physical = float(settings.start_position_pu)   # the slider in its own frame
        self.offset = -self.physical                        # drive frame = physical + offset (0 at power-on)
        self.velocity = 0.0                                 # pu/s
        self.acceleration = 0.0
        self.blocked = False
        self.current_limit_ma: float | None = None          # the power stage's current limit (None: unlimited)

    # ---- the drive's frame ----
    @property
    def position(self) -> float:
        return self.physical + self.offset

    def reference(self, drive_position: float) -> None:
        """Homing: the slider's present position is `drive_position` from now on."""
        self.offset = drive_position - self.physical

    def forget_reference(self) -> None:
        """MC start: an incremental position starts at 0 where the slider is (INFERRED)."""
        self.offset = -self.physical

    # ---- test hooks ----
    def block(self, on: bool = True) -> None:
        self.blocked = on
        if on:
            self.velocity = 0.0

    def push(self, delta_pu: float) -> None:
        self.physical = self._clamp(self.physical + delta_pu)

    # ---- one MC cycle ----
    def follow(self, xd1: float, vd0: float, vd1: float) -> None:
        """Position controlled over one cycle, ending with the demand (xd1, vd1)."""
        p00, p01, p10, p11 = self._phi
        g0, g1 = self._gam
        e = xd1 - (vd1 - vd0) * self.h / 2 - vd0 * self.h - self.position   # error at the cycle start,
        ed = vd0 - self.velocity                                              # relative to the demand then
        u = (1.0 - self._kff) * (vd1 - vd0) / self.h
        e1 = p00 * e + p01 * ed + g0 * u
        ed1 = p10 * e + p11 * ed + g1 * u
        physical = xd1 - e1 - self.offset
        s = self.s
        if self.blocked or not s.stop_negative_pu <= physical <= s.stop_positive_pu:
            self._move_to(physical, vd1 - ed1)
            return
        v1 = vd1 - ed1                      # the common case, _move_to inlined (the hottest loop of the model)
        if self.current_limit_ma is not None:
            # the current limit bounds the force, so the acceleration (the fast path is off while it is set)
            a_max = self.current_limit_ma * 1e-3 * s.force_constant_n_per_a / s.moving_mass_kg * 1e7
            a = (v1 - self.velocity) / self.h
            if abs(a) > a_max:
                v1 = self.velocity + (a_max if a > 0 else -a_max) * self.h
                self._move_to(self.physical + (self.velocity + v1) * self.h / 2, v1)
                return
        self.acceleration = (v1 - self.velocity) / self.h
        self.physical, self.velocity = physical, v1

    def coast(self) -> None:
        """Power stage off: friction slows the slider down."""
        v, dv = self.velocity, self.s.coast_decel_pu_s2 * self.h
        v1 = 0.0 if abs(v) <= dv else v - math.copysign(dv, v)
        self._move_to(self.physical + (v + v1) * self.h / 2, v1)

    def _move_to(self, physical: float, velocity: float) -> None:
        v0 = self.velocity
        if self.blocked:
            physical, velocity = self.physical, 0.0
        clamped = self._clamp(physical)
        if clamped != physical:
            velocity = 0.0                  # on a mechanical stop
        self.physical = clamped
        self.velocity = velocity
        self.acceleration = (velocity - v0) / self.h

    def _clamp(self, physical: float) -> float:
        return min(max(physical, self.s.stop_negative_pu), self.s.stop_positive_pu)

    def at_rest(self, demand: float) -> bool:
        tol = self.s.settle_pu
        return abs(demand - self.position) < tol and abs(self.velocity) * 1e-3 < tol

    def settle(self, demand: float) -> None:
        """At rest: snap to the demand (the remaining error is below the model's resolution)."""
        if not self.blocked:
            self.physical = self._clamp(demand - self.offset)
        self.velocity = 0.0
        self.acceleration = 0.0

    def demand_current_ma(self) -> float:
        return self.s.moving_mass_kg * self.acceleration * 1e-7 / self.s.force_constant_n_per_a * 1000.0
