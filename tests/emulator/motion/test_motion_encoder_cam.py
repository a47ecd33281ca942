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
    trajectory = link.drive.mc.trajectory
    samples = trajectory.between(t0, t1)
    for s in samples:
        count = trajectory.master_counts(s.t_ns)                    # the encoder as recorded
        want = expected(count, **cam)
        assert s.demand == pytest.approx(want, abs=1e-6), (s.t_ns, count, s.demand, want)
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
    cols = mc.trajectory.columns()
    counts = [c for c, t in zip(cols["master_counts"], cols["t_ns"]) if t >= t0]
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


def test_triggered_cam_starts_after_its_delay_counts_on_every_edge():
    link = link_with_cam({0x170C: 1})                                  # trigger mode: direct ([MC] 7.2.2)
    mc, io = link.drive.mc, link.drive.io
    here = mc.dem_p
    link.command(C.TRIG_CAM_RISE, curve_id=CAM_ID, delay=1500)
    link.advance(2 * MS)
    assert link.drive.ram(U.P_TRIG_CAM_CURVE_RISE) == CAM_ID and link.drive.ram(U.P_TRIG_CAM_DELAY_RISE) == 1500
    t0 = link.t
    mc.encoder.drive_with(ConstantSpeed(10_000, t0_ns=t0), t0)         # 10 counts per ms
    link.advance(100 * MS)
    assert mc.dem_p == here                                            # no edge yet: no motion
    starts = []
    for _ in range(2):                                                 # the event handler re-arms: two parts
        edge = link.t + 300_000                                        # between two MC cycles
        io.set_input("X4.6", 1, edge)
        io.set_input("X4.6", 0, edge + 5 * MS)
        t_edge = edge
        link.advance(1100 * MS)
        start = mc.encoder.counts(t_edge) + 1500
        assert check(link, t_edge + MS, link.t, start=start, offset=here) > 1000
        moving = [s.t_ns for s in mc.trajectory.between(t_edge, link.t) if s.demand != here]
        assert start < mc.encoder.counts(moving[0]) <= start + 10     # after the delay, within one MC cycle
        assert mc.dem_p == pytest.approx(here)                         # a closed cam: back where it started
        starts.append(start)
    assert starts[1] > starts[0] + 8000
    link.command(C.CLEAR_EVENT_EVALUATION)
    link.advance(2 * MS)
    t1 = link.t
    io.set_input("X4.6", 1, t1 + MS)
    link.advance(500 * MS)
    assert all(s.demand == pytest.approx(here) for s in mc.trajectory.between(t1, link.t))   # cleared by 008xh


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
    assert len(cam_rows) == 28 and all(c.drives == {C.E1100} for c in cam_rows)
    link = link_with_cam()
    link.drive.curves.ram[8] = cam_curve([0, 10 * MM, 30 * MM, 60 * MM, 100 * MM], 4000, 8)     # a cam that can be scaled to a target
    mc = link.drive.mc
    for c in cam_rows:
        fields = {n: (8 if n == "curve_id" else 100) for n in c.field_names}
        if c.transport is C.Transport.COMMAND_TABLE:              # 1y3xh: 18 parameter bytes
            from test_motion_encoder_sync import direct
            link.advance(1 * MS)
            direct(link, c.cid, **fields)
        else:
            link.command(c.cid, 1 * MS, **fields)
        link.advance(2 * MS)
        assert mc.error_code == 0, f"{c.cid:03X}h: error {mc.error_code:04X}h"


def test_the_b1100_has_no_cam_motions():
    """The drive's series (its model's name) decides; main has no B1100 model yet, so an E1100 renamed stands
    in for it (with the B1100 model merged: make_drive("B1100", 1))."""
    import dataclasses

    from linmot_st.emulator.linmot.model import E1100
    from linmot_st.emulator.models import MODELS, make_drive
    from linmot_st.protocol import words as W
    b1100 = MODELS.get("B1100") or dataclasses.replace(E1100, name="B1100")
    for model, expect in ((b1100, W.ERR_UNKNOWN_MOTION_CMD), (E1100, 0)):
        d = make_drive(model, 1)
        d.mc.error_code = 0
        header = C.ENCODER_CAM_DISABLE << 4 | 1
        assert d.mc.execute(header, b"", 0) == (expect == 0)
        assert d.mc.error_code == expect


