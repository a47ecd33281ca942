"""Force control on the emulated E1100 (380xh..384xh, [MC] 4.3.217..221; INFERRED sensor and regulator,
docs/emulator.md): a VAI move onto a contact (a spring of 10 N/mm beyond it, measured with 0.5 N noise) changes
to force control at the force limit and holds the target force; 382xh changes it, 381xh returns to position
control. The force is computed here from the contact and the axis's actual position."""

from __future__ import annotations

import statistics

import pytest
from test_motion_encoder_sync import MM, MS, direct, make_link

from linmot_st.protocol import commands as C
from linmot_st.protocol import upids as U

STIFFNESS = 10.0                                    # N/mm
NOISE = 0.5                                         # N (standard deviation)
HOLD_ERROR = 2.0                                    # N: every cycle after settling, the true force within this


def force_at(position: float, contact: float) -> float:
    return max(position - contact, 0.0) / MM * STIFFNESS


def pressing_link():
    probe = make_link()
    contact = round(probe.drive.mc.dem_p) + 20 * MM
    link = make_link(force_contact_pu=contact, force_stiffness_n_per_mm=STIFFNESS, force_noise_n=NOISE)
    return link, contact


def test_force_control_reaches_the_target_force_on_the_contact_and_holds_it():
    link, contact = pressing_link()
    mc = link.drive.mc
    here = round(mc.dem_p)
    direct(link, C.FORCE_VAI_HIGHER_LIMIT, target=here + 40 * MM, vmax=100_000, acc=100_000, force_limit=500)
    t0 = link.t
    link.advance(600 * MS)
    samples = mc.trajectory.between(t0, link.t)
    # it never went to its target 40 mm away: it stopped on the contact at about 50 N / 10 N/mm = 5 mm in
    assert max(s.actual for s in samples) < contact + 7 * MM
    settled = [s for s in samples if s.t_ns >= link.t - 200 * MS]
    forces = [force_at(s.actual, contact) for s in settled]
    assert max(abs(f - 50.0) for f in forces) < HOLD_ERROR, (min(forces), max(forces))
    assert statistics.mean(forces) == pytest.approx(50.0, abs=0.5)
    assert mc.variable(U.V_ACTUAL_FORCE) == pytest.approx(500, abs=4 * NOISE * 10)     # 0.1 N, with the noise
    assert mc.error_code == 0
    # 382xh: a new target force of 80 N
    link.command(C.FORCE_CHANGE_TARGET_FORCE, target_force=800)
    link.advance(400 * MS)
    assert force_at(mc.axis.position, contact) == pytest.approx(80.0, abs=HOLD_ERROR)
    # 381xh: back to position control, away from the contact
    direct(link, C.FORCE_VAI_FROM_ACT_POS_RESET, target=here, vmax=100_000, acc=100_000, dec=100_000)
    link.advance(800 * MS)
    assert mc.dem_p == pytest.approx(here) and force_at(mc.axis.position, contact) == 0.0


def test_lower_force_limit_changes_to_force_control_when_the_force_falls():
    link, contact = pressing_link()
    mc = link.drive.mc
    here = round(mc.dem_p)
    direct(link, C.FORCE_VAI_HIGHER_LIMIT, target=here + 40 * MM, vmax=100_000, acc=100_000, force_limit=800)
    link.advance(500 * MS)
    assert force_at(mc.axis.position, contact) == pytest.approx(80.0, abs=HOLD_ERROR)
    # moving back out of the contact: at 30 N (falling) it regulates to 30 N instead of leaving the contact
    direct(link, C.FORCE_VAI_LOWER_LIMIT, target=here, vmax=50_000, acc=100_000, force_limit=300)
    link.advance(600 * MS)
    assert force_at(mc.axis.position, contact) == pytest.approx(30.0, abs=HOLD_ERROR)


def test_with_target_force_the_limit_starts_force_control_and_the_target_force_is_held():
    # 383xh ([MC] 4.3.220): force control from a limit of 30 N, then regulating to the command's 60 N
    link, contact = pressing_link()
    mc = link.drive.mc
    here = round(mc.dem_p)
    direct(link, C.FORCE_VAI_HIGHER_LIMIT_TARGET_FORCE, target=here + 40 * MM, vmax=100_000, acc=100_000,
           force_limit=300, target_force=600)
    link.advance(600 * MS)
    assert force_at(mc.axis.position, contact) == pytest.approx(60.0, abs=HOLD_ERROR)
    # 385xh: leaving at a lower limit of 40 N, regulating to 20 N
    direct(link, C.FORCE_VAI_LOWER_LIMIT_TARGET_FORCE, target=here, vmax=50_000, acc=100_000, force_limit=400,
           target_force=200)
    link.advance(600 * MS)
    assert force_at(mc.axis.position, contact) == pytest.approx(20.0, abs=HOLD_ERROR)
    assert mc.error_code == 0
