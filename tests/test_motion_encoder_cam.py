"""Encoder cams on the emulated E1100 ([MC] 4.3.63..68, 4.3.150..162, 5.5; master encoder [MC] 7.3): the demand
follows a cam curve (object type 0103h) as a master encoder turns, at two speeds, backwards, repeated in modulo
mode, and a triggered cam starts its delay counts after the edge.

The expected demand is computed here from the curve as written (N setpoints equally spaced over the cam length,
linear between) at the encoder's counter in each trajectory sample, not taken from the emulator's cam model.
"""

from __future__ import annotations

import pytest

from linmot_st.emulator import Curve, DriveTimings, E1100Drive, load_profile
from linmot_st.emulator.linmot.master_encoder import ConstantSpeed, Function, Recorded, SpeedProfile
from linmot_st.emulator.motion.encoder_cams import trigger_edge
from linmot_st.emulator.testing import MotionLink
from linmot_st.protocol import commands as C
from linmot_st.protocol import upids as U

MS = 1_000_000
MM = 10_000
CAM_ID = 7
SETPOINTS = [0, 20 * MM, 60 * MM, 80 * MM, 60 * MM, 20 * MM, 0]      # a closed cam: 0 -> 80 mm -> 0
CAM_LENGTH = 8000                                                     # counts = one revolution


def cam_curve(points=SETPOINTS, length=CAM_LENGTH, curve_id=CAM_ID) -> Curve:
    return Curve.build(curve_id, points, name="cam", x_length=length, object_type=0x0103, x_dim=0x001B)


def link_with_cam(values: dict | None = None) -> MotionLink:
    defaults = {0x1194: 2, 0x146F: 280 * MM, 0x146E: -10 * MM, 0x2041: 2,
                U.P_MASTER_ENCODER_SOURCE: 1, U.P_MASTER_ENCODER_COUNTS_PER_REV: 8000}
    defaults.update(values or {})
    d = E1100Drive(1, load_profile().with_defaults(defaults), timings=DriveTimings.fast())
    d.curves.flash[CAM_ID] = cam_curve()
    link = MotionLink(d)
    link.enable()
    link.home()
    link.advance(MS)
    return link


def expected(count: int, start: int, offset: float, amp: float = 1.0, length: int = CAM_LENGTH,
             modulo: int | None = None, points=SETPOINTS) -> float:
    rel = (count - start) % modulo if modulo else count - start
    rel = min(max(rel, 0), length)
    x = rel / length * (len(points) - 1)
    i = min(int(x), len(points) - 2)
    return offset + amp * (points[i] + (x - i) * (points[i + 1] - points[i]))


def check(link, t0: int, t1: int, **cam) -> int:
    """Every sample's demand equals the cam at the counter then; returns how many were checked."""
    enc = link.drive.mc.encoder
    samples = link.drive.mc.trajectory.between(t0, t1)
    for s in samples:
        want = expected(enc.counts(s.t_ns), **cam)
        assert s.demand == pytest.approx(want, abs=1e-6), (s.t_ns, enc.counts(s.t_ns), s.demand, want)
    return len(samples)


def test_cam_follows_the_master_at_two_speeds_backwards_and_repeats_in_modulo_mode():
    link = link_with_cam({U.P_CAM_MODE: 1})                 # modulo cam length = counts/rev 8000
    mc = link.drive.mc
    start_pos = mc.dem_p
    link.command(C.cam_command(1, C.CAM_DEFINE_FROM_ACT_POS), curve_id=CAM_ID, start_count=0)
    link.command(C.cam_command(1, C.CAM_Y_ENABLE), 1 * MS)
    link.command(C.ENCODER_CAM_ENABLE, 1 * MS)
    link.advance(2 * MS)
    assert mc.variable(U.V_CAM_ENABLED) == 1 and mc.error_code == 0
    # 0.5 s forwards at 20 000 counts/s (1.25 revolutions), 0.5 s at 6 000 counts/s, 0.4 s backwards at -9 000
    t0 = link.t
    mc.encoder.drive_with(SpeedProfile([(t0, 20_000), (t0 + 500 * MS, 6_000), (t0 + 1000 * MS, -9_000)]), t0)
    link.advance(1400 * MS)
    cam = dict(start=0, offset=start_pos, modulo=8000)
    assert check(link, t0, link.t, **cam) > 1000
    counts = [mc.encoder.counts(s.t_ns) for s in mc.trajectory.between(t0, link.t)]
    assert max(counts) == 13_000 and counts[-1] == 13_000 - 3_600      # forwards, then backwards
    # the cam repeated: it reached its top (80 mm) in the first and the second revolution
    tops = [s.t_ns for s in mc.trajectory.between(t0, link.t) if s.demand >= start_pos + 79 * MM]
    assert tops and min(tops) < t0 + 300 * MS and max(tops) > t0 + 500 * MS
    # the axis followed the demand (a stable loop, no error)
    assert mc.error_code == 0 and abs(mc.dem_p - mc.axis.position) < 2 * MM
    assert mc.variable(U.V_MASTER_ENCODER_COUNTS) == counts[-1]
    assert mc.variable(U.V_MASTER_ENCODER_SPEED) == pytest.approx(-9_000, rel=0.01)


