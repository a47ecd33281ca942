"""Quiet cycles: plain motion, or a special state's plan running (homing, jogging...), nothing for the state
machine to do. A part of MotionControl (control.py).

A cycle is quiet when the generic cycle would only move the setpoint and the axis and find every output word
(status, state var, warn, error) unchanged. Such cycles run in a tight loop, and, where no event-driven TxPDO
depends on them (pdo.cycle_sensitive), ahead of the bus: the drive then asks to be woken only at the first
cycle that is not quiet. tests/emulator/motion/test_motion_equivalence.py checks that frames and trajectory are the same as
with every cycle run one by one.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from itertools import islice
from operator import itemgetter

from ....protocol import words as W
from .trajectory import Sample

_PLAIN_STATES = frozenset({W.READY_TO_OPERATE, W.OPERATION_ENABLED, W.ABORTING, W.FREEZING})
# the special states (homing, jogging, going to a position...): quiet too while their plan runs, as their
# per-cycle step (_progress_special) then changes nothing; _quiet_run says when it would
_SPECIAL_STATES = frozenset(W.SPECIAL_STATES)
_CYCLE_TIME = itemgetter(0)     # the time of a cycle computed ahead (made once: _apply_ahead runs on every SYNC)


class FastPath:
    """Quiet cycles in a tight loop and ahead of the bus (a mixin of MotionControl)."""

    lookahead = True
    AHEAD_MAX = 2000                # cycles computed ahead at most; the horizon doubles while undisturbed
    _horizon = 8

    def _plain(self) -> bool:
        return (self.running and self.controlled and (self.state in _PLAIN_STATES or self.state in _SPECIAL_STATES)
                and self.after_stop is None
                and (not self.ct_runner.running or self.ct_runner.quiet_wait is not None)
                and not self.events.pending and not self.axis.blocked
                and not self._range1.ram and not self.pending.armed and self.axis.current_limit_ma is None
                and self._next_tick is not None and self.s.quiet_cycles
                and not getattr(self.gen, "stepwise", False))   # a plan computed cycle by cycle (stepwise.py)

    def _quiet_run(self, t_limit: int, entries: list | None = None, samples: list | None = None) -> bool:
        """Commit quiet cycles from the next tick up to t_limit; True when any ran. It stops before the first
        cycle that is not quiet: the generic cycle runs that one. `entries` collects each cycle's state and
        `samples` its trajectory sample (computing ahead); without them the samples go to the trajectory.

        The hottest loop of the model: the demand comes from the plan's `demands` walk, Axis.follow's
        arithmetic is inlined term for term (so every value is bit-identical to the generic cycle's; the
        equivalence tests compare them exactly), the state lives in locals and is written back once."""
        gen, axis = self.gen, self.axis
        cyc, t = self.s.cycle_ns, self._next_tick
        r_warn, r_err, r_st_warn, r_st_err = self._lag              # _monitor's parameters
        lag_warn, lag_err, st_warn, st_err = r_warn.ram, r_err.ram, r_st_warn.ram, r_st_err.ram
        enabled, negative, positive = self._limits
        state = self.state
        # a special state's step (_progress_special) acts when its plan ends (the next phase, or finished), and
        # in the homing search when the following error shows the mechanical stop; finished, it does nothing
        special = state in _SPECIAL_STATES and self.sub != W.SUB_FINISHED
        homing_search = special and state == W.HOMING and self._special_phase == 1
        limits = self.homed and state != W.HOMING and enabled.ram      # _monitor's condition
        lim_neg, lim_pos = negative.ram, positive.ram
        target_ok = state >= W.OPERATION_ENABLED
        window, hold = self.s.in_target_window_pu, self.s.in_target_hold_ns
        gen_target = gen.target
        # `active` (the setpoint generation runs) is the same in every quiet cycle of a run: the first cycle
        # where it changes is not quiet. It is the status word's Motion Active bit as last recorded, not the plan
        # at _now: _now may be a later observation time, and a plan that ended between the last cycle and it has
        # not cleared the bit yet (the next cycle does). A running command table holds the bit after the plan's
        # end too: the run still ends before the plan's end (the generic cycles take the table's waits from there).
        active = bool(self.words[0] & W.SW_MOTION_ACTIVE)
        if active:
            t_limit = min(t_limit, gen.end_ns - 1)      # a run while active ends before the plan's end
        elif t < gen.end_ns or special:
            return False                                # the plan runs again: the bit comes back; or the
                                                        # special state's plan ended: its step acts
        warn_bits, in_target, since, prev_vd = self.warn_bits, self.in_target, self._in_window_since, self._prev_vd
        if not limits:
            lim_neg, lim_pos = -math.inf, math.inf
        # while active: the warn word has no standing bit, the axis is never in the target window
        if active and (in_target or warn_bits & ~W.WARN_POS_LAG_ALWAYS):
            return False
        # while active, a cycle is quiet when lag_lo < err <= lag_hi (the always-warn bit and error unchanged)
        lag_lo = lag_warn if warn_bits & W.WARN_POS_LAG_ALWAYS else -1.0
        lag_hi = lag_err if warn_bits & W.WARN_POS_LAG_ALWAYS else min(lag_warn, lag_err)
        if homing_search:
            # _monitor sets no warn bit and checks no lag there; the search ends where err exceeds the stop error
            if warn_bits:
                return False
            lag_lo, lag_hi = -1.0, self.s.homing_stop_error_pu
        # a command-table sequence in a wait (_plain lets only the quiet ones through): its step changes nothing
        # in a cycle where the condition does not hold yet, so the cycle is quiet up to the one where it does
        wait = self.ct_runner.quiet_wait if self.ct_runner.running else None
        sw, sv = self.words[0], self.words[1]
        record = self.s.record_trajectory
        to_trajectory = samples is None
        if to_trajectory:
            samples = []
        new_sample = tuple.__new__          # Sample(...) without its Python-level __new__
        add_sample, add_entry = samples.append, entries.append if entries is not None else None
        # Axis.follow, inlined (its constants, then its state in locals)
        h, p00, p01, p10, p11, g0, g1, one_kff, stop_neg, stop_pos, settle = axis.follow_constants
        offset = axis.offset
        physical, velocity, acceleration = axis.physical, axis.velocity, axis.acceleration
        p = 0.0
        t0 = t
        # the cycles up to t_limit, so that no demand past it is computed (one per call: in a run of one cycle,
        # as where a TxPDO needs every cycle, a second demand would cost as much as the first)
        for p1, v1 in islice(gen.demands(t, cyc), (t_limit - t) // cyc + 1 if t_limit >= t else 0):
            if wait is not None and wait(t):
                break
            dv = v1 - prev_vd                           # the same float in both terms: computed once
            e = p1 - dv * h / 2 - prev_vd * h - (physical + offset)
            ed = prev_vd - velocity
            u = one_kff * dv / h
            ph1 = p1 - (p00 * e + p01 * ed + g0 * u) - offset
            if stop_neg <= ph1 <= stop_pos:
                va1 = v1 - (p10 * e + p11 * ed + g1 * u)
                ac1 = (va1 - velocity) / h
            else:                                   # on a mechanical stop: Axis.follow's own path
                axis.physical, axis.velocity, axis.acceleration = physical, velocity, acceleration
                axis.follow(p1, prev_vd, v1)
                ph1, va1, ac1 = axis.physical, axis.velocity, axis.acceleration
            pos = ph1 + offset
            err = p1 - pos                              # abs() without the builtin call (exact for floats)
            if err < 0:
                err = -err
            if active:
                if err <= lag_lo or err > lag_hi or not lim_neg <= pos <= lim_pos:
                    break
                since = None
            else:
                warn = (W.WARN_POS_LAG_ALWAYS if err > lag_warn else 0) | \
                       (W.WARN_POS_LAG_STANDING if err > st_warn else 0)
                in_window = target_ok and abs(gen_target - pos) <= window
                new_since = (t if since is None else since) if in_window else None
                now_in_target = in_window and t - new_since >= hold
                if (warn != warn_bits or err > lag_err or err > st_err or not lim_neg <= pos <= lim_pos
                        or now_in_target != in_target
                        or (not (new_since is not None and not now_in_target)
                            and err < settle and abs(va1) * 1e-3 < settle)):      # Axis.at_rest
                    break
                since = new_since
            physical, velocity, acceleration = ph1, va1, ac1
            p = p1
            prev_vd = v1
            if record:
                add_sample(new_sample(Sample, (t, p1, pos, v1, va1, sv, sw)))
            if entries is not None:
                add_entry((t, ph1, va1, ac1, v1, p1, v1, since))
            t += cyc
        axis.physical, axis.velocity, axis.acceleration = physical, velocity, acceleration
        if to_trajectory:
            self.trajectory.extend(samples)
        if t > t0:
            self.dem_p, self.dem_v, self._last_tick, self._now = p, prev_vd, t - cyc, t - cyc
        self._prev_vd, self._in_window_since, self._next_tick = prev_vd, since, t
        return t > t0

    def compute_ahead(self) -> int | None:
        """With quiet cycles ahead, the first cycle the generic path has to run (the drive's next timer)."""
        if not self._ahead and self.lookahead and self._plain():
            axis = self.axis
            saved = (axis.physical, axis.velocity, axis.acceleration, self._prev_vd, self.dem_p, self.dem_v,
                     self._last_tick, self._next_tick, self._in_window_since, self._now)
            entries: list[tuple] = []
            samples: list[Sample] = []
            self._quiet_run(self._next_tick + (self._horizon - 1) * self.s.cycle_ns, entries, samples)
            self._horizon = min(self._horizon * 2, self.AHEAD_MAX)
            (axis.physical, axis.velocity, axis.acceleration, self._prev_vd, self.dem_p, self.dem_v,
             self._last_tick, self._next_tick, self._in_window_since, self._now) = saved
            self._ahead, self._ahead_samples = entries, samples
        if self._ahead:
            return self._ahead[-1][0] + self.s.cycle_ns
        return None

    def _apply_ahead(self, t: int) -> None:
        """Take over the cycles computed ahead up to t."""
        ahead = self._ahead
        k = bisect_right(ahead, t, key=_CYCLE_TIME)
        if k:
            samples = self._ahead_samples
            if samples:
                self.trajectory.extend(samples[:k])
                del samples[:k]
            (tk, self.axis.physical, self.axis.velocity, self.axis.acceleration, self._prev_vd, self.dem_p,
             self.dem_v, self._in_window_since) = ahead[k - 1]
            self._last_tick, self._next_tick, self._now = tk, tk + self.s.cycle_ns, tk
        del ahead[:k]
