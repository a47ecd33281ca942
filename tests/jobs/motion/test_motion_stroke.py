"""The motion plan fits the axis (issue 24, section 2): the job places the emulated mechanics so that every step
lies within the stroke, or refuses before motion, with the figures, what the PVL's own settings exclude.

tests/data/curve_below_home.pvl is examples/two_axes.pvl with curve 1 replaced by a time curve from -0.1 mm to
-30 mm (minimum jerk, 300 ms), the negative position limit at -50 mm (so that the limits allow the curve) and no
cam curve. Before the placement, commissioning passed and the curve step failed with 000Bh (following error):
the emulated slider homed on its negative stop at 0 mm."""

from __future__ import annotations

import pytest

import repo_paths
from linmot_st.cli import main
from linmot_st.emulator.linmot.motion import MotionSettings
from linmot_st.jobs.commission.project import build_project, prepare
from linmot_st.jobs.commission.runner import RunOptions
from linmot_st.jobs.motion.check import check_motion
from linmot_st.jobs.motion.job import run_job
from linmot_st.jobs.motion.plan import plan
from linmot_st.pvl import load_pvl, parse_pvl
from repo_paths import EXAMPLES

DATA = repo_paths.DATA / "curve_below_home.pvl"
EXAMPLE = EXAMPLES / "two_axes.pvl"


def _variant(replace: dict[str, str], add: str = ""):
    """The test file with MC parameter rows replaced (UPID -> row) or one added after the homing mode."""
    lines = DATA.read_text().splitlines()
    out = []
    for line in lines:
        upid = line.split(",", 1)[0]
        out.append(replace.get(upid, line))
        if upid == "1500" and add:
            out.append(add)
    return parse_pvl("\n".join(out) + "\n", "variant.pvl")


def _inside(p) -> None:
    for s in p.steps:
        if s.span_mm is not None:
            assert p.stroke.negative_mm <= s.span_mm[0] and s.span_mm[1] <= p.stroke.positive_mm, s.label


def test_the_example_keeps_the_emulators_mechanics():
    p = plan(load_pvl(EXAMPLE))
    assert not p.stroke.placed and p.stroke.home_position_raw is None and not p.refusals
    assert (p.stroke.negative_mm, p.stroke.positive_mm) == (0, 300)
    assert p.stroke.start_position_pu == MotionSettings().start_position_pu
    _inside(p)


def test_a_curve_below_the_home_gets_a_stop_below_it():
    p = plan(load_pvl(DATA))
    curve = next(s for s in p.steps if s.kind == "curve" and s.curve_id == 1)
    assert curve.span_mm == (pytest.approx(-30.0), pytest.approx(-0.1))
    assert p.stroke.placed and not p.refusals
    assert p.stroke.negative_mm == pytest.approx(-31.0) and p.stroke.home_position_raw == -310_000
    _inside(p)


def test_the_job_runs_the_curve_below_the_home():
    pvl = load_pvl(DATA)
    p = plan(pvl)
    res = run_job(pvl, RunOptions(axes=1, timings="fast"), build_project(prepare(pvl, DATA.name)), p)
    m = res.after
    assert m is not None and m.finished and not any(a.error for a in m.axes), [a.drive_error for a in m.axes]
    chk = check_motion(m, p, res.drives)
    assert chk.passed, [s.what for s in chk.steps if not s.ok]
    rec = next(r for r in m.axes[0].steps if r.kind == "curve" and p.steps[r.index - 1].curve_id == 1)
    low = min(s.actual for s in res.drives[1].mc.trajectory.between(rec.t0_ns, rec.t1_ns)) / 10_000
    assert low == pytest.approx(-30.0, abs=0.5)              # the slider followed the curve down to -30 mm


def test_the_pvls_own_limits_refuse_before_motion(tmp_path, capsys):
    # two_axes.pvl's negative limit, -10 mm: the curve to -30 mm is excluded by the file itself
    text = DATA.read_text().replace("146E,FFF85EE0,Motion Control SW\\Position Limits\\Negative Limit,-50 mm",
                                    "146E,FFFE7960,Motion Control SW\\Position Limits\\Negative Limit,-10 mm")
    f = tmp_path / "limited.pvl"
    f.write_text(text)
    p = plan(load_pvl(f))
    assert any("-30 mm" in r and "-10 mm" in r and "146Eh" in r for r in p.refusals), p.refusals
    rc = main(["motion", str(f), "--axes", "1", "-q"])
    out = capsys.readouterr().out
    assert rc == 1 and "REFUSED before motion" in out and "-30 mm" in out
    assert "commissioned" not in out                          # nothing ran
    with pytest.raises(ValueError, match="does not fit"):
        run_job(load_pvl(f), RunOptions(axes=1, timings="fast"), None, p)


def test_a_home_position_set_by_the_pvl_is_kept_and_a_step_beyond_its_stop_refused():
    p = plan(_variant({}, add="13C7,00000000,Motion Control SW\\State Machine Setup\\Homing\\Home Position,0 mm"))
    assert not p.stroke.placed and p.stroke.negative_mm == 0
    assert any("-30" in r and "beyond the stroke 0..300 mm" in r for r in p.refusals), p.refusals


def test_homing_at_the_power_on_position_places_the_power_on_position():
    # mode 0: the home (0 mm) is where the slider powered on: 20 mm above the stop by default, too little
    p = plan(_variant({"1500": "1500,00000000,Motion Control SW\\State Machine Setup\\Homing\\Mode,0"}))
    assert p.stroke.placed and not p.refusals and p.stroke.home_position_raw is None
    assert p.stroke.start_position_pu == 310_000 and p.stroke.negative_mm == pytest.approx(-31.0)
    _inside(p)


def test_a_plan_longer_than_the_stroke_is_refused():
    p = plan(load_pvl(DATA), position_mm=190.0, settings=MotionSettings().with_(stop_positive_pu=200 * 10_000))
    assert any("more than the stroke" in r for r in p.refusals), p.refusals
