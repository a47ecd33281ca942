"""The PLCopen FBs of issue 22 against the moving emulated E1100 (tests/st_lib/motion_testbench.st): MC_MoveAdditive
(increment the target position), MC_Jog (control-word jog bits, states 16/17), MC_SetPosition (master homing),
FB_LmMotionCommand (any catalogue command, raw), MC_ReadParameter / MC_WriteParameter and MC_ReadActualVelocity
(parameter services), each checked on the drive's trajectory record or its parameters, and their refusals
before any frame."""

from __future__ import annotations

import struct

import pytest

from motionbench import MM, MotionBench

from linmot_st.protocol import commands as C
from linmot_st.protocol.errors import BY_NAME

E = {name: e.value for name, e in BY_NAME.items()}
MS = 1_000_000
MOVE = dict(VELOCITY=1000.0, ACCELERATION=10000.0, DECELERATION=10000.0)    # 1 m/s, 10 m/s^2


def bench() -> MotionBench:
    return MotionBench(nodes=1).ready()


def heads(b: MotionBench, t0: int) -> list[int]:
    return [struct.unpack_from("<H", f)[0] >> 4 for f in b.payloads(0x301, t0)]


def no_motion_frames(b: MotionBench, t0: int) -> bool:
    return b.payloads(0x301, t0) == [] and b.payloads(0x401, t0) == []


# ---------------------------------------------------------------- MC_MoveAdditive
def test_move_additive_adds_to_the_target_of_the_interrupted_move():
    """MC_MoveAdditive during a move to 60 mm by +10 mm ends at 70 mm (092xh: the last target plus the
    distance); MC_MoveRelative would add to the demand position at that moment."""
    b = bench()
    t0 = b.plc.time_ns
    b.fb("MVA").start(POSITION=60.0, VELOCITY=200.0, ACCELERATION=10000.0, DECELERATION=10000.0)
    b.step(30)
    assert b["MVA.ACTIVE"]
    mid = b.drive.mc.dem_p
    r = b.fb("MVADD").run(DISTANCE=10.0, VELOCITY=200.0, ACCELERATION=10000.0, DECELERATION=10000.0)
    assert r.done, r
    assert b["MVA.COMMANDABORTED"]
    assert abs(b.drive.mc.axis.position - 70 * MM) <= 1000 and abs(b["RP.POSITION"] - 70.0) <= 0.1
    assert mid + 10 * MM < 60 * MM                   # a relative move would have ended short of 60 mm
    assert heads(b, t0) == [0x090, 0x092]


def test_move_additive_with_32_bit_values_goes_as_predefined_vai():
    b = bench()
    start = b.drive.mc.dem_p
    t0 = b.plc.time_ns
    r = b.fb("MVADD").run(DISTANCE=12.3456, VELOCITY=333.3, ACCELERATION=7777.0, DECELERATION=6666.0)
    assert r.done, r
    assert heads(b, t0) == [0x002, 0x002, 0x002, 0x022]
    assert abs(b.drive.mc.dem_p - (start + 123456)) < 1


def test_move_additive_invalid_input_before_any_frame():
    b = bench()
    t0 = b.plc.time_ns
    r = b.fb("MVADD").run(DISTANCE=5.0, VELOCITY=-1.0, ACCELERATION=1.0, DECELERATION=1.0, max_scans=5)
    assert r.error and r.error_id == E["InvalidVelocity"] and no_motion_frames(b, t0)


# ---------------------------------------------------------------- MC_Jog
def jog(b: MotionBench, **inputs) -> None:
    base = dict(VELOCITY=100.0, ACCELERATION=1000.0, DECELERATION=1000.0, INCREMENT=0.0,
                JOGFORWARD=False, JOGBACKWARD=False)
    for k, v in {**base, **inputs}.items():
        b[f"JOG.{k}"] = v


