"""The motion FBs' own PLCopen rules (spec/linmot-motion.md 5), beside the one suite every Execute-type FB
passes (tests/st_lib/test_plcopen.py, its motion FB list tests/st_lib/plcopen_motion_fbs.py): the FBs that run
until something ends them (CONTINUOUS: MC_MoveVelocity with InVelocity, MC_CamIn with InSync), MC_Jog, whose
JogForward / JogBackward are levels, and MC_Reset, which needs an error to acknowledge before each run."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import pytest

from motionbench import MotionBench
from plcopen_checks import (
    IDLE,
    assert_exclusive,
    check_done_held,
    check_one_scan_pulse,
    check_reset_on_falling_edge,
    outputs,
    run_recording,
)
from plcopen_motion_fbs import CAM_INPUTS, MOVE, MS, bench, cam_table_1, curves_and_table, rx_frames


# ---------------------------------------------------------------- FBs that run until something ends them
@dataclass
class Continuous:
    name: str
    state: str                                 # the output that says it reached its motion
    inputs: dict
    alt: dict                                  # set while Busy: must change nothing
    bad: dict                                  # invalid: Error before any frame
    newer: tuple                               # the FB that ends it (CommandAborted)
    setup: Callable[[MotionBench], None] | None = None
    ready: Callable[[MotionBench], None] | None = None
    defaults: dict | None = None


CONTINUOUS = [
    Continuous("MVV", "INVELOCITY", dict(VELOCITY=50.0, ACCELERATION=1000.0, DECELERATION=1000.0,
                                         DIRECTION="LM_DIR_POSITIVE"),
               dict(VELOCITY=90.0), dict(ACCELERATION=0.0), ("HALT", dict(DECELERATION=5000.0))),
    Continuous("CAMIN", "INSYNC", dict(CAMTABLEID=1), dict(CAMTABLEID=2), dict(CAMTABLEID=3), ("CAMOUT", {}),
               setup=curves_and_table, ready=cam_table_1, defaults=CAM_INPUTS),
]
CIDS = [c.name for c in CONTINUOUS]


def state_of(fb, c: Continuous) -> tuple:
    """(reached, Busy, Error, CommandAborted, ErrorID): Done's place taken by InVelocity / InSync."""
    return fb[c.state], fb["BUSY"], fb["ERROR"], fb["COMMANDABORTED"], fb["ERRORID"]


def assert_continuous_exclusive(s: tuple) -> None:
    reached, busy, error, aborted, error_id = s
    assert busy + error + aborted <= 1, s
    assert not reached or busy, s                               # InVelocity / InSync only while Busy
    assert (error_id != 0) == error, s


def reach(b: MotionBench, fb, c: Continuous, execute_scans: int | None = None) -> list[tuple]:
    states = []
    for k in range(1, 1000):
        fb["EXECUTE"] = execute_scans is None or k <= execute_scans
        b.step(1)
        s = state_of(fb, c)
        assert_continuous_exclusive(s)
        states.append(s)
        if s[0] or s[2]:
            return states
    raise AssertionError(f"{c.name} never reached its motion")


def first_commands(b: MotionBench, t0: int) -> list[bytes]:
    return rx_frames(b, t0, (0x301, 0x401))


@pytest.mark.parametrize("c", CONTINUOUS, ids=CIDS)
def test_continuous_busy_until_a_newer_command_aborts_it_held_then_reset(c):
    """Busy from the Execute scan, never Done: it keeps running (Busy, Active, InVelocity / InSync) also after
    Execute fell; the FB that ends it makes it CommandAborted, held while Execute stays TRUE."""
    b = bench(c)
    fb = b.fb(c.name)
    fb.set(**c.inputs)
    states = reach(b, fb, c)
    assert all(s[1] for s in states) and states[-1][0], states[-1]
    b.step(50)
    assert fb["BUSY"] and fb["ACTIVE"] and fb[c.state]
    newer = b.fb(c.newer[0])
    newer.start(**c.newer[1])
    b.sim.run_until(lambda: fb["COMMANDABORTED"] or fb["ERROR"], max_scans=500)
    s = state_of(fb, c)
    assert s[3] and not s[1] and not s[0] and not fb["ACTIVE"], s
    b.step(3)
    assert fb["COMMANDABORTED"]                                  # held while Execute stays TRUE
    fb["EXECUTE"] = False
    b.step(1)
    assert state_of(fb, c) == (False, False, False, False, 0)
    b.sim.run_until(lambda: newer["DONE"], max_scans=1000)


