"""The VAI families of issue 20 section 3 (protocol/commands/vai_variants.py, system_mc.py) on the emulated
E1100: every row is accepted (no 0081h); golden timing per family from the kinematics (t = d/v + v/(2 acc) +
v/(2 dec) for a trapezoid, 2 sqrt(d/a) for a triangle with dec = acc), not from the emulator; the From Act Pos
starts, the 16-bit and predefined units; the queued "After Actual Command" move; infinite motion; the position
transitions; the maximal current; Select Position Controller Set and Reset.

Commands up to 12 parameter bytes travel in RxPDO2 + RxPDO3 (2041h = 2, par bytes 6..11); the longer ones as a
command-table entry started with 200xh, the transport the catalogue names for them.
"""

from __future__ import annotations

import math

import pytest

from catalogue_programs import NEW_ROWS
from linmot_st.bus.frame import Frame
from linmot_st.emulator import DriveTimings, E1100Drive, build_entry, load_profile
from linmot_st.emulator.testing import MotionLink
from linmot_st.protocol import commands as C
from linmot_st.protocol import words as W
from repo_paths import VECTORS

MS = 1_000_000
MM = 10_000           # pu per mm
CYCLE = MS

# the rows this issue adds: catalogue_programs.NEW_ROWS


def homed_link(defaults: dict | None = None) -> MotionLink:
    values = {0x1194: 2, 0x146F: 280 * MM, 0x146E: -10 * MM, 0x2041: 2}    # RxPDO3 = par bytes 6..11
    values.update(defaults or {})
    d = E1100Drive(1, load_profile().with_defaults(values), timings=DriveTimings.fast())
    link = MotionLink(d)
    link.enable()
    link.home()
    link.advance(MS)
    return link


def run(link: MotionLink, cid: int, dt_ns: int = 0, **fields) -> None:
    """The command over RxPDO2/3, or (more than 12 parameter bytes) as command-table entry 1 started by 200xh."""
    if C.COMMANDS[cid].transport is C.Transport.COMMAND_TABLE:
        link.drive.ct.ram[1] = build_entry(cid << 4, C.encode(cid, 0, **fields)[2:])
        link.command(C.START_COMMAND_TABLE, dt_ns, entry=1)
    else:
        link.command(cid, dt_ns, **fields)


def samples(link: MotionLink, t0: int):
    return link.drive.mc.trajectory.between(t0)


def motion_window(link: MotionLink, t0: int) -> tuple[int, int]:
    """First and last sample (ns after t0) with Motion Active set."""
    active = [s.t_ns for s in samples(link, t0) if s.status_word & W.SW_MOTION_ACTIVE]
    return active[0] - t0, active[-1] - t0


def sample_fields(c: C.CommandDef) -> dict:
    """Plausible values for every field of a row: 10 mm, 0.1 m/s, 1 m/s^2 in its units."""
    values = {}
    for f in c.fields:
        small = f.type in ("INT", "UINT")
        values[f.name] = {
            "target": 100 if small else 10 * MM, "position": 50 if small else 5 * MM,
            "vmax": 100 if small else 100_000, "acc": 10 if small else 100_000, "dec": 10 if small else 100_000,
            "max_current": 5000, "controller_set": 1}[f.name]
    return values


# ---------------------------------------------------------------- every row: accepted, encoded alike

def test_the_new_rows_are_in_the_catalogue_with_their_transport():
    assert len(NEW_ROWS) == 40
    for cid in NEW_ROWS:
        c = C.COMMANDS[cid]
        assert c.source.startswith("[MC] 4.3.")
    assert C.COMMANDS[0x0C5].transport is C.Transport.COMMAND_TABLE      # 14 bytes
    assert C.COMMANDS[0x0C0].transport is C.Transport.RXPDO3             # 12 bytes
    assert C.COMMANDS[0x0B0].transport is C.Transport.RXPDO3             # 8 bytes
    assert C.COMMANDS[0x0A0].transport is C.Transport.RXPDO2             # 2 bytes
    # seed 004 4.2: master IDs 01h/02h on both drives; the rest E1100 only
    assert {cid for cid in NEW_ROWS if C.B1100 in C.COMMANDS[cid].drives} == {
        0x018, 0x01E, 0x01F, 0x023, 0x024, 0x028, 0x02E, 0x02F}