def test_jog_forward_while_held_then_stops_when_released():
    b = bench()
    start = b.drive.mc.axis.position
    t0 = b.plc.time_ns
    jog(b, JOGFORWARD=True)
    b.sim.run_until(lambda: b["JOG.ACTIVE"], max_scans=200)
    assert b["JOG.BUSY"] and b["RSTAT.STATEVAR"] >> 8 == 16
    b.step(300)                                       # 0.3 s held
    assert b.drive.mc.params[0x14B0].ram == 100_000                   # 100 mm/s written first
    samples = b.drive.mc.trajectory.between(t0)
    assert max(abs(s.demand_velocity) for s in samples) / MM == pytest.approx(100.0, rel=0.01)
    jog(b, JOGFORWARD=False)
    b.sim.run_until(lambda: b["JOG.DONE"] or b["JOG.ERROR"], max_scans=500)
    assert b["JOG.DONE"] and not b["JOG.BUSY"]
    moved = (b.drive.mc.axis.position - start) / MM
    # 0.3 s at 100 mm/s plus the ramps: about 30 mm, the ramps 5 mm each way
    assert 25.0 < moved < 45.0, moved
    assert b["RSTAT.STATEVAR"] >> 8 == 8 and b["RSTAT.STANDSTILL"]
    assert heads(b, t0) == [0x002, 0x002, 0x002, 0x002]
    assert b.payloads(0x201, t0)[0][1] & 0x01                           # control word bit 8


def test_jog_backward_by_an_increment():
    b = bench()
    b.fb("MVA").run(POSITION=60.0, **MOVE)
    jog(b, JOGBACKWARD=True, INCREMENT=5.0)
    b.sim.run_until(lambda: b["JOG.ACTIVE"], max_scans=200)
    assert b["RSTAT.STATEVAR"] >> 8 == 17
    b.step(400)                                       # the increment is done long before: the drive holds
    assert abs(b.drive.mc.axis.position - 55 * MM) <= 1000
    jog(b, JOGBACKWARD=False)
    b.sim.run_until(lambda: b["JOG.DONE"], max_scans=500)
    assert abs(b["RP.POSITION"] - 55.0) <= 0.1


def test_jog_both_directions_or_bad_velocity_refused_before_any_frame():
    b = bench()
    t0 = b.plc.time_ns
    jog(b, JOGFORWARD=True, JOGBACKWARD=True)
    b.step(3)
    assert b["JOG.ERROR"] and b["JOG.ERRORID"] == E["JogDirection"]
    jog(b)
    b.step(2)
    assert not b["JOG.ERROR"]
    jog(b, JOGFORWARD=True, VELOCITY=0.0)
    b.step(3)
    assert b["JOG.ERROR"] and b["JOG.ERRORID"] == E["InvalidVelocity"]
    assert no_motion_frames(b, t0) and all(p[1] & 0x03 == 0 for p in b.payloads(0x201, t0))


def test_halt_aborts_a_jog():
    b = bench()
    jog(b, JOGFORWARD=True)
    b.sim.run_until(lambda: b["JOG.ACTIVE"], max_scans=200)
    b.step(100)
    r = b.fb("HALT").run(DECELERATION=5000.0)
    assert r.done, r
    assert b["JOG.COMMANDABORTED"] and not b["JOG.BUSY"] and b["RSTAT.STATEVAR"] >> 8 == 8
    v = b.drive.mc.trajectory.samples[-1].demand_velocity
    assert v == 0