@pytest.mark.parametrize("c", CONTINUOUS, ids=CIDS)
def test_continuous_goes_on_after_execute_fell_and_its_abort_is_a_one_scan_pulse(c):
    b = bench(c)
    fb = b.fb(c.name)
    fb.set(**c.inputs)
    reach(b, fb, c, execute_scans=1)
    b.step(30)
    assert fb["BUSY"] and fb[c.state]                            # Execute low: it runs on
    b.fb(c.newer[0]).start(**c.newer[1])
    seen = []
    for _ in range(300):
        b.step(1)
        s = state_of(fb, c)
        assert_continuous_exclusive(s)
        seen.append(s[3])
        if len(seen) > 3 and seen[-4] and not any(seen[-3:]):
            break
    assert seen.count(True) == 1                                 # CommandAborted for one scan
    assert state_of(fb, c) == (False, False, False, False, 0)


@pytest.mark.parametrize("c", CONTINUOUS, ids=CIDS)
def test_continuous_retrigger_while_busy_is_ignored_and_inputs_are_latched(c):
    b = bench(c)
    fb = b.fb(c.name)
    fb.set(**c.inputs)
    t0 = b.plc.time_ns
    reach(b, fb, c)
    reference = first_commands(b, t0)
    for k in range(6):
        fb["EXECUTE"] = k % 2 == 1                               # low, high, ...: edges while Busy
        if k == 1:
            fb.set(**c.alt)
        b.step(1)
        assert fb["BUSY"] and not fb["ERROR"] and not fb["COMMANDABORTED"]
    b.step(30)
    assert first_commands(b, t0) == reference and fb[c.state]   # no second run, the first one's inputs


@pytest.mark.parametrize("c", CONTINUOUS, ids=CIDS)
def test_continuous_invalid_input_error_before_any_frame_held_then_reset(c):
    b = bench(c)
    fb = b.fb(c.name)
    fb.set(**{**c.inputs, **c.bad})
    t0 = b.plc.time_ns
    fb["EXECUTE"] = True
    b.step(1)
    assert state_of(fb, c)[2] and fb["ERRORID"] != 0
    b.step(5)
    assert state_of(fb, c)[2] and first_commands(b, t0) == []
    fb["EXECUTE"] = False
    b.step(1)
    assert state_of(fb, c) == (False, False, False, False, 0)


# ---------------------------------------------------------------- MC_Jog: JogForward / JogBackward are levels
JOG = dict(VELOCITY=100.0, ACCELERATION=1000.0, DECELERATION=1000.0, INCREMENT=0.0)


def jog_state(b: MotionBench) -> tuple:
    return b["JOG.DONE"], b["JOG.BUSY"], b["JOG.ERROR"], b["JOG.COMMANDABORTED"], b["JOG.ERRORID"]


def jog_bits(b: MotionBench, t0: int) -> list[int]:
    return [p[1] & 0x03 for p in b.payloads(0x201, t0)]            # control word bits 8, 9


@pytest.mark.parametrize("direction, state, bit", [("JOGFORWARD", 16, 0x01), ("JOGBACKWARD", 17, 0x02)])
def test_jog_busy_while_held_then_done_for_one_scan_after_release(direction, state, bit):
    """Busy from the scan the input rises, Active in the jog state while it stays TRUE, never Done while held;
    the input falls: Done for one scan at standstill (Execute is already low), then every output reset."""
    b = MotionBench(nodes=1).ready()
    if direction == "JOGBACKWARD":
        assert b.fb("MVA").run(POSITION=60.0, **MOVE).done
    b.fb("JOG").set(**JOG)
    t0 = b.plc.time_ns
    b[f"JOG.{direction}"] = True
    states = []
    for _ in range(200):
        b.step(1)
        s = jog_state(b)
        assert_exclusive(s)
        states.append(s)
    assert all(s[1] and not s[0] for s in states) and b["JOG.ACTIVE"]
    assert b["RSTAT.STATEVAR"] >> 8 == state and bit in jog_bits(b, t0)
    b[f"JOG.{direction}"] = False
    done_scans = 0
    for _ in range(500):
        b.step(1)
        s = jog_state(b)
        assert_exclusive(s)
        done_scans += s[0]
        if done_scans and not s[0]:
            break
    assert done_scans == 1 and jog_state(b) == IDLE
    assert b["RSTAT.STATEVAR"] >> 8 == 8 and b["RSTAT.STANDSTILL"]


def test_jog_both_directions_error_held_while_an_input_stays_true_before_any_frame():
    b = MotionBench(nodes=1).ready()
    b.fb("JOG").set(**JOG)
    t0 = b.plc.time_ns
    b["JOG.JOGFORWARD"] = True
    b["JOG.JOGBACKWARD"] = True
    b.step(1)
    assert jog_state(b)[2] and b["JOG.ERRORID"] != 0
    b["JOG.JOGBACKWARD"] = False                                   # still one input TRUE: no new edge
    b.step(20)
    assert jog_state(b)[2] and b.payloads(0x301, t0) == [] and all(x == 0 for x in jog_bits(b, t0))
    b["JOG.JOGFORWARD"] = False
    b.step(1)
    assert jog_state(b) == IDLE


