"""VAI motions of the emulated E1100 driven by PDO frames: the CANopen manual's example, golden trapezoids and
triangles, re-targeting, stops, and the errors a move can raise (spec/linmot-motion.md sections 2-4).

Golden figures are computed here from the kinematics (t = d/v + v/a for a trapezoid with equal acc and dec,
t = 2 sqrt(d/a) for a triangle), not taken from the emulator.
"""

from __future__ import annotations

import math
import struct

import pytest

from linmot_st.bus.frame import Frame
from linmot_st.emulator import DriveTimings, E1100Drive, load_profile
from linmot_st.emulator.testing import MotionLink
from linmot_st.protocol import commands as C

MS = 1_000_000
MM = 10_000           # pu per mm
CYCLE = MS            # the default MC cycle


def homed_link(defaults: dict | None = None, **motion) -> MotionLink:
    from linmot_st.emulator.linmot.motion import MotionSettings

    values = {0x1194: 2, 0x146F: 280 * MM, 0x146E: -10 * MM}         # position limits inside the stroke
    values.update(defaults or {})
    d = E1100Drive(1, load_profile().with_defaults(values), timings=DriveTimings.fast(),
                   motion=MotionSettings(**motion))
    link = MotionLink(d)
    link.enable()
    link.home()
    link.advance(MS)
    return link


def motion_window(link, t0: int) -> tuple[int, int]:
    """First and last sample (ns after t0) with Motion Active set."""
    active = [s.t_ns for s in link.drive.mc.trajectory.between(t0) if s.status_word & 0x2000]
    return active[0] - t0, active[-1] - t0


def test_canopen_manual_example_home_then_50mm():
    """[CO1100] 14: 201h 3F 08, 201h 3F 00, 301h 01 09 F4 01 E8 03 64 00, 401h 01 09 64 00."""
    d = E1100Drive(1, load_profile().with_defaults({0x1194: 2}), timings=DriveTimings.fast())
    link = MotionLink(d)
    link.enable()
    link.send(Frame(0x201, bytes.fromhex("3F08")))
    assert link.wait(lambda: d.mc.state_var == 0x090F)
    link.send(Frame(0x201, bytes.fromhex("3F00")), MS)
    assert d.mc.homed and d.mc.axis.position == 0                   # homed at 0 mm
    link.advance(5 * MS)
    t0 = link.t
    link.send(Frame(0x301, bytes.fromhex("0109F401E8036400")))
    link.send(Frame(0x401, bytes.fromhex("01096400")))
    link.advance(400 * MS)
    # 50 mm < v^2/a = 100 mm: a triangle peaking at sqrt(a d) = 0.707 m/s after sqrt(d/a) = 70.7 ms
    start, end = motion_window(link, t0)
    assert start == 0
    assert abs(end - 2 * math.sqrt(0.05 / 10) * 1e9) <= CYCLE
    peak = max(s.demand_velocity for s in d.mc.trajectory.between(t0)) * 1e-7
    assert peak == pytest.approx(math.sqrt(10 * 0.05), rel=0.01)
    assert d.mc.axis.position == pytest.approx(50 * MM, abs=0.5)     # at rest on target
    # the count echo: state var low nibble and TxPDO2's motion command status
    sv = struct.unpack("<H", link.pdos(1)[-1][1][2:4])[0]
    assert sv == 0x08C1                                              # homed, in target, count 1
    cmd_status, act16, _, dem16 = struct.unpack("<HhhH", link.pdos(2)[-1][1])
    assert cmd_status == 0x0901 and act16 == 500 and dem16 == 500    # 16-bit positions in 0.1 mm


@pytest.mark.parametrize("d_mm, v, a", [(100, 0.5, 5.0), (20, 1.0, 10.0), (200, 2.0, 20.0)])
def test_golden_trapezoid_and_triangle(d_mm, v, a):
    link = homed_link()
    t0 = link.t
    # VAI 16 bit: 0.1 mm, 1 mm/s, 0.1 m/s^2 per unit (the default 16-bit scaling)
    link.command(C.VAI16_GO_TO_POS, target=d_mm * 10, vmax=int(v * 1000), acc=int(a * 10), dec=int(a * 10))
    link.advance(int(3e9))
    d = d_mm / 1000
    trapezoid = d >= v * v / a
    t_end = d / v + v / a if trapezoid else 2 * math.sqrt(d / a)
    start, end = motion_window(link, t0)
    assert abs(end - t_end * 1e9) <= CYCLE
    # the demand sample by sample against the analytic profile
    vp = v if trapezoid else math.sqrt(a * d)
    t1 = vp / a

    def golden(t: float) -> float:
        if t <= t1:
            return 0.5 * a * t * t
        if t <= t_end - t1:
            return 0.5 * a * t1 * t1 + vp * (t - t1)
        if t <= t_end:
            return d - 0.5 * a * (t_end - t) ** 2
        return d

    for s in link.drive.mc.trajectory.between(t0, t0 + int(t_end * 1e9) + 5 * CYCLE):
        assert s.demand * 1e-7 == pytest.approx(golden((s.t_ns - t0) * 1e-9), abs=1e-7)