@pytest.mark.parametrize("cid", NEW_ROWS, ids=lambda cid: f"{cid:03X}h")
def test_every_new_row_is_accepted_by_the_drive(cid):
    link = homed_link()
    d, mc = link.drive, link.drive.mc
    t0 = link.t
    run(link, cid, **sample_fields(C.COMMANDS[cid]))
    link.advance(20 * MS)
    assert (t0, cid) in {(t, h >> 4) for t, h, _ in mc.executed} or cid == C.RESET
    assert W.ERR_UNKNOWN_MOTION_CMD not in [e.code for e in d.errlog.entries]
    if cid == C.RESET:                      # the firmware restarted: booted again, MC not yet enabled
        assert d.nmt_state != "OPERATIONAL" and not mc.homed
    else:
        assert mc.state == W.OPERATION_ENABLED and mc.error_code == 0


def test_the_shared_vectors_of_the_new_rows():
    """tests/vectors/motion_commands_vai.json: images written by hand from the layouts of [MC] 4.3."""
    import json

    data = json.loads((VECTORS / "motion_commands_vai.json").read_text())
    cids = set()
    for v in data["vectors"]:
        cid, image = int(v["cid"], 16), bytes.fromhex(v["image"])
        assert C.encode(cid, v["count"], **v["fields"]) == image, v["name"]
        row, fields = C.decode(int.from_bytes(image[:2], "little"), image[2:])
        assert row is C.COMMANDS[cid] and fields == v["fields"], v["name"]
        cids.add(cid)
    # one vector per layout of the new rows
    layouts = {C.COMMANDS[cid].format for cid in NEW_ROWS}
    assert {C.COMMANDS[cid].format for cid in cids} == layouts


# ---------------------------------------------------------------- golden timing per family

def _trapezoid_s(d: float, v: float, acc: float, dec: float) -> float:
    """Duration of a rest-to-rest move (m, m/s, m/s^2): trapezoid, or triangle when v is not reached."""
    if d >= v * v / (2 * acc) + v * v / (2 * dec):
        return d / v + v / (2 * acc) + v / (2 * dec)
    vp = math.sqrt(2 * d / (1 / acc + 1 / dec))
    return vp / acc + vp / dec


PREDEF = {0x14BE: 400_000, 0x14BF: 200_000, 0x14C0: 400_000}   # predefined: 0.4 m/s, 2 m/s^2, 4 m/s^2

GOLDEN = [
    # (command, fields, defaults, distance m, vmax, acc, dec)
    (0x0C0, dict(target=100 * MM, vmax=500_000, acc=500_000), {}, 0.1, 0.5, 5.0, 5.0),          # dec=acc trapezoid
    (0x0C0, dict(target=20 * MM, vmax=1_000_000, acc=1_000_000), {}, 0.02, 1.0, 10.0, 10.0),    # dec=acc triangle
    (0x0C1, dict(target=30 * MM, vmax=500_000, acc=500_000), {}, 0.03, 0.5, 5.0, 5.0),          # increment dem pos
    (0x0B0, dict(target=100 * MM, vmax=300_000), PREDEF, 0.1, 0.3, 2.0, 4.0),                   # predef acc/dec
    (0x0B1, dict(target=50 * MM, vmax=300_000), PREDEF, 0.05, 0.3, 2.0, 4.0),
    (0x0A0, dict(target=1000), PREDEF, 0.1, 0.4, 2.0, 4.0),                                     # 16 bit: 0.1 mm
    (0x0A1, dict(target=500), PREDEF, 0.05, 0.4, 2.0, 4.0),
    (0x0D1, dict(target=1000, vmax=500, acc=50), {}, 0.1, 0.5, 5.0, 5.0),                       # 16 bit dec=acc
    (0x0D1, dict(target=1000, vmax=500, acc=50), {0x14C8: 2000}, 0.2, 0.5, 5.0, 5.0),           # 0.2 mm units
    (0x0C8, dict(target=100 * MM, vmax=500_000, acc=500_000), {}, 0.1, 0.5, 5.0, 5.0),          # queue, at rest
    (0x028, dict(target=100 * MM), PREDEF, 0.1, 0.4, 2.0, 4.0),
    (0x098, dict(target=1000, vmax=500, acc=50, dec=100), {}, 0.1, 0.5, 5.0, 10.0),
    (0x0A8, dict(target=1000), PREDEF, 0.1, 0.4, 2.0, 4.0),
    (0x0B8, dict(target=100 * MM, vmax=300_000), PREDEF, 0.1, 0.3, 2.0, 4.0),
    (0x018, dict(target=100 * MM, vmax=500_000, acc=500_000, dec=250_000), {}, 0.1, 0.5, 5.0, 2.5),
]


