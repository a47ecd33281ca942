"""The fast path of the motion model (quiet MC cycles in a tight loop and ahead of the bus, the plans' forward
walk, the inlined axis step) changes nothing: the bench scenario and the motion scenarios of the other motion
tests (moves, re-targeting, stops, quick stop, freeze, abort, time curves, a command table, errors and their
acknowledgement) give the same frames at the same times, the same trajectory samples and the same error log
with the fast path off (MotionSettings(quiet_cycles=False): every MC cycle through the generic path) and on.
Compared exactly (==), float for float."""

from __future__ import annotations

import random

import pytest

from linmot_st.bus import Frame
from linmot_st.emulator import Curve, DriveTimings, E1100Drive, build_entry, load_profile
from linmot_st.emulator.linmot.motion import MotionSettings
from linmot_st.emulator.linmot.motion.setpoints import CurvePlan, Hold, StopPlan, VaPlan
from linmot_st.emulator.testing import MotionLink
from linmot_st.protocol import commands as C
from linmot_st.pvl import load_pvl
from linmot_st_bench import emulator_mc as bench
from repo_paths import EXAMPLES

MS = 1_000_000
MM = 10_000
PVL = EXAMPLES / "two_axes.pvl"


# ---- the bench scenario --------------------------------------------------------------------------------
def _mc_state(d) -> tuple:
    """What the samples and frames do not show in full (the acceleration only reaches TxPDO2 rounded)."""
    mc, axis = d.mc, d.mc.axis
    return (axis.physical, axis.velocity, axis.acceleration, mc.dem_p, mc.dem_v, mc.words, mc.in_target)


def _bench_run(quiet: bool, n_drives: int):
    bus, master, drives = bench._setup(n_drives, MotionSettings(quiet_cycles=quiet))
    states = []
    for k in range(1, 25):                       # observed now and then, as the bench and tests do
        bus.run_until(master.moves_from + k * 70 * MS + k * 37_000)
        states.append([_mc_state(d) for d in drives])
    trace = [(e.start_ns, e.end_ns, e.sender, e.frame, e.status) for e in bus.trace]
    return trace, [list(d.mc.trajectory.samples) for d in drives], [d.errlog.entries for d in drives], states


@pytest.mark.parametrize("n_drives", [1, 3])
def test_bench_scenario_is_the_same_with_the_fast_path_off_and_on(n_drives):
    ref_trace, ref_samples, ref_errors, ref_states = _bench_run(False, n_drives)
    trace, samples, errors, states = _bench_run(True, n_drives)
    assert len(trace) > 400 * n_drives and trace == ref_trace
    assert all(len(s) > 1000 for s in samples) and samples == ref_samples
    assert errors == ref_errors and states == ref_states


# ---- the motion scenarios ------------------------------------------------------------------------------
def _pars(cid: int, **fields) -> bytes:
    return C.encode(cid, 0, **fields)[2:]


CT_SEQUENCE = {   # as tests/st_lib/motion/test_motion_ct.py writes it with the library (here put in the drive's flash)
    1: (C.VAI_GO_TO_POS << 4, _pars(C.VAI_GO_TO_POS, target=50 * MM, vmax=500_000, acc=500_000, dec=500_000), 2),
    2: (C.WAIT_IN_TARGET_POSITION << 4, b"", 3),
    3: (C.WAIT_TIME << 4, _pars(C.WAIT_TIME, time=1000), 4),
    4: (C.PREDEF_VAI_GO_TO_POS << 4, _pars(C.PREDEF_VAI_GO_TO_POS, target=10 * MM), 5),
    5: (C.WAIT_MOTION_FINISHED << 4, b"", 0xFFFF),
}


def _link(quiet: bool, sync: bool, hold_ns: int) -> MotionLink:
    values = {0x1194: 2, 0x146F: 280 * MM, 0x146E: -10 * MM, 0x2041: 2, 0x1530: 2_000_000,
              0x14BE: 500_000, 0x14BF: 500_000, 0x14C0: 500_000}
    d = E1100Drive(1, load_profile().with_defaults(values), timings=DriveTimings.fast(),
                   motion=MotionSettings(quiet_cycles=quiet, in_target_hold_ns=hold_ns))
    d.curves.flash.update({c.curve_id: Curve(c.curve_id, c.info_block, c.data_block)
                           for c in load_pvl(PVL).curves})
    d.ct.flash.update({e: build_entry(h, p, link=k, name=f"step{e}") for e, (h, p, k) in CT_SEQUENCE.items()})
    if sync:                                     # TxPDO2 on every SYNC: the MC may compute ahead of the bus
        d.comm.objects[0x1801].subs[2].default = 1
        d.comm.reset()
    return MotionLink(d)