def test_new_target_mid_motion_is_replanned_smoothly():
    link = homed_link()
    d = link.drive
    t0 = link.t
    link.command(C.VAI16_GO_TO_POS, target=1000, vmax=1000, acc=50, dec=50)    # 100 mm
    link.advance(150 * MS)
    x_at, v_at = d.mc.dem_p, d.mc.dem_v
    assert v_at > 0
    link.command(C.VAI16_GO_TO_POS, target=200, vmax=1000, acc=50, dec=50)     # back to 20 mm: overshoot
    assert link.wait(lambda: d.mc.in_target, 3000 * MS)
    samples = d.mc.trajectory.between(t0)
    # continuous: no sample-to-sample jump beyond what 5 m/s^2 and 1 m/s allow in a cycle
    for a_, b_ in zip(samples, samples[1:]):
        dt = (b_.t_ns - a_.t_ns) * 1e-9
        assert abs(b_.demand_velocity - a_.demand_velocity) <= 5.0 * 1e7 * dt + 1
        assert abs(b_.demand - a_.demand) <= 1.0 * 1e7 * dt + 1
    assert max(s.demand for s in samples) > x_at                      # braked past, then came back
    assert d.mc.dem_p == 20 * MM and abs(d.mc.axis.position - 20 * MM) < 1000


def test_increment_target_and_increment_demand():
    link = homed_link()
    d = link.drive
    link.command(C.VAI16_GO_TO_POS, target=100, vmax=500, acc=50, dec=50)
    link.advance(10 * MS)
    link.command(C.VAI16_INCREMENT_TARGET_POS, target=50, vmax=500, acc=50, dec=50)   # last target + 5 mm
    assert link.wait(lambda: d.mc.in_target, 3000 * MS)
    assert d.mc.dem_p == 15 * MM
    link.command(C.VAI16_INCREMENT_DEM_POS, target=-30, vmax=500, acc=50, dec=50)
    assert link.wait(lambda: d.mc.in_target and d.mc.dem_p != 15 * MM, 3000 * MS)
    assert d.mc.dem_p == 12 * MM


def test_vai_stop_brakes_with_its_deceleration():
    link = homed_link()
    d = link.drive
    link.command(C.VAI16_GO_TO_POS, target=2000, vmax=1000, acc=100, dec=100)
    assert link.wait(lambda: d.mc.dem_v >= 1.0 * 1e7 - 1)             # cruising at 1 m/s
    x0 = d.mc.dem_p
    link.command(C.VAI_STOP, dec=500_000)                             # 5 m/s^2 (017xh fits RxPDO2)
    assert link.wait(lambda: not d.mc.motion_active, 2000 * MS)
    assert (d.mc.dem_p - x0) * 1e-7 == pytest.approx(1.0 ** 2 / (2 * 5.0), abs=0.0011)
    link.command(C.VAI16_GO_TO_POS, target=0, vmax=1000, acc=100, dec=100)
    assert link.wait(lambda: d.mc.dem_v <= -1.0 * 1e7 + 1)
    x0 = d.mc.dem_p
    link.command(C.VAI16_STOP, dec=200)                               # 20 m/s^2 in the 16-bit scaling
    assert link.wait(lambda: not d.mc.motion_active, 2000 * MS)
    assert (x0 - d.mc.dem_p) * 1e-7 == pytest.approx(1.0 / 40, abs=0.0011)


def test_quick_stop_bit_2_ramps_with_the_quick_stop_deceleration_then_switch_on_disabled():
    link = homed_link({0x1530: 2_000_000})                            # 20 m/s^2
    d = link.drive
    link.command(C.VAI16_GO_TO_POS, target=2000, vmax=1000, acc=100, dec=100)
    assert link.wait(lambda: d.mc.dem_v >= 1e7 - 1)
    x0 = d.mc.dem_p
    link.cw(0x003B)                                                   # /Quick Stop = 0
    assert link.wait(lambda: d.mc.state == 1, 1000 * MS)
    assert (d.mc.dem_p - x0) * 1e-7 == pytest.approx(1 / 40, abs=0.0011)
    assert not d.mc.controlled


def test_predef_vai_uses_the_drive_parameters():
    link = homed_link({0x14BE: 500_000, 0x14BF: 500_000, 0x14C0: 500_000})   # 0.5 m/s, 5 m/s^2
    t0 = link.t
    link.command(C.PREDEF_VAI_GO_TO_POS, target=100 * MM)
    link.advance(1000 * MS)
    _, end = motion_window(link, t0)
    assert abs(end - (0.1 / 0.5 + 0.5 / 5) * 1e9) <= CYCLE
    link.command(C.PREDEF_VAI_INCREMENT_DEM_POS, target=-10 * MM)
    link.advance(1000 * MS)
    assert link.drive.mc.dem_p == 90 * MM