@pytest.mark.parametrize("cid, fields, defaults, d, v, acc, dec", GOLDEN,
                         ids=[f"{g[0]:03X}h-{i}" for i, g in enumerate(GOLDEN)])
def test_golden_timing(cid, fields, defaults, d, v, acc, dec):
    link = homed_link(defaults)
    t0 = link.t
    run(link, cid, **fields)
    link.advance(int(3e9))
    t_end = _trapezoid_s(d, v, acc, dec)
    start, end = motion_window(link, t0)
    queued = C.COMMANDS[cid].start is C.Start.AFTER_ACTUAL_COMMAND
    # at rest, a queued move starts one cycle later: the cycle of the command shows Motion Active 0
    assert start == (CYCLE if queued else 0)
    assert abs(end - start - t_end * 1e9) <= CYCLE
    # the peak velocity, as sampled once per cycle
    peak = min(v, math.sqrt(2 * d / (1 / acc + 1 / dec)))
    vmax_seen = max(abs(s.demand_velocity) for s in samples(link, t0)) * 1e-7
    assert peak - max(acc, dec) * CYCLE * 1e-9 <= vmax_seen <= peak + 1e-9
    assert link.drive.mc.axis.position == pytest.approx(d * 1e7, abs=0.5)


def test_from_act_pos_variants_start_from_the_actual_position():
    """093h/0A3h/0B3h/0C3h/023h: actual position and velocity; 094h/0A4h/0B4h/0C4h/024h: actual position, demand
    velocity 0; 095h/096h: the increment on the actual position. The slider is pushed 2 mm off its demand first."""
    cases = [
        (0x093, dict(target=500, vmax=100, acc=10, dec=10)), (0x094, dict(target=500, vmax=100, acc=10, dec=10)),
        (0x0A3, dict(target=500)), (0x0A4, dict(target=500)),
        (0x0B3, dict(target=50 * MM, vmax=100_000)), (0x0B4, dict(target=50 * MM, vmax=100_000)),
        (0x0C3, dict(target=50 * MM, vmax=100_000, acc=100_000)),
        (0x0C4, dict(target=50 * MM, vmax=100_000, acc=100_000)),
        (0x023, dict(target=50 * MM)), (0x024, dict(target=50 * MM)),
        (0x095, dict(target=300, vmax=100, acc=10, dec=10)), (0x096, dict(target=300, vmax=100, acc=10, dec=10)),
    ]
    for cid, fields in cases:
        link = homed_link({0x1473: 100 * MM, 0x1475: 100 * MM})      # the push must not raise a lag error
        mc = link.drive.mc
        mc.push(2 * MM, link.t)
        t0 = link.t
        actual = mc.axis.position
        assert actual == pytest.approx(2 * MM) and mc.dem_p == 0
        run(link, cid, **fields)
        p, v, _ = mc.gen.at(t0)                                            # where the new plan starts
        assert p == pytest.approx(actual) and v == 0, f"{cid:03X}h"
        link.advance(int(3e9))
        goal = 30 * MM + actual if cid in (0x095, 0x096) else 50 * MM       # 300 x 0.1 mm
        assert mc.dem_p == pytest.approx(goal, abs=1e-6), f"{cid:03X}h"