# ---------------------------------------------------------------- MC_SetPosition
def test_set_position_absolute_and_relative():
    b = bench()
    at = b.drive.mc.axis.position
    t0 = b.plc.time_ns
    r = b.fb("SETPOS").run(POSITION=100.0)
    assert r.done, r
    assert heads(b, t0) == [0x009] and b.payloads(0x301, t0)[0][2:6] == struct.pack("<i", 100 * MM)
    b.step(5)
    assert abs(b["RP.POSITION"] - 100.0) <= 0.1 and abs(b.drive.mc.axis.position - 100 * MM) <= 10
    assert b.drive.mc.params[0x13C7].ram == 100 * MM
    assert abs(b.drive.mc.axis.position - at - (100 * MM - at)) <= 10          # no motion: only the frame moved
    r = b.fb("SETPOS").run(POSITION=-5.0, RELATIVE=True)
    assert r.done, r
    b.step(5)
    assert abs(b["RP.POSITION"] - 95.0) <= 0.15
    r = b.fb("MVA").run(POSITION=90.0, **MOVE)                          # the new frame moves
    assert r.done and abs(b.drive.mc.axis.position - 90 * MM) <= 1000


def test_set_position_refusals_before_any_frame():
    b = MotionBench(nodes=1)
    t0 = b.plc.time_ns
    r = b.fb("SETPOS").run(POSITION=1.0, max_scans=5)
    assert r.error and r.error_id == E["AxisNotEnabled"] and no_motion_frames(b, t0)
    b.power()
    r = b.fb("SETPOS").run(POSITION=3e5, max_scans=5)
    assert r.error and r.error_id == E["PositionRange"] and no_motion_frames(b, t0)


# ---------------------------------------------------------------- FB_LmMotionCommand
def test_raw_command_moves_as_the_catalogue_says():
    b = bench()
    t0 = b.plc.time_ns
    # 090xh: 40 mm (0.1 mm units), 1 m/s, 1 m/s^2 (16-bit interface scaling)
    r = b.fb("CMD").run(CID=0x090, A=400, B=1000, C=100, D=100, WAITINTARGET=True)
    assert r.done, r
    assert heads(b, t0) == [0x090] and b.payloads(0x301, t0)[0][2:] == struct.pack("<hHH", 400, 1000, 100)
    assert abs(b.drive.mc.axis.position - 40 * MM) <= 1000


def test_raw_command_without_follow_is_done_when_taken():
    b = bench()
    r = b.fb("CMD").run(CID=0x002, A=0x14B0, B=123_000, FOLLOW=False)
    assert r.done, r
    assert b.drive.mc.params[0x14B0].ram == 123_000


def test_raw_command_refused_by_the_drive_reports_its_error():
    b = bench()
    r = b.fb("CMD").run(CID=0x040, A=77)                      # curve 77 is not in the drive's curve RAM
    assert r.error and r.error_id == E["DriveError"] and r["DRIVEERROR"] == 0x0062


def test_raw_command_unknown_or_not_mapped_refused_before_any_frame():
    b = bench()
    t0 = b.plc.time_ns
    unknown = next(c for c in range(0x0F0, 0x1000) if c not in C.COMMANDS)
    r = b.fb("CMD").run(CID=unknown, max_scans=5)
    assert r.error and r.error_id == E["UnknownCommand"]
    r = b.fb("CMD").run(CID=0x1234, max_scans=5)
    assert r.error and r.error_id == E["UnknownCommand"]
    r = b.fb("CMD").run(CID=0x010, A=10, B=10, C=10, D=10, max_scans=5)   # 16 bytes: no RxPDO carries them
    assert r.error and r.error_id == E["CommandNotMapped"]
    assert no_motion_frames(b, t0)


# ---------------------------------------------------------------- parameters and velocity
def test_write_then_read_parameter():
    b = MotionBench(nodes=1)
    r = b.fb("WPAR").run(UPID=0x14B0, VALUE=250_000)
    assert r.done, r
    assert b.drive.mc.params[0x14B0].ram == 250_000
    b["RPAR.UPID"] = 0x14B0
    b["RPAR.ENABLE"] = True
    b.sim.run_until(lambda: b["RPAR.VALID"] or b["RPAR.ERROR"], max_scans=200)
    assert b["RPAR.VALID"] and b["RPAR.VALUE"] == 250_000 and not b["RPAR.BUSY"]
    n = len(b.sdo_trace())
    b.step(20)
    assert len(b.sdo_trace()) == n                              # once per Enable
    b["RPAR.ENABLE"] = False
    b.step(1)
    assert not b["RPAR.VALID"]
    b["RPAR.UPID"] = 0x5000
    b["RPAR.ENABLE"] = True
    b.step(3)
    assert b["RPAR.ERROR"] and b["RPAR.ERRORID"] == E["InvalidUpid"]


