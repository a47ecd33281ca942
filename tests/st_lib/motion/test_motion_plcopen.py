"""PLCopen conformance of every Execute-type motion FB (spec/conventions.md, spec/linmot-motion.md 5), with the
checks the configuration FBs get (tests/st_lib/plcopen_checks.py), extended with Active and CommandAborted:
edge latching, exclusive outputs, Done/Error held while Execute stays TRUE, one-scan pulses after Execute fell,
re-trigger while Busy ignored, inputs latched at the rising edge, invalid inputs before any frame, a newer
command aborting the running one. A run's frames are its RxPDOs (the motion command, or the control word for
homing and reset)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import pytest

from motionbench import MotionBench
from plcopen_checks import (assert_exclusive, check_done_held, check_one_scan_pulse,
                            check_reset_on_falling_edge, check_rising_edge_after_the_pulse, check_toggled_execute,
                            outputs, run_recording)

from linmot_st.emulator import Curve, build_entry
from linmot_st.protocol import commands as C

MS = 1_000_000
MOVE = dict(VELOCITY=1000.0, ACCELERATION=10000.0, DECELERATION=10000.0)
RX = (0x201, 0x301, 0x401)


def curves_and_table(b: MotionBench) -> None:
    b.drive.curves.ram[1] = Curve.build(1, [k * k * 100 for k in range(11)], x_length=5000)   # 0 .. 1 mm, 50 ms
    params = C.encode(C.VAI16_INCREMENT_DEM_POS, 0, target=10, vmax=500, acc=100, dec=100)[2:]
    b.drive.ct.ram[5] = build_entry(C.VAI16_INCREMENT_DEM_POS << 4, params)
    b.drive.curves.ram[7] = Curve.build(7, [0, 10_000, 0], x_length=8000, object_type=0x0103, x_dim=0x001B)   # a cam


@dataclass
class Spec:
    name: str
    inputs: dict
    alt: dict | None = None                    # set while Busy: must change nothing
    bad: dict | None = None                    # invalid: Error before any frame
    frames: tuple = (0x301,)                   # the frames a run sends
    setup: Callable[[MotionBench], None] | None = None
    abortable: bool = True                     # a newer command aborts it (CommandAborted)
    newer: tuple = ("MVA2", dict(POSITION=1.0, **MOVE))   # the newer command


SPECS = [
    Spec("MVA", dict(POSITION=3.0, **MOVE), dict(POSITION=9.0), dict(VELOCITY=0.0)),
    Spec("MVR", dict(DISTANCE=2.0, **MOVE), dict(DISTANCE=7.0), dict(ACCELERATION=0.0)),
    Spec("HALT", dict(DECELERATION=5000.0), dict(DECELERATION=100.0), dict(DECELERATION=-1.0)),
    Spec("STOP", dict(DECELERATION=5000.0), dict(DECELERATION=100.0), dict(DECELERATION=0.0), abortable=False),
    Spec("HOME", {}, frames=(0x201,), newer=("HALT", dict(DECELERATION=5000.0))),   # MC_Halt aborts MC_Home
    Spec("CURVE", dict(CURVEID=1), dict(CURVEID=2), dict(CURVEID=101), setup=curves_and_table),
    Spec("CT", dict(ENTRY=5), dict(ENTRY=6), dict(ENTRY=300), setup=curves_and_table),
    Spec("LIVE", dict(UPID=0x13A2, VALUE=20), dict(VALUE=30), dict(UPID=0x5000)),
    # issue 22
    Spec("MVADD", dict(DISTANCE=2.0, **MOVE), dict(DISTANCE=7.0), dict(DECELERATION=0.0)),
    Spec("SETPOS", dict(POSITION=12.5), dict(POSITION=20.0), dict(POSITION=1.0e6)),
    Spec("CMD", dict(CID=0x090, A=40, B=1000, C=100, D=100), dict(A=90),
         dict(CID=next(c for c in range(0x0F0, 0x1000) if c not in C.COMMANDS))),     # an ID no row has
    Spec("CAMSEL", dict(CAMTABLE=7, CAM=1), dict(CAMTABLE=8), dict(CAMTABLE=101), setup=curves_and_table),
    Spec("CAMOUT", {}, abortable=False),
    Spec("WDO", dict(CONNECTOR="LM_IO_X4", OUTPUTNUMBER=1, VALUE=True), dict(OUTPUTNUMBER=2),
         dict(OUTPUTNUMBER=20)),
    Spec("ABORTTRIG", {}),
    Spec("WPAR", dict(UPID=0x14B0, VALUE=20000), dict(VALUE=30000), dict(UPID=0x5000), frames=(0x601,),
         abortable=False),
]
IDS = [s.name for s in SPECS]


def bench(spec: Spec) -> MotionBench:
    b = MotionBench(nodes=1)
    if spec.setup:
        spec.setup(b)
    return b.ready()


def rx_frames(b: MotionBench, t0: int, ids: tuple = RX) -> list[tuple[int, bytes]]:
    return [(e.frame.can_id, bytes(e.frame.data)) for e in b.bus.trace
            if e.frame.can_id in ids and e.start_ns >= t0 and e.status != "error"]


def motion_starts(ids: tuple):
    return lambda b, t0: [e.start_ns for e in b.bus.trace if e.frame.can_id in ids and e.start_ns >= t0]


def active_only_while_busy(b: MotionBench, fb) -> None:
    try:
        active = fb["ACTIVE"]
    except Exception:
        return
    assert not active or fb["BUSY"]


@pytest.mark.parametrize("spec", SPECS, ids=IDS)
def test_done_held_while_execute_then_reset_on_falling_edge(spec):
    b = bench(spec)
    fb = b.fb(spec.name)
    fb.set(**spec.inputs)
    check_done_held(b, fb)
    active_only_while_busy(b, fb)
    check_reset_on_falling_edge(b, fb)


@pytest.mark.parametrize("spec", SPECS, ids=IDS)
def test_done_is_a_one_scan_pulse_when_execute_fell_before(spec):
    b = bench(spec)
    fb = b.fb(spec.name)
    fb.set(**spec.inputs)
    check_one_scan_pulse(b, fb, 0)


@pytest.mark.parametrize("spec", SPECS, ids=IDS)
def test_retrigger_while_busy_is_ignored_and_inputs_are_latched(spec):
    ref = bench(spec)
    t0 = ref.plc.time_ns
    assert ref.fb(spec.name).run(**spec.inputs).done
    reference = rx_frames(ref, t0, spec.frames)

    b = bench(spec)
    b.bus.delay(lambda f: f.can_id in (0x181, 0x581), 3 * MS)   # the drive's echo (SDO reply) comes late
    fb = b.fb(spec.name)
    fb.set(**spec.inputs)
    t0 = b.plc.time_ns
    states = run_recording(b, fb, execute_scans=None, retrigger_at=3, alt_at=spec.alt)
    assert any(s[0] for s in states) and not any(s[2] for s in states)
    b.step(20)
    assert rx_frames(b, t0, spec.frames) == reference            # one run, with the inputs of the first edge


@pytest.mark.parametrize("spec", [s for s in SPECS if s.bad], ids=[s.name for s in SPECS if s.bad])
def test_invalid_input_error_held_then_reset(spec):
    b = bench(spec)
    fb = b.fb(spec.name)
    fb.set(**{**spec.inputs, **spec.bad})
    t0 = b.plc.time_ns
    states = run_recording(b, fb, execute_scans=None)
    assert states[0][2] and states[0][4] != 0 and all(s[2] for s in states)
    assert rx_frames(b, t0, (0x301, 0x401) + spec.frames) == []
    check_reset_on_falling_edge(b, fb)


@pytest.mark.parametrize("spec", [s for s in SPECS if s.frames == (0x301,)],
                         ids=[s.name for s in SPECS if s.frames == (0x301,)])
def test_error_is_a_one_scan_pulse_when_execute_fell_before(spec):
    b = bench(spec)
    b["PDO1.COMMANDTIMEOUT"] = 30 * MS
    b.bus.drop(lambda f: f.can_id == 0x301)                      # the drive never gets the command
    fb = b.fb(spec.name)
    fb.set(**spec.inputs)
    check_one_scan_pulse(b, fb, 2)


@pytest.mark.parametrize("spec", [s for s in SPECS if s.abortable], ids=[s.name for s in SPECS if s.abortable])
def test_a_newer_command_aborts_it(spec):
    b = bench(spec)
    b.bus.delay(lambda f: f.can_id == 0x181, 5 * MS)             # keep it busy
    fb = b.fb(spec.name)
    fb.start(**spec.inputs)
    b.step(2)
    assert fb["BUSY"]
    newer = b.fb(spec.newer[0])
    newer.start(**spec.newer[1])
    b.sim.run_until(lambda: fb["COMMANDABORTED"] or fb["DONE"] or fb["ERROR"], max_scans=200)
    s = outputs(fb)
    assert_exclusive(s)
    assert s[3] and not s[1], s
    b.step(3)
    assert fb["COMMANDABORTED"]                                  # held while Execute stays TRUE
    check_reset_on_falling_edge(b, fb)
    b.sim.run_until(lambda: newer["DONE"], max_scans=1000)       # the newer one runs to its end


@pytest.mark.parametrize("spec", SPECS, ids=IDS)
def test_execute_rising_in_the_scan_after_the_pulse_starts_a_new_run(spec):
    b = bench(spec)
    fb = b.fb(spec.name)
    fb.set(**spec.inputs)
    check_rising_edge_after_the_pulse(b, fb, first_request_scans=2, request_starts=motion_starts(spec.frames))


@pytest.mark.parametrize("spec", SPECS, ids=IDS)
def test_execute_toggled_every_scan_gives_one_run_per_edge_after_completion(spec):
    b = bench(spec)
    fb = b.fb(spec.name)
    fb.set(**spec.inputs)
    check_toggled_execute(b, fb, first_request_scans=2, request_starts=motion_starts(spec.frames))