def test_from_act_pos_and_act_vel_keeps_the_velocity_vel_0_does_not():
    """Mid-motion (0.1 m/s), 0C3h starts from the actual velocity, 0C4h from demand velocity 0."""
    for cid, v_start in ((0x0C3, 0.1), (0x0C4, 0.0)):
        link = homed_link()
        mc = link.drive.mc
        run(link, 0x0C0, target=200 * MM, vmax=100_000, acc=1_000_000)
        link.advance(100 * MS)                                         # cruising at 0.1 m/s
        t0 = link.t
        actual_p, actual_v = mc.axis.position, mc.axis.velocity
        assert actual_v * 1e-7 == pytest.approx(0.1, abs=1e-3) and actual_p != mc.dem_p   # lagging a little
        run(link, cid, target=150 * MM, vmax=100_000, acc=1_000_000)
        p, v, _ = mc.gen.at(t0)                                            # where the new plan starts
        assert p == actual_p and v == (actual_v if v_start else 0.0), f"{cid:03X}h"


# ---------------------------------------------------------------- the queue (After Actual Command)

@pytest.mark.parametrize("cid, fields", [(0x028, dict(target=0)), (0x0C8, dict(target=0, vmax=500_000, acc=500_000)),
                                         (0x018, dict(target=0, vmax=500_000, acc=500_000, dec=500_000))],
                         ids=["028h", "0C8h", "018h"])
def test_a_queued_move_starts_when_motion_active_drops_and_not_before(cid, fields):
    link = homed_link(PREDEF)
    mc = link.drive.mc
    run(link, 0x0C0, target=50 * MM, vmax=500_000, acc=500_000)       # 0 -> 50 mm: 0.1 + 0.1 s
    link.advance(50 * MS)
    t_queue = link.t
    run(link, cid, **fields)
    link.advance(2 * MS)
    assert mc.status_word & W.SW_EVENT_HANDLER and mc.state_var & W.SV_EVENT_HANDLER      # the handler waits
    assert mc.gen.target == 50 * MM                                    # the running move goes on unchanged
    link.advance(1000 * MS)
    trace = samples(link, t_queue)
    idle = [s for s in trace if not s.status_word & W.SW_MOTION_ACTIVE]
    first_idle = idle[0]
    # the first move ended as planned (50 mm after 200 ms) and its last cycle shows Motion Active 0 ...
    assert first_idle.demand == 50 * MM and first_idle.t_ns == pytest.approx(t_queue + 150 * MS, abs=CYCLE)
    before = [s for s in trace if s.t_ns <= first_idle.t_ns]
    assert all(s.demand_velocity >= 0 for s in before)                 # nothing of the queued move before
    # ... the queued move starts in the next cycle and is back at 0 mm
    after = [s for s in trace if s.t_ns > first_idle.t_ns]
    assert after[0].t_ns == first_idle.t_ns + CYCLE and after[0].status_word & W.SW_MOTION_ACTIVE
    assert not after[0].status_word & W.SW_EVENT_HANDLER               # one shot: the handler is off
    assert mc.dem_p == 0 and not mc.status_word & W.SW_EVENT_HANDLER


def test_a_stop_ends_the_running_motion_so_the_queued_one_starts_and_a_newer_queue_replaces_it():
    link = homed_link()
    mc = link.drive.mc
    run(link, 0x0C0, target=50 * MM, vmax=500_000, acc=500_000)
    link.advance(20 * MS)
    run(link, 0x0C8, target=20 * MM, vmax=500_000, acc=500_000)
    run(link, 0x0C8, target=30 * MM, vmax=500_000, acc=500_000, dt_ns=MS)      # replaces the 20 mm
    run(link, C.VAI_STOP, dt_ns=MS, dec=1_000_000)
    link.advance(600 * MS)
    assert mc.dem_p == 30 * MM and not mc.pending.armed


