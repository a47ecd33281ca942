"""Time curves on the emulated E1100 (040xh..045xh): the curves commissioning writes, played as the curve model
says (N setpoints equally spaced over the x-length, [CFG] 5.3 / spec 3), with offset, time and amplitude scale.

The curves come from examples/two_axes.pvl, as commissioning writes them; the expected demand is computed here
from the setpoints (linear between them), not taken from the emulator.
"""

from __future__ import annotations

import pytest

from linmot_st.emulator import Curve, DriveTimings, E1100Drive, load_profile
from linmot_st.emulator.testing import MotionLink
from linmot_st.protocol import commands as C
from linmot_st.pvl import load_pvl
from repo_paths import EXAMPLES

MS = 1_000_000
MM = 10_000
PVL = EXAMPLES / "two_axes.pvl"


def pvl_curves() -> dict[int, Curve]:
    return {c.curve_id: Curve(c.curve_id, c.info_block, c.data_block) for c in load_pvl(PVL).curves}


def link_with_curves(defaults: dict | None = None) -> MotionLink:
    # RxPDO3 carries parameter bytes 6..11 (mapping 2041h = 2): 043xh..045xh need up to 12 bytes
    values = {0x1194: 2, 0x146F: 280 * MM, 0x146E: -10 * MM, 0x2041: 2}
    values.update(defaults or {})
    d = E1100Drive(1, load_profile().with_defaults(values), timings=DriveTimings.fast())
    d.curves.flash.update(pvl_curves())            # as a commissioned drive holds them after its reset
    link = MotionLink(d)
    link.enable()
    link.home()
    link.advance(MS)
    return link


def expected(setpoints, duration_s: float, t: float, offset: float = 0.0, amp: float = 1.0) -> float:
    """The curve model: setpoints at k * T / (N - 1), linear between them."""
    n = len(setpoints)
    if t >= duration_s:
        return offset + amp * setpoints[-1]
    x = t / duration_s * (n - 1)
    i = int(x)
    return offset + amp * (setpoints[i] + (x - i) * (setpoints[i + 1] - setpoints[i]))


def run(link, command, **fields) -> int:
    t0 = link.t
    link.command(command, **fields)
    assert link.wait(lambda: not link.drive.mc.motion_active, 5000 * MS)
    link.advance(20 * MS)
    return t0


def check_demand(link, t0: int, setpoints, duration_s: float, offset=0.0, amp=1.0) -> None:
    samples = link.drive.mc.trajectory.between(t0, t0 + int(duration_s * 1e9))
    assert len(samples) >= duration_s / 1e-3 - 1                # one sample per 1 ms cycle
    for s in samples:
        assert s.demand == pytest.approx(expected(setpoints, duration_s, (s.t_ns - t0) * 1e-9, offset, amp),
                                         abs=0.01)


def test_commissioned_min_jerk_curve_with_default_parameters():
    link = link_with_curves()
    curve = pvl_curves()[1]                       # MinJerk_100mm_400ms: 400 setpoints, x-length 40000 (400 ms)
    assert curve.setpoint_count == 400 and curve.x_length == 40000
    t0 = run(link, C.TIME_CURVE, curve_id=1)
    check_demand(link, t0, curve.setpoints, 0.400)
    d = link.drive
    active = [s.t_ns - t0 for s in d.mc.trajectory.between(t0) if s.status_word & 0x2000]
    assert active[0] == 0 and abs(active[-1] - 400 * MS) <= MS
    assert d.mc.axis.position == pytest.approx(100 * MM, abs=0.02 * MM)
    # the axis followed: a min-jerk curve keeps the following error small
    assert max(abs(s.following_error) for s in d.mc.trajectory.between(t0)) < 0.5 * MM


def test_curve_from_actual_position_and_to_position():
    link = link_with_curves()
    curve = pvl_curves()[23]                      # Example_Curve: 10 setpoints, 0 .. 100 mm in 200 ms
    link.command(C.VAI16_GO_TO_POS, target=200, vmax=1000, acc=100, dec=100)     # to 20 mm first
    assert link.wait(lambda: link.drive.mc.in_target, 2000 * MS)
    t0 = run(link, C.TIME_CURVE_FROM_ACT_POS, curve_id=23)
    check_demand(link, t0, curve.setpoints, 0.200, offset=20 * MM)
    assert link.drive.mc.dem_p == 120 * MM
    # to 40 mm: offset = demand (120 mm), amplitude (40 - 120) / 100 = -80 %
    t0 = run(link, C.TIME_CURVE_TO_POS, curve_id=23, target=40 * MM)
    check_demand(link, t0, curve.setpoints, 0.200, offset=120 * MM, amp=-0.8)
    assert link.drive.mc.dem_p == pytest.approx(40 * MM)
    # the same with its own curve time: 300 ms
    t0 = run(link, C.TIME_CURVE_TO_POS_TIME, curve_id=23, target=140 * MM, curve_time=30_000)
    check_demand(link, t0, curve.setpoints, 0.300, offset=40 * MM, amp=1.0)


def test_offset_time_scale_and_amplitude_scale():
    link = link_with_curves()
    curve = pvl_curves()[1]
    # 044xh: offset 0 (where the axis is: a curve starting elsewhere jumps), time scale 50 % (INFERRED: the
    # curve time x 0.5), amplitude 50 %
    t0 = run(link, C.TIME_CURVE_OFFSET_TIME_SCALE_AMP, curve_id=1, offset=0, time_scale=5000, amplitude=500)
    check_demand(link, t0, curve.setpoints, 0.200, offset=0, amp=0.5)
    assert link.drive.mc.dem_p == pytest.approx(50 * MM)
    # 045xh: offset 50 mm, curve time 250 ms, amplitude -40 %
    t0 = run(link, C.TIME_CURVE_OFFSET_TIME_AMP, curve_id=1, offset=50 * MM, curve_time=25_000, amplitude=-400)
    check_demand(link, t0, curve.setpoints, 0.250, offset=50 * MM, amp=-0.4)
    assert link.drive.mc.dem_p == pytest.approx(10 * MM)


def test_default_curve_parameters_apply_to_040x():
    link = link_with_curves({0x14D0: 5 * MM, 0x14D1: 20000, 0x14D2: 1500})   # offset 5 mm, 200 %, 150 %
    curve = pvl_curves()[23]
    link.command(C.VAI16_GO_TO_POS, target=50, vmax=100, acc=100, dec=100)     # to the curve's start, 5 mm
    assert link.wait(lambda: link.drive.mc.in_target, 2000 * MS)
    t0 = run(link, C.TIME_CURVE, curve_id=23)
    check_demand(link, t0, curve.setpoints, 0.400, offset=5 * MM, amp=1.5)


@pytest.mark.parametrize("command, fields, code", [
    (C.TIME_CURVE, {"curve_id": 5}, 0x0062),                                        # not in RAM
    (C.TIME_CURVE, {"curve_id": 2}, 0x0062),                                        # a cam: no time axis
    (C.TIME_CURVE_TO_POS, {"curve_id": 23, "target": 2500 * MM}, 0x0089),           # needs 2500 %
    (C.TIME_CURVE_OFFSET_TIME_SCALE_AMP,
     {"curve_id": 23, "offset": 0, "time_scale": 10000, "amplitude": 20001}, 0x0089),   # above 2000 %
])
def test_curve_errors(command, fields, code):
    link = link_with_curves()
    link.command(command, **fields)
    link.advance(10 * MS)
    d = link.drive
    assert d.mc.state == 4 and d.mc.error_code == code and d.errlog.entries[-1].code == code