def test_jog_inputs_latched_at_the_rising_edge():
    b = MotionBench(nodes=1).ready()
    b.fb("JOG").set(**JOG)
    b["JOG.JOGFORWARD"] = True
    b.step(1)
    b.fb("JOG").set(VELOCITY=20.0, ACCELERATION=9.0)               # while Busy: changes nothing
    b.step(300)
    assert b.drive.mc.params[0x14B0].ram == 100_000                 # 100 mm/s, the edge's
    assert b.drive.mc.params[0x14BF].ram == 100_000                 # 1000 mm/s^2
    b["JOG.JOGFORWARD"] = False
    b.sim.run_until(lambda: b["JOG.DONE"], max_scans=500)


@pytest.mark.parametrize("newer", [("HALT", dict(DECELERATION=5000.0)), ("STOP", dict(DECELERATION=5000.0))])
def test_a_newer_command_aborts_a_jog_held_while_the_input_stays_true(newer):
    b = MotionBench(nodes=1).ready()
    b.fb("JOG").set(**JOG)
    b["JOG.JOGFORWARD"] = True
    b.sim.run_until(lambda: b["JOG.ACTIVE"], max_scans=200)
    t0 = b.plc.time_ns
    other = b.fb(newer[0])
    other.start(**newer[1])
    b.sim.run_until(lambda: b["JOG.COMMANDABORTED"] or b["JOG.ERROR"], max_scans=200)
    s = jog_state(b)
    assert_exclusive(s)
    assert s[3] and not b["JOG.ACTIVE"], s
    b.step(5)
    assert b["JOG.COMMANDABORTED"] and all(x == 0 for x in jog_bits(b, t0)[1:])   # the jog bit dropped
    b["JOG.JOGFORWARD"] = False
    b.step(1)
    assert jog_state(b) == IDLE
    b.sim.run_until(lambda: other["DONE"], max_scans=2000)


# ---------------------------------------------------------------- MC_Reset: each run needs an error to acknowledge
def in_error(b: MotionBench) -> MotionBench:
    """The drive detected a following error (000Bh, not fatal): quick stop, then state 4."""
    b.drive.inject_error(0x000B, b.bus.now)
    b.sim.run_until(lambda: b["RSTAT.STATEVAR"] >> 8 in (4, 14), max_scans=200)
    return b


def ack_edges(b: MotionBench, t0: int) -> int:
    """Rising edges of control word bit 7 (error acknowledge) in the RxPDO1s since t0."""
    bits = [p[0] & 0x80 for p in b.payloads(0x201, t0)]
    return sum(1 for a, z in zip([0] + bits, bits) if z and not a)


def test_reset_done_held_while_execute_then_reset_on_falling_edge():
    b = in_error(MotionBench(nodes=1).ready())
    t0 = b.plc.time_ns
    fb = b.fb("RST")
    check_done_held(b, fb)
    assert fb["ERRORCLEARED"] == 0x000B and ack_edges(b, t0) == 1
    check_reset_on_falling_edge(b, fb)


def test_reset_done_is_a_one_scan_pulse_when_execute_fell_before():
    b = in_error(MotionBench(nodes=1).ready())
    check_one_scan_pulse(b, b.fb("RST"), 0)


def test_reset_retrigger_while_busy_is_ignored():
    b = in_error(MotionBench(nodes=1).ready())
    b.bus.delay(lambda f: f.can_id == 0x181, 3 * MS)             # the drive's state comes late: Busy longer
    fb = b.fb("RST")
    t0 = b.plc.time_ns
    states = run_recording(b, fb, execute_scans=None, retrigger_at=3)
    assert any(s[0] for s in states) and not any(s[2] for s in states)
    assert sum(1 for a, z in zip(states, states[1:]) if z[1] and not a[1]) == 0
    assert ack_edges(b, t0) == 1                                  # one acknowledge


def test_reset_without_an_error_is_done_in_its_execute_scan_without_a_frame():
    """Nothing to acknowledge (FB_LmReset's documented case): Done at once, ErrorCleared 0, no acknowledge."""
    b = MotionBench(nodes=1).ready()
    t0 = b.plc.time_ns
    fb = b.fb("RST")
    fb["EXECUTE"] = True
    b.step(1)
    assert outputs(fb) == (True, False, False, False, 0) and fb["ERRORCLEARED"] == 0
    b.step(5)
    assert fb["DONE"] and ack_edges(b, t0) == 0
    check_reset_on_falling_edge(b, fb)