def test_with_the_setting_a_stop_drops_the_queued_move():
    from linmot_st.emulator.linmot.motion import MotionSettings

    values = {0x1194: 2, 0x146F: 280 * MM, 0x146E: -10 * MM, 0x2041: 2}
    d = E1100Drive(1, load_profile().with_defaults(values), timings=DriveTimings.fast(),
                   motion=MotionSettings(stop_drops_pending=True))
    link = MotionLink(d)
    link.enable()
    link.home()
    run(link, 0x0C0, target=50 * MM, vmax=500_000, acc=500_000, dt_ns=MS)
    link.advance(20 * MS)
    run(link, 0x0C8, target=30 * MM, vmax=500_000, acc=500_000)
    run(link, C.VAI_STOP, dt_ns=MS, dec=1_000_000)
    link.advance(2 * MS)
    assert not d.mc.pending.armed and not d.mc.status_word & W.SW_EVENT_HANDLER
    link.advance(600 * MS)
    assert d.mc.dem_p < 30 * MM and d.mc.in_target                   # stopped where the ramp ended


def test_a_queue_is_dropped_when_the_drive_leaves_operation_enabled():
    link = homed_link()
    mc = link.drive.mc
    run(link, 0x0C0, target=50 * MM, vmax=500_000, acc=500_000)
    link.advance(20 * MS)
    run(link, 0x0C8, target=0, vmax=500_000, acc=500_000)
    link.advance(2 * MS)
    link.cw(0x003E)                                                   # Enable Operation off: state 6
    link.advance(500 * MS)
    assert not mc.pending.armed and not mc.status_word & W.SW_EVENT_HANDLER
    link.cw(0x003F)
    link.advance(500 * MS)
    assert mc.state == W.OPERATION_ENABLED and mc.dem_p != 0           # the queued move did not run


# ---------------------------------------------------------------- infinite motion

@pytest.mark.parametrize("cid, sign", [(0x02E, 1), (0x02F, -1)], ids=["02Eh", "02Fh"])
def test_infinite_motion_at_the_predefined_velocity_until_stopped(cid, sign):
    link = homed_link({**PREDEF, 0x146E: -280 * MM})
    mc = link.drive.mc
    start = 100 * MM
    run(link, 0x0C0, target=start if sign > 0 else 200 * MM, vmax=1_000_000, acc=1_000_000)
    link.advance(600 * MS)
    p0 = mc.dem_p
    t0 = link.t
    run(link, cid)
    link.advance(300 * MS)                                             # 0.2 s ramp (0.4 m/s at 2 m/s^2)
    trace = samples(link, t0)
    ramp_end = next(s for s in trace if abs(s.demand_velocity) * 1e-7 >= 0.4 - 1e-9)
    assert (ramp_end.t_ns - t0) == pytest.approx(200 * MS, abs=CYCLE)
    assert all(s.status_word & W.SW_MOTION_ACTIVE and not s.status_word & W.SW_IN_TARGET for s in trace)
    assert all(s.demand_velocity * 1e-7 * sign == pytest.approx(0.4) for s in trace if s.t_ns >= ramp_end.t_ns)
    # the demand after 0.3 s: 0.04 m in the ramp, then 0.1 s at 0.4 m/s
    assert (mc.dem_p - p0) * sign == pytest.approx(0.08e7, abs=1)
    t1 = link.t
    run(link, C.VAI_STOP, dec=1_000_000)                               # 10 m/s^2: 40 ms to rest
    link.advance(200 * MS)
    start, end = motion_window(link, t1)
    assert end == pytest.approx(40 * MS, abs=CYCLE)
    assert mc.in_target and mc.state == W.OPERATION_ENABLED