def test_read_parameter_cyclic_follows_the_drive():
    b = MotionBench(nodes=1)
    b["RPAR.UPID"] = 0x14B0
    b["RPAR.CYCLIC"] = True
    b["RPAR.ENABLE"] = True
    b.sim.run_until(lambda: b["RPAR.VALID"], max_scans=200)
    b.drive.mc.params[0x14B0].ram = 4242
    b.sim.run_until(lambda: b["RPAR.VALUE"] == 4242, max_scans=200)
    assert b["RPAR.BUSY"] and b["RPAR.VALID"]


def test_read_actual_velocity_during_a_move():
    b = bench()
    b["RV.ENABLE"] = True
    b.sim.run_until(lambda: b["RV.VALID"], max_scans=200)
    assert abs(b["RV.VELOCITY"]) < 1.0 and b["RV.DEMANDVELOCITY"] == 0.0
    b.fb("MVA").start(POSITION=200.0, VELOCITY=300.0, ACCELERATION=10000.0, DECELERATION=10000.0)
    b.step(200)                                                # cruising at 300 mm/s
    assert b["RV.DEMANDVELOCITY"] == pytest.approx(300.0, abs=0.01)
    assert b["RV.VELOCITY"] == pytest.approx(300.0, abs=15.0)


# ---------------------------------------------------------------- MC_MoveVelocity
HAS_INFINITE = 0x02E in C.COMMANDS and 0x02F in C.COMMANDS
needs_infinite = pytest.mark.skipif(not HAS_INFINITE, reason="the catalogue has no 02Exh/02Fxh yet (branch vai20)")


def mvv(b: MotionBench, **inputs):
    f = b.fb("MVV")
    f.start(**{**dict(VELOCITY=100.0, ACCELERATION=1000.0, DECELERATION=1000.0, DIRECTION="LM_DIR_POSITIVE"),
               **inputs})
    return f


def test_move_velocity_invalid_inputs_before_any_frame():
    b = bench()
    t0 = b.plc.time_ns
    f = mvv(b, VELOCITY=0.0)
    b.step(2)
    assert f["ERROR"] and f["ERRORID"] == E["InvalidVelocity"] and not f["BUSY"]
    b["MVV.EXECUTE"] = False
    b.step(2)
    f = mvv(b, DECELERATION=-5.0)
    b.step(2)
    assert f["ERROR"] and f["ERRORID"] == E["InvalidDeceleration"]
    assert no_motion_frames(b, t0)


@pytest.mark.skipif(HAS_INFINITE, reason="the catalogue has 02Exh/02Fxh")
def test_move_velocity_without_the_infinite_motion_rows_is_refused_before_any_frame():
    b = bench()
    t0 = b.plc.time_ns
    f = mvv(b)
    b.step(2)
    assert f["ERROR"] and f["ERRORID"] == E["UnknownCommand"] and no_motion_frames(b, t0)