def test_write_live_parameter_and_interface_control_word_commands():
    link = homed_link()
    d = link.drive
    link.command(C.WRITE_LIVE_PARAMETER, upid=0x13A2, value=77)
    link.advance(MS)
    assert d.params[0x13A2].ram == 77 and d.params[0x13A2].rom == 9   # RAM only
    link.command(C.WRITE_LIVE_PARAMETER, upid=0x1194, value=5)        # not live: ignored (INFERRED)
    link.advance(MS)
    assert d.params[0x1194].ram == 2 and d.mc.state == 8
    link.command(C.MASTER_HOMING, home_position=-5 * MM)
    link.advance(MS)
    assert d.mc.axis.position == -5 * MM and d.params[0x13C7].ram == -5 * MM


def error_case(command, fields, defaults=None, homed=True):
    values = {0x1194: 2}
    values.update(defaults or {})
    d = E1100Drive(1, load_profile().with_defaults(values), timings=DriveTimings.fast())
    link = MotionLink(d)
    link.enable()
    if homed:
        link.home()
    link.advance(MS)
    link.command(command, **fields)
    link.advance(100 * MS)
    return d


@pytest.mark.parametrize("command, fields, code, homed", [
    (0x0FF, {}, 0x0081, True),                                                    # unknown command
    (C.TIME_CURVE, {"curve_id": 7}, 0x0062, True),                                # curve not in RAM
    (C.START_COMMAND_TABLE, {"entry": 9}, 0x008A, True),                          # CT entry not defined
    (C.VAI16_GO_TO_POS, {"target": 100, "vmax": 100, "acc": 100, "dec": 100}, 0x0080, False),   # not homed
])
def test_error_codes_leave_the_drive_in_error_state(command, fields, code, homed):
    d = error_case(command, fields, homed=homed)
    assert d.mc.state == 4 and d.mc.error_code == code and d.mc.state_var == 0x0400 | code
    assert d.errlog.entries[-1].code == code
    assert not d.mc.controlled


def test_following_error_during_a_move_then_reset_and_move_again():
    link = homed_link()
    d = link.drive
    link.command(C.VAI16_GO_TO_POS, target=1000, vmax=500, acc=50, dec=50)
    link.advance(100 * MS)
    d.mc.block(True, link.t)
    assert link.wait(lambda: d.mc.state == 4, 2000 * MS)
    assert d.mc.error_code == 0x000B
    d.mc.block(False, link.t)
    link.cw(0x00BF)
    link.cw(0x003E, MS)
    link.cw(0x003F, MS)
    assert link.wait(lambda: d.mc.state == 8)
    assert d.mc.homed                                                # the position stayed known
    link.command(C.VAI16_GO_TO_POS, target=300, vmax=500, acc=50, dec=50)
    assert link.wait(lambda: d.mc.in_target, 3000 * MS)
    assert abs(d.mc.axis.position - 30 * MM) < 1000


def test_standing_lag_error():
    link = homed_link({0x1475: 5000})                                 # 0.5 mm standing error level
    d = link.drive
    d.mc.block(True, link.t)
    d.mc.push(8000, link.t)                                           # pushed 0.8 mm away and held there
    assert link.wait(lambda: d.mc.state == 4, 100 * MS)
    assert d.mc.error_code == 0x000C


@pytest.mark.parametrize("target, code", [(2100, 0x0008), (-200, 0x0007)])
def test_position_limits(target, code):
    link = homed_link({0x146F: 200 * MM, 0x146E: -10 * MM}, stop_negative_pu=-1000 * MM)
    d = link.drive
    link.command(C.VAI16_GO_TO_POS, target=target, vmax=500, acc=50, dec=50)
    assert link.wait(lambda: d.mc.state == 14, 3000 * MS)
    assert d.mc.error_code == code
    assert link.wait(lambda: d.mc.state == 4, 1000 * MS)


def test_motion_variables_over_sdo():
    link = homed_link()
    d = link.drive
    link.command(C.VAI16_GO_TO_POS, target=500, vmax=1000, acc=100, dec=100)
    link.advance(30 * MS)

    def read(upid: int) -> int:
        r = link.sdo(struct.pack("<BHB4x", 0x40, 0x2000 + upid, 1))
        return struct.unpack_from("<i", r, 4)[0]

    assert read(0x1B8D) == round(d.mc.axis.position)                 # actual position, 0.1 um
    assert read(0x1B8C) == round(d.mc.dem_p)                          # demand position
    assert read(0x1BAF) == round(d.mc.axis.velocity / 10)            # actual velocity, 1E-6 m/s
    assert 0 < read(0x1BAE) <= 1_000_000                              # demand velocity
    assert read(0x1B62) & 0xFFFF == d.mc.state_var
    assert read(0x1D51) & 0xFFFF == d.mc.status_word and read(0x1D51) & 0x2000
    assert read(0x1B90) == 500_000                                    # target position