def test_cam_to_position_in_infinite_mode_runs_once_and_holds():
    link = link_with_cam()
    mc = link.drive.mc
    here = mc.dem_p
    ramp = [0, 10 * MM, 30 * MM, 60 * MM, 100 * MM]                                       # a rising cam, scaled to its target
    link.drive.curves.ram[8] = cam_curve(ramp, 4000, 8)
    link.command(C.cam_command(2, C.CAM_DEFINE_TO_POS_IN_COUNTS), curve_id=8, start_count=1000,
                 target=round(here) + 50 * MM, cam_length=2000)
    link.command(C.cam_command(2, C.CAM_Y_ENABLE), 1 * MS)
    link.command(C.ENCODER_CAM_ENABLE, 1 * MS)
    t0 = link.t
    mc.encoder.drive_with(Recorded([(t0, 0), (t0 + 400 * MS, 4000)]), t0)
    link.advance(500 * MS)
    here = round(here)
    amp = 0.5
    assert check(link, t0, link.t, start=1000, offset=here, amp=amp, length=2000, points=ramp) > 400
    assert mc.dem_p == pytest.approx(here + 50 * MM)                   # ran once, holds at its end


def test_triggered_cam_starts_after_its_delay_counts():
    link = link_with_cam()
    mc = link.drive.mc
    here = mc.dem_p
    link.command(C.TRIG_CAM_RISE, curve_id=CAM_ID, delay=1500)
    link.advance(2 * MS)
    assert link.drive.ram(U.P_TRIG_CAM_CURVE_RISE) == CAM_ID and link.drive.ram(U.P_TRIG_CAM_DELAY_RISE) == 1500
    t0 = link.t
    mc.encoder.drive_with(ConstantSpeed(10_000, t0_ns=t0), t0)
    link.advance(100 * MS)
    assert mc.dem_p == here                                            # not triggered yet: no motion
    t_edge = link.t
    edge_count = mc.encoder.counts(t_edge)
    trigger_edge(mc, True, t_edge)
    link.advance(1200 * MS)
    start = edge_count + 1500
    assert check(link, t_edge, link.t, start=start, offset=here) > 1000
    moving = [s.t_ns for s in mc.trajectory.between(t_edge, link.t) if s.demand != here]
    assert mc.encoder.counts(moving[0]) > start                       # it started after the delay counts
    assert mc.encoder.counts(moving[0]) <= start + 20                 # within one MC cycle of counts (10/ms)
    trigger_edge(mc, True, link.t)                                     # one shot: the next edge starts nothing
    assert mc.dem_p == pytest.approx(here)


def test_the_master_encoder_parameters_and_signals():
    link = link_with_cam({U.P_MASTER_ENCODER_DIRECTION: 1, U.P_MASTER_ENCODER_DECODING: 1})
    enc = link.drive.mc.encoder
    t0 = link.t
    enc.drive_with(Function(lambda s: 40_000 * (s - t0 * 1e-9)), t0)   # 40 000 edges/s from t0
    link.advance(100 * MS)
    assert enc.counts(link.t) == -2000                                 # 2x decoding, negative direction
    link.command(C.ENCODER_CAM_SET_VALUE, counter_value=123)
    link.advance(1 * MS)
    assert enc.counts(link.t) == pytest.approx(123 - 20, abs=1)      # (the float time arithmetic of the signal)


def test_cams_are_e1100_only_and_every_row_is_accepted():
    cam_rows = [c for c in C.COMMANDS.values() if c.kind in (C.Kind.ENCODER_CAM, C.Kind.TRIGGERED_CAM)]
    assert len(cam_rows) == 26 and all(c.drives == {C.E1100} for c in cam_rows)
    link = link_with_cam()
    link.drive.curves.ram[8] = cam_curve([0, 10 * MM, 30 * MM, 60 * MM, 100 * MM], 4000, 8)     # a cam that can be scaled to a target
    mc = link.drive.mc
    for c in cam_rows:
        fields = {n: (8 if n == "curve_id" else 100) for n in c.field_names}
        link.command(c.cid, 1 * MS, **fields)
        link.advance(2 * MS)
        assert mc.error_code == 0, f"{c.cid:03X}h: error {mc.error_code:04X}h"