def test_the_fast_path_runs_a_cam_as_the_generic_cycle_does():
    """The quiet cycles (fast_path.py) compute the cam follower ahead: the trajectory is the same as with every
    cycle run one by one (MotionSettings.quiet_cycles False), sample for sample."""
    from linmot_st.emulator.linmot.motion import MotionSettings
    runs = []
    for quiet in (True, False):
        defaults = {0x1194: 2, 0x146F: 280 * MM, 0x146E: -10 * MM, 0x2041: 2, U.P_CAM_MODE: 1,
                    U.P_MASTER_ENCODER_SOURCE: 1}
        d = E1100Drive(1, load_profile().with_defaults(defaults), timings=DriveTimings.fast(),
                       motion=MotionSettings(quiet_cycles=quiet))
        d.curves.flash[CAM_ID] = cam_curve()
        link = MotionLink(d)
        link.enable()
        link.home()
        link.command(C.cam_command(1, C.CAM_DEFINE_FROM_ACT_POS), 1 * MS, curve_id=CAM_ID, start_count=0)
        link.command(C.cam_command(1, C.CAM_Y_ENABLE), 1 * MS)
        link.command(C.ENCODER_CAM_ENABLE, 1 * MS)
        t0 = link.t
        d.mc.encoder.drive_with(SpeedProfile([(t0, 15_000), (t0 + 300 * MS, -7_000)]), t0)
        link.advance(600 * MS)
        runs.append(d.mc.trajectory.between(t0, link.t))
    assert len(runs[0]) > 500 and runs[0] == runs[1]


def test_triggered_cam_with_target_and_length_on_the_falling_edge():
    link = link_with_cam({0x170C: 1})
    mc, io = link.drive.mc, link.drive.io
    here = round(mc.dem_p)
    ramp = [0, 10 * MM, 30 * MM, 60 * MM, 100 * MM]
    link.drive.curves.ram[8] = cam_curve(ramp, 4000, 8)
    link.command(C.TRIG_CAM_FALL_TARGET_LENGTH, curve_id=8, delay=200, target=here + 30 * MM, cam_length=3000)
    link.advance(2 * MS)
    assert link.drive.ram(U.P_TRIG_CAM_CURVE_FALL) == 8 and link.drive.ram(U.P_TRIG_CAM_DELAY_FALL) == 200
    t0 = link.t
    mc.encoder.drive_with(ConstantSpeed(-10_000, t0_ns=t0), t0)       # the master turns backwards
    mc.encoder.set_value(50_000, t0)
    io.set_input("X4.6", 1, t0 + 10 * MS)                             # the rising edge: not armed
    link.advance(50 * MS)
    assert mc.dem_p == here
    edge = t0 + 60 * MS
    io.set_input("X4.6", 0, edge)
    link.advance(600 * MS)
    assert mc.dem_p == here                                           # backwards: the counter never reaches it
    mc.encoder.drive_with(ConstantSpeed(10_000, t0_ns=link.t), link.t)   # forwards again
    link.advance(2000 * MS)
    start = mc.trajectory.master_counts(edge) + 200
    assert check(link, edge, link.t, start=start, offset=here, amp=30 * MM / (100 * MM), length=3000,
                 points=ramp) > 2000
    assert mc.dem_p == pytest.approx(here + 30 * MM)


def test_the_counter_and_cam_enabled_over_sdo():
    """1BA0h (counter) and 1BA9h (cam enabled) as a PLC reads them: SDO upload of 2000h + UPID, sub 01h."""
    link = link_with_cam()
    mc = link.drive.mc

    def upload(upid: int) -> int:
        index = 0x2000 + upid
        r = link.sdo(bytes([0x40, index & 0xFF, index >> 8, 0x01, 0, 0, 0, 0]))
        return int.from_bytes(r[4:8], "little", signed=True)

    mc.encoder.drive_with(ConstantSpeed(-1000, t0_ns=link.t), link.t)
    link.advance(100 * MS)
    asked = link.t
    assert upload(U.V_MASTER_ENCODER_COUNTS) == mc.encoder.counts(asked) == -100     # the counter when asked
    assert upload(U.V_CAM_ENABLED) == 0
    link.command(C.ENCODER_CAM_ENABLE)
    link.advance(2 * MS)
    assert upload(U.V_CAM_ENABLED) == 1


def test_cam_from_a_start_position_to_a_target_in_counts():
    # 1y3xh ([MC] 4.3.157): the curve scaled from its start position to its target (18 parameter bytes: a
    # command-table entry on CANopen, here straight into the command interface)
    from test_motion_encoder_sync import direct
    link = link_with_cam()
    mc = link.drive.mc
    here = round(mc.dem_p)
    ramp = [0, 10 * MM, 30 * MM, 60 * MM, 100 * MM]
    link.drive.curves.ram[8] = cam_curve(ramp, 4000, 8)
    start = here + 2 * MM
    direct(link, C.cam_command(1, C.CAM_DEFINE_FROM_POS_TO_POS_IN_COUNTS), curve_id=8, start_count=1000,
           start_pos=start, target=start + 40 * MM, cam_length=2000)
    link.command(C.cam_command(1, C.CAM_Y_ENABLE), 1 * MS)
    link.command(C.ENCODER_CAM_ENABLE, 1 * MS)
    t0 = link.t
    mc.encoder.drive_with(Recorded([(t0, 1000), (t0 + 400 * MS, 4000)]), t0)
    link.advance(500 * MS)
    # from the first cycle after the counter is at the cam's start count (1000) on
    assert check(link, t0 + MS, link.t, start=1000, offset=start, amp=0.4, length=2000, points=ramp) > 400
    assert mc.dem_p == pytest.approx(start + 40 * MM) and mc.error_code == 0