@needs_infinite
@pytest.mark.parametrize("direction, sign, cid", [("LM_DIR_POSITIVE", 1, 0x02E), ("LM_DIR_NEGATIVE", -1, 0x02F)])
def test_move_velocity_reaches_the_velocity_and_halt_aborts_it(direction, sign, cid):
    b = bench()
    b.fb("MVA").run(POSITION=150.0, **MOVE)
    t0 = b.plc.time_ns
    f = mvv(b, VELOCITY=100.0, DIRECTION=direction)
    b.sim.run_until(lambda: f["INVELOCITY"] or f["ERROR"], max_scans=1000)
    assert f["INVELOCITY"] and f["BUSY"] and f["ACTIVE"], (f["ERRORID"], f["DRIVEERROR"])
    assert heads(b, t0) == [0x002, 0x002, 0x002, cid]
    s = b.drive.mc.trajectory.samples[-1]
    assert s.demand_velocity / MM == pytest.approx(sign * 100.0, abs=0.01)
    b.step(100)
    assert f["INVELOCITY"] and not f["ERROR"]
    r = b.fb("HALT").run(DECELERATION=5000.0)
    assert r.done and f["COMMANDABORTED"] and not f["INVELOCITY"] and not f["BUSY"]


@needs_infinite
def test_move_velocity_current_direction_follows_the_running_motion():
    b = bench()
    b.fb("MVA").run(POSITION=200.0, **MOVE)
    b.fb("MVA").start(POSITION=20.0, VELOCITY=300.0, ACCELERATION=5000.0, DECELERATION=5000.0)
    b.step(100)                                                  # moving in the negative direction
    t0 = b.plc.time_ns
    f = mvv(b, VELOCITY=50.0, DIRECTION="LM_DIR_CURRENT")
    b.sim.run_until(lambda: f["INVELOCITY"] or f["ERROR"], max_scans=1000)
    assert f["INVELOCITY"], (f["ERRORID"], f["DRIVEERROR"])
    assert heads(b, t0)[-1] == 0x02F
    assert b.drive.mc.trajectory.samples[-1].demand_velocity / MM == pytest.approx(-50.0, abs=0.01)


# ---------------------------------------------------------------- every VAI variant: VAI Dec=Acc
HAS_DEC_ACC = all(c in C.COMMANDS for c in (0x0C0, 0x0C1, 0x0C2))
needs_dec_acc = pytest.mark.skipif(not HAS_DEC_ACC, reason="the catalogue has no VAI Dec=Acc rows yet (branch vai20)")


def bench12() -> MotionBench:
    """RxPDO3 maps par bytes 6..11: 12-byte commands fit."""
    return MotionBench(nodes=1, defaults={0x2041: 2}, pdo={"RX3BYTES": 8}).ready()


@needs_dec_acc
@pytest.mark.parametrize("fb, inputs, cid, end_mm", [
    ("MVA", dict(POSITION=123.4567), 0x0C0, 123.4567),
    ("MVR", dict(DISTANCE=-5.4321), 0x0C1, 50.0 - 5.4321),
    ("MVADD", dict(DISTANCE=7.0001), 0x0C2, 57.0001),
])
def test_32_bit_moves_with_acc_equal_dec_go_as_one_dec_acc_command(fb, inputs, cid, end_mm):
    b = bench12()
    assert b.fb("MVA").run(POSITION=50.0, **MOVE).done
    t0 = b.plc.time_ns
    r = b.fb(fb).run(**inputs, VELOCITY=333.3, ACCELERATION=7777.0, DECELERATION=7777.0)
    assert r.done, r
    assert heads(b, t0) == [cid]
    frame = b.payloads(0x301, t0)[0] + b.payloads(0x401, t0)[0][2:]
    assert struct.unpack_from("<iII", frame, 2)[1:] == (333_300, 777_700)
    assert abs(b.drive.mc.dem_p - end_mm * MM) < 1


