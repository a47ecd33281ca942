"""The motion FBs of the one PLCopen suite (tests/st_lib/test_plcopen.py; spec/linmot-motion.md 5): the
Execute-type FBs that end Done (moves, stops, homing, curves, the command table, the raw command, cams selected
and decoupled, I/O, the triggered move and the touch probe, which finish on an edge of X4.6 / X4.5 the drive's
inputs get every few ms) with their inputs, and how a run of them is seen and disturbed on the motion testbench:
a run's frames are its RxPDOs (the motion command, or the control word for homing), or its SDO requests
(MC_WriteParameter, MC_TouchProbe). The motion FBs' own rules (the FBs that run until something ends them,
MC_Jog, MC_Reset) are in tests/st_lib/motion/test_motion_plcopen.py."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from linmot_st.emulator import Curve, build_entry
from linmot_st.protocol import commands as C
from linmot_st.protocol import upids as U
from motionbench import MotionBench

MS = 1_000_000
MOVE = dict(VELOCITY=1000.0, ACCELERATION=10000.0, DECELERATION=10000.0)
RX = (0x201, 0x301, 0x401)


def curves_and_table(b: MotionBench) -> None:
    b.drive.curves.ram[1] = Curve.build(1, [k * k * 100 for k in range(11)], x_length=5000)   # 0 .. 1 mm, 50 ms
    params = C.encode(C.VAI16_INCREMENT_DEM_POS, 0, target=10, vmax=500, acc=100, dec=100)[2:]
    b.drive.ct.ram[5] = build_entry(C.VAI16_INCREMENT_DEM_POS << 4, params)
    b.drive.curves.ram[7] = Curve.build(7, [0, 10_000, 0], x_length=8000, object_type=0x0103, x_dim=0x001B)   # a cam


TRIGGER_DIRECT = {0x170C: 1}                   # the trigger input X4.6's edges as they come ([MC] 7.2.2)
CAM_INPUTS = {U.P_MASTER_ENCODER_SOURCE: 1, U.P_MASTER_ENCODER_COUNTS_PER_REV: 8000}


def trigger_pulses(b: MotionBench) -> None:
    """X4.6 pulses every 60 ms for a minute: an armed triggered move runs on the next one (and, as the drive keeps
    it armed, on every later one: an increment of 2 mm takes 28 ms at 1 m/s, 10 m/s^2)."""
    b.drive.io.pulse_train("X4.6", b.bus.now + 5 * MS, 60 * MS, 5 * MS, 1000)


def moving_with_capture_pulses(b: MotionBench) -> None:
    """The axis crawls at 20 mm/s (MVA2) while X4.5 pulses every 20 ms: each capture lies 0.4 mm further on."""
    b.fb("MVA2").start(POSITION=250.0, VELOCITY=20.0, ACCELERATION=1000.0, DECELERATION=1000.0)
    b.step(20)
    b.drive.io.pulse_train("X4.5", b.bus.now + 5 * MS, 20 * MS, 5 * MS, 3000)


def cam_table_1(b: MotionBench) -> None:
    r = b.fb("CAMSEL").run(CAMTABLE=7, CAM=1, MASTERSTART=0, PERIODIC=True)
    assert r.done, r


@dataclass
class Spec:
    name: str
    inputs: dict
    alt: dict | None = None                    # set while Busy: must change nothing
    bad: dict | None = None                    # invalid: Error before any frame
    frames: tuple = (0x301,)                   # the frames a run sends
    setup: Callable[[MotionBench], None] | None = None       # before power and homing
    ready: Callable[[MotionBench], None] | None = None       # after them
    defaults: dict | None = None               # the drive's parameters at its start
    abortable: bool = True                     # a newer command aborts it (CommandAborted)
    newer: tuple = ("MVA2", dict(POSITION=1.0, **MOVE))   # the newer command
    same_frames: bool = True                   # a run sends the same frames whatever the bus timing


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
    # armed on X4.6 (an increment: each run moves, also where the last one ended), Done in target
    Spec("TRIG", dict(ARM="LM_TRIG_INCREMENT", POSITION=2.0, **MOVE), dict(POSITION=9.0), dict(VELOCITY=0.0),
         defaults=TRIGGER_DIRECT, ready=trigger_pulses),
    # the capture on X4.5 read by SDO until it changes; MC_AbortTrigger ends it; its reads repeat until the capture
    Spec("PROBE", {}, frames=(0x601,), ready=moving_with_capture_pulses, newer=("ABORTTRIG", {}),
         same_frames=False),
]
IDS = [s.name for s in SPECS]


def bench(spec) -> MotionBench:
    b = MotionBench(nodes=1, defaults=spec.defaults)
    if spec.setup:
        spec.setup(b)
    b.ready()
    if spec.ready:
        spec.ready(b)
    return b


def rx_frames(b: MotionBench, t0: int, ids: tuple = RX) -> list[tuple[int, bytes]]:
    return [(e.frame.can_id, bytes(e.frame.data)) for e in b.bus.trace
            if e.frame.can_id in ids and e.start_ns >= t0 and e.status != "error"]


def motion_starts(ids: tuple):
    return lambda b, t0: [e.start_ns for e in b.bus.trace if e.frame.can_id in ids and e.start_ns >= t0]


class MotionFamily:
    """The motion FBs' side of the suite: a run's frames are its `frames` (a command on RxPDO2, ...); the
    drive's count echo (TxPDO1, 0x181) or SDO answer kept late keeps an FB busy; a command the drive never gets
    (RxPDO2 lost) ends it in CommandTimeout."""

    name = "motion"
    specs = SPECS

    bench = staticmethod(bench)

    @staticmethod
    def frames(b: MotionBench, spec: Spec, t0: int) -> list:
        return rx_frames(b, t0, spec.frames)

    @staticmethod
    def frames_of_a_refused_run(b: MotionBench, spec: Spec, t0: int) -> list:
        return rx_frames(b, t0, (0x301, 0x401) + spec.frames)

    @staticmethod
    def keep_busy(b: MotionBench) -> None:
        b.bus.delay(lambda f: f.can_id in (0x181, 0x581), 3 * MS)   # the drive's echo (SDO reply) comes late

    @staticmethod
    def fails(spec: Spec) -> bool:
        return spec.frames == (0x301,)

    @staticmethod
    def make_it_fail(b: MotionBench, spec: Spec) -> dict:
        b["PDO1.COMMANDTIMEOUT"] = 30 * MS
        b.bus.drop(lambda f: f.can_id == 0x301)                      # the drive never gets the command
        return {}

    @staticmethod
    def pulse_options(spec: Spec) -> dict:
        return dict(first_request_scans=2, request_starts=motion_starts(spec.frames))