def test_infinite_motion_runs_into_the_position_limit():
    link = homed_link({**PREDEF, 0x146F: 100 * MM})
    mc = link.drive.mc
    run(link, 0x02E)
    link.advance(int(2e9))
    assert mc.state == W.ERROR and mc.error_code == W.ERR_MAX_POS_OVERSHOT


# ---------------------------------------------------------------- position transitions

def test_positive_transition_changes_vmax_at_the_crossing():
    """09Eh at 30 mm: the move 0 -> 100 mm at 0.5 m/s slows to 0.1 m/s (new dec 2 m/s^2) once the demand has
    passed 30 mm; its target stays."""
    link = homed_link()
    mc = link.drive.mc
    t0 = link.t
    run(link, 0x09E, position=300, vmax=100, acc=20, dec=20)
    link.advance(MS)
    assert mc.status_word & W.SW_EVENT_HANDLER
    run(link, 0x0C0, target=100 * MM, vmax=500_000, acc=500_000)
    link.advance(int(2e9))
    trace = samples(link, t0)
    crossing = next(s for s in trace if s.demand >= 30 * MM)
    before = [s for s in trace if s.t_ns < crossing.t_ns]
    assert max(s.demand_velocity for s in before) * 1e-7 == pytest.approx(0.5)           # still the old vmax
    after = [s for s in trace if s.t_ns > crossing.t_ns]
    # decelerating with the new dec (2 m/s^2) from 0.5 to 0.1 m/s: 200 ms, then cruising at the new vmax
    slow = next(s for s in after if s.demand_velocity * 1e-7 <= 0.1 + 1e-9)
    assert slow.t_ns - crossing.t_ns == pytest.approx(200 * MS, abs=CYCLE)
    assert after[0].demand_velocity * 1e-7 == pytest.approx(0.5 - 2 * 1e-3, abs=1e-6)
    assert mc.dem_p == 100 * MM and not mc.status_word & W.SW_EVENT_HANDLER           # the target stays; one shot
    # golden: 0.1 s up to 0.5 m/s (25 mm), 10 ms to 30 mm, 0.2 s down to 0.1 m/s (60 mm), then the last 10 mm:
    # 75 ms at 0.1 m/s and 50 ms braking at 2 m/s^2 (2.5 mm)
    start, end = motion_window(link, t0)
    assert end - start == pytest.approx((0.1 + 0.01 + 0.2 + 0.075 + 0.05) * 1e9, abs=2 * CYCLE)


def test_negative_transition_does_not_fire_on_the_way_up_but_on_the_way_down():
    link = homed_link()
    mc = link.drive.mc
    run(link, 0x01F, position=50 * MM, vmax=100_000, acc=500_000, dec=500_000)      # 16 bytes: a CT entry
    link.advance(MS)
    run(link, 0x0C0, target=100 * MM, vmax=500_000, acc=500_000)
    link.advance(600 * MS)
    assert mc.dem_p == 100 * MM and mc.pending.transition is not None                 # passed upwards: armed
    t0 = link.t
    run(link, 0x0C0, target=0, vmax=500_000, acc=500_000)
    link.advance(int(2e9))
    trace = samples(link, t0)
    crossing = next(s for s in trace if s.demand <= 50 * MM)
    assert crossing.t_ns - t0 == pytest.approx(150 * MS, abs=CYCLE)
    # 80 ms from -0.5 to -0.1 m/s (24 mm), 1 mm braking at the end (20 ms), 25 mm at 0.1 m/s between
    assert all(s.demand_velocity * 1e-7 >= -0.1 - 1e-9 for s in trace if s.t_ns > crossing.t_ns + 80 * MS)
    start, end = motion_window(link, t0)
    assert end - start == pytest.approx((0.15 + 0.08 + 0.25 + 0.02) * 1e9, abs=2 * CYCLE)
    assert mc.dem_p == 0 and mc.pending.transition is None