@needs_dec_acc
def test_dec_acc_forced_refusals_and_the_default_pdos():
    b = bench()                                   # the default mapping: 8 parameter bytes
    t0 = b.plc.time_ns
    r = b.fb("MVA").run(POSITION=12.34567, VELOCITY=333.3, ACCELERATION=7777.0, DECELERATION=7777.0)
    assert r.done and heads(b, t0) == [0x002, 0x002, 0x002, 0x020]          # AUTO: predefined VAI
    r = b.fb("MVA").run(POSITION=20.0, VELOCITY=333.3, ACCELERATION=7777.0, DECELERATION=7777.0,
                        COMMAND="LM_VAI_DEC_ACC", max_scans=5)
    assert r.error and r.error_id == E["CommandNotMapped"]
    b = bench12()
    t0 = b.plc.time_ns
    r = b.fb("MVA").run(POSITION=20.0, VELOCITY=333.3, ACCELERATION=7777.0, DECELERATION=6666.0,
                        COMMAND="LM_VAI_DEC_ACC", max_scans=5)
    assert r.error and r.error_id == E["InvalidDeceleration"] and no_motion_frames(b, t0)
    r = b.fb("MVA").run(POSITION=20.0, **MOVE, COMMAND="LM_VAI_DEC_ACC")   # 16-bit-exact, forced 0C0xh
    assert r.done and heads(b, t0) == [0x0C0]


# ---------------------------------------------------------------- BufferMode Buffered: After Actual Command
HAS_AFTER = all(c in C.COMMANDS for c in (0x098, 0x028))
needs_after = pytest.mark.skipif(not HAS_AFTER, reason="the catalogue has no After Actual Command rows yet (vai20)")


@needs_after
@pytest.mark.parametrize("position, cid", [(30.0, 0x098), (30.0005, 0x028)])
def test_buffered_move_runs_after_the_running_one_which_ends_done(position, cid):
    b = bench()
    t0 = b.plc.time_ns
    first = b.fb("MVA")
    first.start(POSITION=120.0, VELOCITY=500.0, ACCELERATION=10000.0, DECELERATION=10000.0)
    b.step(30)
    assert first["ACTIVE"]
    second = b.fb("MVA2")
    second.start(POSITION=position, VELOCITY=500.0, ACCELERATION=10000.0, DECELERATION=10000.0,
                 BUFFERMODE="LM_BUFFER_BUFFERED")
    b.step(30)
    assert first["BUSY"] and first["ACTIVE"] and not first["COMMANDABORTED"]
    assert second["BUSY"] and not second["ACTIVE"]                    # queued on the drive
    b.sim.run_until(lambda: first["DONE"] or first["ERROR"] or first["COMMANDABORTED"], max_scans=2000)
    assert first["DONE"], (first["ERRORID"], first["COMMANDABORTED"])
    reached = b.drive.mc.trajectory.between(t0)
    assert max(s.demand for s in reached) == pytest.approx(120 * MM, abs=1)   # the first reached its target
    b.sim.run_until(lambda: second["DONE"] or second["ERROR"], max_scans=2000)
    assert second["DONE"] and abs(b.drive.mc.axis.position - position * MM) <= 1000
    assert heads(b, t0)[-1] == cid


@needs_after
def test_an_aborting_move_aborts_both_the_running_and_the_buffered_one():
    b = bench()
    first = b.fb("MVA")
    first.start(POSITION=120.0, VELOCITY=500.0, ACCELERATION=10000.0, DECELERATION=10000.0)
    b.step(30)
    second = b.fb("MVA2")
    second.start(POSITION=30.0, VELOCITY=500.0, ACCELERATION=10000.0, DECELERATION=10000.0,
                 BUFFERMODE="LM_BUFFER_BUFFERED")
    b.step(30)
    r = b.fb("HALT").run(DECELERATION=10000.0)
    assert r.done
    assert first["COMMANDABORTED"] and second["COMMANDABORTED"]


@pytest.mark.skipif(HAS_AFTER, reason="the catalogue has the After Actual Command rows")
def test_buffered_without_the_rows_refused_before_any_frame():
    b = bench()
    t0 = b.plc.time_ns
    r = b.fb("MVA").run(POSITION=30.0, **MOVE, BUFFERMODE="LM_BUFFER_BUFFERED", max_scans=5)
    assert r.error and r.error_id == E["UnknownCommand"] and no_motion_frames(b, t0)