def _scenario(quiet: bool, sync: bool, hold_ns: int = 0):
    link = _link(quiet, sync, hold_ns)
    d = link.drive

    states = []

    def go(ms: int) -> None:                     # time passes; a master sends SYNC every 4 ms where asked
        for _ in range(ms // 4):
            if sync:
                link.send(Frame(0x080, b""))
            link.advance(4 * MS)
        link.advance(13_000)                     # observed off the cycle grid too
        states.append(_mc_state(d))

    def ack() -> None:                           # error acknowledge (rising bit 7), switch on again
        for word in (0x00BF, 0x003E, 0x003F):    # one per SYNC period: RxPDOs may act on SYNC only
            link.cw(word)
            go(8)
        go(40)

    link.cw(0x003E)                              # enable and home (RxPDOs act on SYNC where TxPDO2 is synchronous)
    go(8)
    link.cw(0x003F)
    go(60)
    link.cw(0x083F)
    go(100)
    link.cw(0x003F)
    go(20)
    assert d.mc.state == 8 and d.mc.homed
    link.command(C.VAI16_GO_TO_POS, target=1000, vmax=1000, acc=100, dec=100)
    go(120)
    link.command(C.VAI16_GO_TO_POS, target=200, vmax=700, acc=80, dec=80)             # re-target mid-motion
    go(600)
    link.command(C.VAI16_GO_TO_POS, target=2000, vmax=1000, acc=100, dec=100)
    go(200)
    link.command(C.VAI_STOP, dec=500_000)                                                # VAI stop
    go(300)
    link.command(C.VAI16_GO_TO_POS, target=300, vmax=1500, acc=200, dec=200)
    go(60)
    link.cw(0x001F)                                                                      # freeze ...
    go(100)
    link.cw(0x003F)                                                                      # ... and resume
    go(100)
    link.cw(0x002F)                                                                      # abort
    go(60)
    link.cw(0x003F)
    go(20)
    link.command(C.VAI16_GO_TO_POS, target=0, vmax=1000, acc=100, dec=100)              # the curves start at 0
    go(500)
    link.command(C.TIME_CURVE, curve_id=1)                                               # commissioned curve
    go(500)
    link.command(C.VAI16_GO_TO_POS, target=0, vmax=1000, acc=100, dec=100)
    go(500)
    link.command(C.TIME_CURVE_OFFSET_TIME_SCALE_AMP, curve_id=1, offset=0, time_scale=5000, amplitude=500)
    go(300)
    link.command(C.VAI16_GO_TO_POS, target=500, vmax=1000, acc=100, dec=100)
    go(500)
    link.command(C.TIME_CURVE_OFFSET_TIME_AMP, curve_id=1, offset=50 * MM, curve_time=25_000, amplitude=-400)
    go(400)
    link.command(C.START_COMMAND_TABLE, entry=1)                                        # command table
    go(900)
    link.command(C.VAI16_GO_TO_POS, target=1000, vmax=500, acc=50, dec=50)
    go(100)
    d.mc.block(True, link.t)                                                             # following error
    go(200)
    d.mc.block(False, link.t)
    ack()
    link.command(C.VAI16_GO_TO_POS, target=2900, vmax=1000, acc=100, dec=100)           # towards the limit
    go(700)
    ack()
    link.command(C.VAI16_GO_TO_POS, target=1500, vmax=1000, acc=100, dec=100)
    go(150)
    link.cw(0x003B)                                                                      # quick stop
    go(200)
    link.cw(0x003E)
    go(8)
    link.cw(0x003F)
    go(40)
    link.command(C.TIME_CURVE, curve_id=5)                                               # not in RAM: 0062h
    go(20)
    ack()
    d.mc.push(8000, link.t)                                                              # a disturbance
    go(300)
    trace = [(t, f) for t, f in link.received]
    return trace, list(d.mc.trajectory.samples), d.errlog.entries, list(d.mc.executed), states


@pytest.mark.parametrize("sync, hold_ns", [(False, 0), (True, 0), (True, 5 * MS)])
def test_motion_scenarios_are_the_same_with_the_fast_path_off_and_on(sync, hold_ns):
    ref = _scenario(False, sync, hold_ns)
    got = _scenario(True, sync, hold_ns)
    trace, samples, errors, executed, states = got
    assert {e.code for e in errors} >= {0x000B, 0x0062}             # the error cases were reached
    assert {s.state for s in samples} >= {4, 8, 12, 13, 14}          # error, enabled, aborting, freezing, stop
    assert any(header >> 4 == C.START_COMMAND_TABLE for _, header, _ in executed) and len(executed) >= 18
    assert trace == ref[0]
    assert len(samples) > 4000 and samples == ref[1]
    assert errors == ref[2] and executed == ref[3] and states == ref[4]


# ---- the plans' forward walk -----------------------------------------------------------------------------
def _take(it, n):
    return [next(it) for _ in range(n)]


def test_plan_demands_walk_gives_at_values_bit_for_bit():
    rnd = random.Random(8)
    curve = [rnd.randint(-30000, 30000) for _ in range(40)]
    plans = [Hold(123.5), CurvePlan(3 * MS, 1, curve, 310 * MS + 7, 1000.0, 0.75)]
    for _ in range(300):
        origin = rnd.randint(0, 50) * MS + rnd.choice([0, 1, 999_999])
        p0, v0 = rnd.uniform(-1e6, 1e6), rnd.choice([0.0, rnd.uniform(-2e7, 2e7)])
        plans.append(VaPlan(origin, p0, v0, rnd.uniform(-3e6, 3e6), rnd.uniform(1e5, 3e7), rnd.uniform(1e6, 3e8),
                            rnd.uniform(1e6, 3e8)))
        plans.append(StopPlan(origin, p0, v0, rnd.uniform(1e6, 3e8)))
    for plan in plans:
        start = rnd.randint(0, 60) * MS
        walked = _take(plan.demands(start, MS), 1500)
        assert walked == [plan.at(start + k * MS)[:2] for k in range(1500)], plan