# ---------------------------------------------------------------- max current, controller sets, reset

LAX_LAG = {0x1472: 300 * MM, 0x1473: 300 * MM, 0x1474: 300 * MM, 0x1475: 300 * MM}


def test_max_current_limits_the_force_and_is_written_into_the_active_set():
    """0C5h with 1 A: the model's 0.5 kg and 10 N/A reach 20 m/s^2 at most, so a 50 m/s^2 demand lags; 0C6h
    brings the axis back with 8 A, which follows again."""
    link = homed_link(LAX_LAG)
    d, mc = link.drive, link.drive.mc
    t0 = link.t
    run(link, 0x0C5, target=100 * MM, vmax=2_000_000, acc=5_000_000, max_current=1000)
    link.advance(500 * MS)
    assert d.ram(0x13A6) == 1000 and d.ram(0x13BA) == 8000
    trace = samples(link, t0)
    acc_actual = [abs(b.actual_velocity - a.actual_velocity) / 1e-3 * 1e-7 for a, b in zip(trace, trace[1:])]
    assert max(acc_actual) <= 20.0 + 1e-6 and max(acc_actual) > 19.9
    assert max(abs(a.demand - a.actual) for a in trace) > 10 * MM                    # it could not follow
    assert mc.axis.position == pytest.approx(100 * MM, abs=MM)
    t1 = link.t
    run(link, 0x0C6, target=0, vmax=500_000, acc=500_000, max_current=8000)
    link.advance(500 * MS)
    assert d.ram(0x13A6) == 8000
    assert max(abs(s.demand - s.actual) for s in samples(link, t1)) < 0.5 * MM
    assert mc.axis.position == pytest.approx(0, abs=1)


def test_select_position_controller_set_chooses_which_max_current_is_written():
    link = homed_link(LAX_LAG)
    d = link.drive
    run(link, C.SELECT_POSITION_CONTROLLER_SET, controller_set=1)
    link.advance(MS)
    assert d.ram(0x1393) == 1
    run(link, 0x0C7, target=10 * MM, vmax=100_000, acc=100_000, max_current=2500)
    link.advance(300 * MS)
    assert d.ram(0x13BA) == 2500 and d.ram(0x13A6) == 8000
    run(link, C.SELECT_POSITION_CONTROLLER_SET, controller_set=7)                    # not a set: ignored
    link.advance(MS)
    assert d.ram(0x1393) == 1 and link.drive.mc.state == W.OPERATION_ENABLED


def test_reset_restarts_the_drive_and_only_a_count_other_than_0_repeats_it():
    """[MC] 4.3.8: "use this command with count = 0, otherwise the drive reboots cyclic": after the boot the
    interface's last count is 0, so the same RxPDO sent again runs the reset again unless its count is 0."""
    link = homed_link()
    d = link.drive
    link.advance(10 * MS)

    def boots() -> int:
        return len([f for _, f in link.received if f.can_id == 0x701 and bytes(f.data) == b"\0"])

    def send_reset(count: int) -> None:
        raw = C.encode(C.RESET, count).ljust(14, b"\0")
        link.send(Frame(0x301, raw[0:8]))
        link.send(Frame(0x401, raw[0:2] + raw[8:14]))

    def restart() -> None:                                          # boot, then Operational again
        link.advance(int(5e9))
        link.nmt(0x01)
        link.advance(10 * MS)

    link.command(C.NOP)                                             # count 1
    link.advance(MS)
    n = boots()
    send_reset(0)                                                   # count 0 differs from 1: runs
    restart()
    assert boots() == n + 1 and not d.mc.homed
    send_reset(0)                                                   # the same frame after the boot: count 0 = last
    restart()
    assert boots() == n + 1
    send_reset(3)                                                   # count 3: runs, the drive reboots ...
    restart()
    assert boots() == n + 2
    send_reset(3)                                                   # ... and the same frame again reboots it again
    restart()
    assert boots() == n + 3
