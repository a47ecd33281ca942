"""The motion FBs of st_lib against the moving emulated E1100 (tests/st_lib/motion_testbench.st): power from
every start state, homing, moves checked against the drive's trajectory, aborts, halt, stop with lock-out,
reset, curves, the command table, the readers, invalid inputs before any frame, and faults (lost RxPDOs,
lost TxPDOs, a drive reset mid-move, errors during a move), each reported with the drive's logged error code
and nothing claimed done that the drive did not do. Then the PLCopen FBs of issue 22, each on the drive's
trajectory record or its parameters: MC_MoveAdditive, MC_Jog, MC_SetPosition, FB_LmMotionCommand,
MC_ReadParameter / MC_WriteParameter, MC_ReadActualVelocity, MC_MoveVelocity, the VAI Dec=Acc moves and
BufferMode Buffered. The PLCopen rules every Execute-type FB keeps: tests/st_lib/test_plcopen.py."""

from __future__ import annotations

import json
import struct

import pytest

from linmot_st.bus import Frame
from linmot_st.emulator import Curve, build_entry
from linmot_st.protocol import commands as C
from linmot_st.protocol.errors import BY_NAME
from linmot_st.pvl import load_pvl
from motionbench import MM, MotionBench
from repo_paths import EXAMPLES
from stbench import VECTORS

E = {name: e.value for name, e in BY_NAME.items()}
MS = 1_000_000
PVL = EXAMPLES / "two_axes.pvl"
MOVE = dict(VELOCITY=1000.0, ACCELERATION=10000.0, DECELERATION=10000.0)    # 1 m/s, 10 m/s^2


@pytest.fixture
def b():
    return MotionBench().ready()


def state(b: MotionBench) -> int:
    return b["MO1.STATEVAR"] >> 8


# ---------------------------------------------------------------- the motion command encoder: shared vectors
def test_encoder_against_the_shared_vectors():
    b = MotionBench(nodes=1)
    vectors = json.loads((VECTORS / "motion_commands.json").read_text())["vectors"]
    for v in vectors:
        fields = list(v["fields"].values()) + [0, 0, 0, 0, 0]
        for name, value in zip(("ENCA", "ENCB", "ENCC", "ENCD", "ENCE"), fields[:5]):
            b[name] = value
        b["ENCCID"] = int(v["cid"], 16)
        b["ENCCOUNT"] = v["count"]
        b["ENC"] = True
        b.step(1)
        image = bytes.fromhex(v["image"])
        assert b["ENCLEN"] == len(image) - 2, v["name"]
        assert bytes(b["ENCIMG"])[:len(image)] == image, v["name"]


# ---------------------------------------------------------------- the CANopen manual's example, by the FBs
def test_frames_of_the_canopen_manual_example():
    b = MotionBench(nodes=1)
    b.power()
    t0 = b.plc.time_ns
    b.home()
    cws = b.payloads(0x201, t0)
    assert cws[:2] == [bytes.fromhex("3F08"), bytes.fromhex("3F00")]        # 083Fh, then 003Fh
    t0 = b.plc.time_ns
    r = b.fb("MVA").run(POSITION=50.0, **MOVE)
    assert r.done, r
    assert b.payloads(0x301, t0) == [bytes.fromhex("0109F401E8036400")]
    assert b.payloads(0x401, t0) == [bytes.fromhex("01096400")]
    assert abs(b.drive.mc.axis.position - 50 * MM) <= 1000                 # in the target window
    # Done came after the drive's motion: no earlier than the 141 ms triangle
    assert r.scans >= 141


# ---------------------------------------------------------------- power
def raw_sender(b: MotionBench):
    ep = b.bus.endpoint("tester")
    return lambda can_id, data: ep.send(Frame(can_id, bytes.fromhex(data)), b.bus.now)


@pytest.mark.parametrize("start, setup", [
    (1, [("0000", 2)]), (2, []), (5, [("3F00", 2)]), (6, [("3700", 13)]), (8, [("3F00", 13)]),
    (12, [("3F00", 13), ("2F00", 2)]),
])
def test_power_walks_to_operation_enabled_from(start, setup):
    """The tester puts the drive into the start state with its own RxPDO1; FB_LmPower is enabled before
    FB_LmPdo's lost-frame check (ResendTime 20 ms) would put its own control word back."""
    b = MotionBench(nodes=1)
    send = raw_sender(b)
    for word, scans in setup:
        send(0x201, word)
        b.step(scans)
    assert state(b) == start, hex(b["MO1.STATEVAR"])
    b["PW.ENABLE"] = True
    b.step(3)
    b.sim.run_until(lambda: b["PW.STATUS"] and state(b) == 8, max_scans=2000)
    assert b["PW.VALID"] and not b["PW.ERROR"] and not b["PW.BUSY"]
    b["PW.ENABLE"] = False
    b.step(5)
    assert state(b) == 2 and not b["PW.STATUS"]                               # and back: power stage off


def test_power_from_state_0_after_an_error_and_reset():
    b = MotionBench(nodes=1)
    b.power()
    send = raw_sender(b)
    raw = C.encode(0x0FF, 7)
    send(0x301, raw.ljust(8, b"\0").hex())
    send(0x401, raw.hex() + "0000")
    b.step(5)
    assert state(b) == 4 and b["PW.ERROR"] and b["PW.ERRORID"] == E["DriveError"]
    assert b["PW.DRIVEERROR"] == 0x0081 and not b["PW.STATUS"]
    r = b.fb("RST").run()
    assert r.done and r["ERRORCLEARED"] == 0x0081
    b.sim.run_until(lambda: b["PW.STATUS"], max_scans=2000)                 # 0 -> 1 -> 2 -> 5 -> 6 -> 8
    states = [s.state for s in b.drive.mc.trajectory.samples]
    walk = [x for i, x in enumerate(states) if i == 0 or x != states[i - 1]]
    assert walk[walk.index(4):] == [4, 0, 2, 5, 8]          # 1 and 6 passed within one event each (003Eh, 003Fh)


def test_power_reports_a_fatal_error_and_reset_refuses_it():
    b = MotionBench(nodes=1).ready()
    b.drive.inject_error(0x000D, b.bus.now)
    b.step(3)
    assert b["PW.ERROR"] and b["PW.ERRORID"] == E["FatalError"] and b["PW.DRIVEERROR"] == 0x000D
    r = b.fb("RST").run()
    assert r.error and r.error_id == E["FatalError"]
    assert state(b) == 4


def test_power_quick_stop_abort_freeze_inputs(b):
    b["PW.ABORT"] = True
    b.step(3)
    assert state(b) == 12 and b["RSTAT.STOPPING"]
    b["PW.ABORT"] = False
    b.step(3)
    assert state(b) == 8
    b["PW.QUICKSTOP"] = True
    b.step(5)
    assert state(b) == 1
    b["PW.QUICKSTOP"] = False
    b.sim.run_until(lambda: b["PW.STATUS"], max_scans=2000)


# ---------------------------------------------------------------- home
def test_home_on_the_mechanical_stop():
    b = MotionBench(nodes=1, defaults={0x1500: 3})                          # mech stop negative search
    b.power()
    t0 = b.plc.time_ns
    h = b.fb("HOME")
    h.start()
    b.step(10)
    assert h["ACTIVE"] and h["BUSY"] and b["RSTAT.HOMING"]
    b.sim.run_until(lambda: h["DONE"] or h["ERROR"], max_scans=10_000)
    assert h["DONE"] and b.drive.mc.homed and state(b) == 8
    assert b["RSTAT.HOMED"] and abs(b["RP.POSITION"] - 10.0) <= 0.1       # at the initial position
    assert b.payloads(0x201, t0)[0] == bytes.fromhex("3F08")


def test_home_aborted_by_a_move_reports_command_aborted():
    b = MotionBench(nodes=1, defaults={0x1500: 3})
    b.power()
    h = b.fb("HOME")
    h.start()
    b.step(20)
    assert h["ACTIVE"]
    m = b.fb("MVA").run(POSITION=10.0, **MOVE, max_scans=5)
    assert m.error and m.error_id == E["AxisBusy"]                           # homing: no motion command
    assert h["BUSY"]


# ---------------------------------------------------------------- moves
def trajectory_end(b: MotionBench, t0: int) -> float:
    return b.drive.mc.trajectory.between(t0)[-1].actual


def test_absolute_and_relative_moves_follow_the_drive(b):
    t0 = b.plc.time_ns
    r = b.fb("MVA").run(POSITION=80.0, VELOCITY=500.0, ACCELERATION=5000.0, DECELERATION=2500.0)
    assert r.done and not r.error
    samples = b.drive.mc.trajectory.between(t0)
    active = [s for s in samples if s.status_word & 0x2000]
    # 80 mm at 0.5 m/s, 5 m/s^2 up, 2.5 m/s^2 down: 0.16 + 0.1/2 + 0.2/2 = 0.31 s of setpoint generation
    assert abs((active[-1].t_ns - active[0].t_ns) / 1e9 - (0.08 / 0.5 + 0.5 / 10 + 0.5 / 5)) <= 0.002
    assert abs(b.drive.mc.axis.position - 80 * MM) <= 1000 and abs(b["RP.POSITION"] - 80.0) <= 0.1
    assert active[-1].t_ns <= b.plc.time_ns                                   # Done after the drive finished
    r = b.fb("MVR").run(DISTANCE=-25.5, **MOVE)
    assert r.done and abs(b.drive.mc.dem_p - 54.5 * MM) < 1
    assert struct.unpack_from("<H", b.payloads(0x301)[-1])[0] >> 4 == 0x091     # VAI 16 bit increment


def test_a_move_that_needs_32_bit_values_goes_as_predefined_vai(b):
    t0 = b.plc.time_ns
    r = b.fb("MVA").run(POSITION=123.4567, VELOCITY=333.3, ACCELERATION=7777.0, DECELERATION=6666.0)
    assert r.done, r
    heads = [struct.unpack_from("<H", f)[0] >> 4 for f in b.payloads(0x301, t0)]
    assert heads == [0x002, 0x002, 0x002, 0x020]                          # vmax, acc, dec, then 020xh
    d = b.drive
    assert (d.params[0x14BE].ram, d.params[0x14BF].ram, d.params[0x14C0].ram) == (333300, 777700, 666600)
    assert d.mc.dem_p == 1234567                                          # 0.1 um exact


def test_forced_16_bit_command_refuses_a_position_it_cannot_carry(b):
    t0 = b.plc.time_ns
    r = b.fb("MVA").run(POSITION=12.34, **MOVE, COMMAND="LM_VAI_16BIT")     # 0.1 mm units: 123.4
    assert r.error and r.error_id == E["PositionRange"] and r.scans == 1
    assert b.payloads(0x301, t0) == []


def test_a_newer_move_aborts_the_running_one(b):
    m1, m2 = b.fb("MVA"), b.fb("MVA2")
    m1.start(POSITION=200.0, **MOVE)
    b.step(60)
    assert m1["ACTIVE"] and m1["BUSY"]
    r = m2.run(POSITION=20.0, **MOVE, release=False)
    assert r.done
    assert m1["COMMANDABORTED"] and not m1["BUSY"] and not m1["DONE"] and not m1["ERROR"]
    assert abs(b.drive.mc.axis.position - 20 * MM) <= 1000
    m1["EXECUTE"] = False
    b.step(1)
    assert not m1["COMMANDABORTED"]


def test_halt_brakes_and_aborts_the_move(b):
    m = b.fb("MVA")
    m.start(POSITION=250.0, **MOVE)
    b.sim.run_until(lambda: b.drive.mc.dem_v >= 0.99e7, max_scans=500)
    t0 = b.plc.time_ns
    r = b.fb("HALT").run(DECELERATION=5000.0)
    assert r.done and m["COMMANDABORTED"]
    # from where the drive took the 017xh command: v^2 / (2 dec)
    [t_cmd] = [e.end_ns for e in b.bus.trace if e.frame.can_id == 0x401 and e.start_ns >= t0]
    at = b.drive.mc.trajectory.at(t_cmd)
    assert (b.drive.mc.dem_p - at.demand) * 1e-7 == pytest.approx((at.demand_velocity * 1e-7) ** 2 / (2 * 5.0),
                                                                 abs=0.0011)
    assert not b.drive.mc.motion_active


def test_stop_locks_out_moves_until_execute_falls(b):
    m = b.fb("MVA")
    m.start(POSITION=250.0, **MOVE)
    b.step(80)
    s = b.fb("STOP")
    r = s.run(DECELERATION=20000.0, release=False)
    assert r.done and m["COMMANDABORTED"] and b["RSTAT.STOPPING"]
    refused = b.fb("MVR").run(DISTANCE=1.0, **MOVE)
    assert refused.error and refused.error_id == E["StopActive"] and refused.scans == 1
    b.step(5)
    assert s["DONE"]                                                        # held while Execute
    s["EXECUTE"] = False
    b.step(1)
    assert b.fb("MVR").run(DISTANCE=1.0, **MOVE).done


def test_reset_after_a_following_error_then_move_again(b):
    m = b.fb("MVA")
    m.start(POSITION=200.0, **MOVE)
    b.step(50)
    b.drive.mc.block(True, b.bus.now)
    b.sim.run_until(lambda: m["ERROR"], max_scans=1000)
    assert m["ERRORID"] == E["DriveError"] and m["DRIVEERROR"] == 0x000B and not m["DONE"]
    assert b["RE.AXISERRORID"] == 0x000B and b["RE.TEXT"] == "Err: Pos Lag Always Too Big"
    assert b["RSTAT.ERRORSTOP"]
    b.sim.run_until(lambda: b.drive.mc.state == 4, max_scans=1000)         # the quick stop has ended
    b.drive.mc.block(False, b.bus.now)
    r = b.fb("RST").run()
    assert r.done and r["ERRORCLEARED"] == 0x000B
    b.sim.run_until(lambda: b["PW.STATUS"], max_scans=2000)
    m["EXECUTE"] = False                                                     # the failed run's Execute
    b.step(1)
    assert b.fb("MVA").run(POSITION=30.0, **MOVE).done


def test_position_limit_error_during_a_move():
    b = MotionBench(nodes=1, defaults={0x146F: 200 * MM}).ready()
    r = b.fb("MVA").run(POSITION=210.0, **MOVE)                             # beyond the 200 mm limit
    assert r.error and r.error_id == E["DriveError"] and r["DRIVEERROR"] == 0x0008
    assert b.drive.mc.state in (4, 14)


# ---------------------------------------------------------------- invalid inputs, refusals: no frame
@pytest.mark.parametrize("fb, inputs, name", [
    ("MVA", dict(POSITION=10.0, VELOCITY=0.0, ACCELERATION=1.0, DECELERATION=1.0), "InvalidVelocity"),
    ("MVA", dict(POSITION=10.0, VELOCITY=1.0, ACCELERATION=-1.0, DECELERATION=1.0), "InvalidAcceleration"),
    ("MVR", dict(DISTANCE=10.0, VELOCITY=1.0, ACCELERATION=1.0, DECELERATION=0.0), "InvalidDeceleration"),
    ("MVA", dict(POSITION=3e6, **MOVE), "PositionRange"),
    ("MVA", dict(POSITION=5000.0, **MOVE, COMMAND="LM_VAI_16BIT"), "PositionRange"),
    ("HALT", dict(DECELERATION=0.0), "InvalidDeceleration"),
    ("CURVE", dict(CURVEID=0), "InvalidCurveId"),
    ("CURVE", dict(CURVEID=1, MODE="LM_CURVE_SCALED", TIMESCALE=250.0), "ScaleRange"),
    ("CURVE", dict(CURVEID=1, MODE="LM_CURVE_SCALED", AMPLITUDESCALE=-2500.0), "ScaleRange"),
    ("CURVE", dict(CURVEID=1, MODE="LM_CURVE_TIMED", CURVETIME=0.0), "InvalidCurveTime"),
    ("CURVE", dict(CURVEID=1, MODE="LM_CURVE_TIMED", CURVETIME=0.2), "CommandNotMapped"),   # 12 bytes: RxPDO3 4
    ("CT", dict(ENTRY=256), "InvalidCtEntry"),
    ("LIVE", dict(UPID=0x4000, VALUE=1), "InvalidUpid"),
])
def test_invalid_inputs_end_in_error_before_any_frame(b, fb, inputs, name):
    t0 = b.plc.time_ns
    r = b.fb(fb).run(**inputs)
    assert r.error and r.error_id == E[name] and r.scans == 1
    assert b.payloads(0x301, t0) == [] and b.payloads(0x401, t0) == []


def test_moves_refused_when_not_enabled_or_not_homed():
    b = MotionBench(nodes=1)
    r = b.fb("MVA").run(POSITION=10.0, **MOVE)
    assert r.error and r.error_id == E["AxisNotEnabled"]
    b.power()
    r = b.fb("MVA").run(POSITION=10.0, **MOVE)
    assert r.error and r.error_id == E["AxisNotHomed"]
    r = b.fb("CURVE").run(CURVEID=1)
    assert r.error and r.error_id == E["AxisNotHomed"]
    assert b.payloads(0x301) == []


def test_flash_save_refused_while_enabled_and_motion_refused_while_mc_stopped():
    b = MotionBench(nodes=1)
    b.power()
    r = b.fb("FS").run(CURVES=True)
    assert r.error and r.error_id == E["AxisEnabled"]
    r = b.fb("MST").run()
    assert r.error and r.error_id == E["AxisEnabled"]
    b["PW.ENABLE"] = False
    b.step(5)
    assert b.fb("MST").run().done                                            # off: the MC may stop
    b.step(5)
    assert b["MO1.STATUSWORD"] == 0
    r = b.fb("HOME").run()
    assert r.error and r.error_id == E["McNotRunning"]


# ---------------------------------------------------------------- curves and the command table
def pvl_curves() -> dict[int, Curve]:
    return {c.curve_id: Curve(c.curve_id, c.info_block, c.data_block) for c in load_pvl(PVL).curves}


@pytest.fixture
def bc():
    b = MotionBench(nodes=1, defaults={0x2041: 2}, pdo={"RX3BYTES": 8})   # RxPDO3 carries par bytes 6..11
    for d in b.drives.values():
        d.curves.ram.update(pvl_curves())
    return b.ready()


@pytest.mark.parametrize("mode, inputs, end_mm, duration_s", [
    ("LM_CURVE_DEFAULT", {}, 100.0, 0.4),
    ("LM_CURVE_FROM_ACTUAL", {}, 100.0, 0.4),
    ("LM_CURVE_TO_POSITION", dict(TARGETPOSITION=60.0), 60.0, 0.4),
    ("LM_CURVE_TO_POSITION_TIME", dict(TARGETPOSITION=40.0, CURVETIME=0.25), 40.0, 0.25),
    ("LM_CURVE_SCALED", dict(OFFSET=0.0, TIMESCALE=150.0, AMPLITUDESCALE=50.0), 50.0, 0.6),
    ("LM_CURVE_TIMED", dict(OFFSET=0.0, CURVETIME=0.3, AMPLITUDESCALE=80.0), 80.0, 0.3),
])
def test_run_curve_each_variant(bc, mode, inputs, end_mm, duration_s):
    t0 = bc.plc.time_ns
    r = bc.fb("CURVE").run(CURVEID=1, MODE=mode, **inputs)
    assert r.done, r
    d = bc.drive
    active = [s for s in d.mc.trajectory.between(t0) if s.status_word & 0x2000]
    assert abs((active[-1].t_ns - active[0].t_ns) / 1e9 - duration_s) <= 0.002
    assert d.mc.dem_p == pytest.approx(end_mm * MM, abs=1)
    head = struct.unpack_from("<H", bc.payloads(0x301, t0)[0])[0] >> 4
    assert head == {"LM_CURVE_DEFAULT": 0x040, "LM_CURVE_FROM_ACTUAL": 0x041, "LM_CURVE_TO_POSITION": 0x042,
                    "LM_CURVE_TO_POSITION_TIME": 0x043, "LM_CURVE_SCALED": 0x044, "LM_CURVE_TIMED": 0x045}[mode]


def test_run_curve_not_in_the_drive_is_the_drives_error(bc):
    r = bc.fb("CURVE").run(CURVEID=42)
    assert r.error and r.error_id == E["DriveError"] and r["DRIVEERROR"] == 0x0062


def test_start_a_command_table_entry_written_by_the_ct_services():
    b = MotionBench(nodes=1).ready()
    seq = {3: (C.VAI16_GO_TO_POS << 4, C.encode(C.VAI16_GO_TO_POS, 0, target=300, vmax=500, acc=50, dec=50)[2:], 4),
           4: (C.WAIT_IN_TARGET_POSITION << 4, b"", 5),
           5: (C.VAI16_GO_TO_POS << 4, C.encode(C.VAI16_GO_TO_POS, 0, target=100, vmax=500, acc=50, dec=50)[2:],
               0xFFFF)}
    for entry, (header, params, link) in seq.items():
        b.drive.ct.ram[entry] = build_entry(header, params, link=link)
    r = b.fb("CT").run(ENTRY=3)
    assert r.done and not b.drive.mc.motion_active
    assert b.drive.mc.ct_runner.executed == [3, 4, 5]
    assert b.drive.mc.dem_p == 10 * MM
    assert max(s.demand for s in b.drive.mc.trajectory.samples) == pytest.approx(30 * MM)


def test_start_a_missing_entry_is_the_drives_error():
    b = MotionBench(nodes=1).ready()
    r = b.fb("CT").run(ENTRY=77)
    assert r.error and r.error_id == E["DriveError"] and r["DRIVEERROR"] == 0x008A


def test_write_live(b):
    r = b.fb("LIVE").run(UPID=0x13A2, VALUE=55)
    assert r.done and b.drive.params[0x13A2].ram == 55


# ---------------------------------------------------------------- readers
def test_read_status_and_position_during_a_move(b):
    m = b.fb("MVA")
    m.start(POSITION=100.0, **MOVE)
    b.step(40)
    assert b["RSTAT.DISCRETEMOTION"] and b["RSTAT.MOTIONACTIVE"] and b["RSTAT.VALID"]
    assert b["RSTAT.AXISSTATE"] == "LM_AXIS_DISCRETE_MOTION"
    pos = b["RP.POSITION"]
    assert 0 < pos < 100 and abs(pos - b.drive.mc.axis.position / MM) < 2.0      # 16-bit: 0.1 mm, one scan old
    b.sim.run_until(lambda: m["DONE"], max_scans=1000)
    assert b["RSTAT.STANDSTILL"] and b["RSTAT.INTARGETPOSITION"] and b["RSTAT.HOMED"]


def test_read_actual_position_32_bit_from_txpdo3():
    b = MotionBench(nodes=1, defaults={0x203B: 0x1B8D}, pdo={"TX3POSITION": True}).ready()
    assert b.fb("MVA").run(POSITION=12.3456, VELOCITY=100.0, ACCELERATION=1000.0, DECELERATION=1000.0).done
    b.step(60)
    assert b["RP.RESOLUTION32"] and b["RP.POSITION"] == pytest.approx(b.drive.mc.axis.position / MM, abs=1e-4)


# ---------------------------------------------------------------- faults
def test_a_lost_rxpdo_is_resent_until_the_echo(b):
    b.bus.drop(lambda f: f.can_id == 0x301, count=1)                       # the command's first RxPDO2 lost
    t0 = b.plc.time_ns
    r = b.fb("MVA").run(POSITION=40.0, **MOVE)
    assert r.done and abs(b.drive.mc.axis.position - 40 * MM) <= 1000
    assert len(b.payloads(0x301, t0)) == 1 and b["MO1.RESENDS"] == 1         # the lost one never reached the bus


def test_a_command_the_drive_never_takes_times_out(b):
    b.bus.drop(lambda f: f.can_id == 0x301)
    b["PDO1.COMMANDTIMEOUT"] = 100 * MS
    r = b.fb("MVA").run(POSITION=40.0, **MOVE)
    assert r.error and r.error_id == E["CommandTimeout"] and 95 <= r.scans <= 110
    assert not b.drive.mc.motion_active and b.drive.mc.dem_p == 0


def test_lost_txpdos_are_reported():
    b = MotionBench(nodes=1, pdo={"PDOTIMEOUT": 100 * MS})
    b.fb("SETUP").run(EVENTTIMERMS=20)                                       # TxPDO1 at least every 20 ms
    b.ready()
    b.step(200)
    assert b["MO1.VALID"]                                                    # a resting drive still sends
    b.bus.drop(lambda f: f.can_id == 0x181)
    m = b.fb("MVA")
    m.start(POSITION=30.0, **MOVE)
    b.sim.run_until(lambda: m["ERROR"], max_scans=400)
    assert m["ERRORID"] in (E["NoProcessData"], E["CommandTimeout"]) and not m["DONE"]
    assert b["PDO1.ERROR"] and b["PDO1.ERRORID"] == E["NoProcessData"] and not b["RSTAT.VALID"]


def test_drive_reset_mid_move_is_reported():
    b = MotionBench(nodes=1).ready()
    m = b.fb("MVA")
    m.start(POSITION=200.0, **MOVE)
    b.step(60)
    b.bus.reset_node("drive1", b.bus.now)
    b.sim.run_until(lambda: m["ERROR"], max_scans=2000)
    assert m["ERRORID"] in (E["DriveRebooted"], E["NoProcessData"], E["PowerLost"]) and not m["DONE"]
    assert not b.drive.mc.homed


def test_both_drives_move_in_parallel():
    b = MotionBench(nodes=2).ready()
    b["PW2.ENABLE"] = True
    b.sim.run_until(lambda: b["PW2.STATUS"], max_scans=2000)
    send = raw_sender(b)
    raw = C.encode(C.MASTER_HOMING, 1, home_position=0)
    send(0x302, raw.ljust(8, b"\0").hex())
    send(0x402, raw[:2].hex() + "0000")
    b.step(5)
    assert b.drives[2].mc.homed
    m1, m2 = b.fb("MVA"), b.fb("MVA_2")
    m1.start(POSITION=50.0, **MOVE)
    m2.start(POSITION=70.0, **MOVE)
    b.sim.run_until(lambda: m1["DONE"] and m2["DONE"], max_scans=1000)
    assert abs(b.drives[1].mc.axis.position - 50 * MM) <= 1000
    assert abs(b.drives[2].mc.axis.position - 70 * MM) <= 1000


def test_pdo_setup_waits_for_room_in_a_full_mailbox():
    """Other axes of a shared mailbox fill Tx in the setup's scans: the NMT frames wait (a lost Enter
    Pre-Operational left the drive Operational, refusing the PDO parameters with 08000022h; found at 17 axes
    on one mailbox), then the setup runs in order and the drive is Operational again."""
    b = MotionBench(nodes=1)
    b["FILLTX"] = 32
    setup = b.fb("SETUP")
    t0 = b.plc.time_ns
    setup.start(MODE="LM_PDO_SYNC", EVENTTIMERMS=0)
    b.step(20)
    assert setup["BUSY"] and not setup["ERROR"]
    assert not [e for e in b.bus.trace if e.start_ns >= t0 and e.frame.can_id in (0x000, 0x601)]
    b["FILLTX"] = 0
    b.sim.run_until(lambda: setup["DONE"] or setup["ERROR"], max_scans=500)
    assert setup["DONE"], setup["ERRORID"]
    b.step(5)                                                    # the NMT Start of the last scan goes out
    sent = [(e.frame.can_id, bytes(e.frame.data[:2])) for e in b.bus.trace
            if e.start_ns >= t0 and e.frame.can_id in (0x000, 0x601)]
    assert sent[0] == (0x000, bytes([0x80, 1])) and sent[-1] == (0x000, bytes([0x01, 1]))
    assert [c.ttype for c in b.drive.pdo.tx][:2] == [1, 1] and b.drive.nmt_state == "OPERATIONAL"


def test_pdo_setup_fails_with_txfull_when_the_mailbox_stays_full():
    """A mailbox that never has room: the setup ends with TxFull one SdoTimeout after its turn, having sent
    nothing (the drive keeps its PDO parameters and stays Operational)."""
    b = MotionBench(nodes=1)
    b["FILLTX"] = 32
    t0 = b.plc.time_ns
    r = b.fb("SETUP").run(MODE="LM_PDO_SYNC", EVENTTIMERMS=0, max_scans=3000)
    assert r.error and r.error_id == E["TxFull"], r
    assert 0.99e9 <= b.plc.time_ns - t0 <= 1.1e9                # the channel's SdoTimeout (1 s)
    assert not [e for e in b.bus.trace if e.start_ns >= t0 and e.frame.can_id in (0x000, 0x601)]
    assert b.drive.nmt_state == "OPERATIONAL" and [c.ttype for c in b.drive.pdo.tx][:2] != [1, 1]


# ---------------------------------------------------------------- SYNC transmission, the library's SYNC producer
def test_sync_mode_with_the_librarys_sync_producer():
    b = MotionBench(nodes=1, pdo={"PDOTIMEOUT": 50 * MS})
    b["SYNC.PERIOD"] = 2 * MS
    b["SYNC.ENABLE"] = True
    r = b.fb("SETUP").run(MODE="LM_PDO_SYNC", EVENTTIMERMS=0)
    assert r.done, r
    assert [c.ttype for c in b.drive.pdo.tx][:2] == [1, 1] and b.drive.pdo.rx_on_sync
    b.ready()
    t0 = b.plc.time_ns
    assert b.fb("MVA").run(POSITION=20.0, **MOVE).done
    assert abs(b.drive.mc.axis.position - 20 * MM) <= 1000
    tx1 = [e.start_ns for e in b.bus.trace if e.frame.can_id == 0x181 and e.start_ns >= t0]
    syncs = [e.start_ns for e in b.bus.trace if e.frame.can_id == 0x080 and e.start_ns >= t0]
    assert len(tx1) >= len(syncs) - 2 and 0.9 <= len(syncs) / ((b.plc.time_ns - t0) / (2 * MS)) <= 1.1
    b.step(100)                                                    # a resting drive keeps sending on SYNC
    assert b["MO1.VALID"]


def test_sync_every_nth_sync():
    """SyncEvery n: transmission type n (1800h/1801h sub 2), the TxPDOs every n-th SYNC (CiA 301); 0 is refused
    before any frame (InvalidMode)."""
    b = MotionBench(nodes=1, pdo={"PDOTIMEOUT": 50 * MS})
    t0 = b.plc.time_ns
    r = b.fb("SETUP").run(MODE="LM_PDO_SYNC", EVENTTIMERMS=0, SYNCEVERY=0)
    assert r.error and r.error_id == E["InvalidMode"], r
    assert not [e for e in b.bus.trace if e.start_ns >= t0 and e.frame.can_id in (0x000, 0x601)]
    b["SYNC.PERIOD"] = 2 * MS
    b["SYNC.ENABLE"] = True
    r = b.fb("SETUP").run(MODE="LM_PDO_SYNC", EVENTTIMERMS=0, SYNCEVERY=3)
    assert r.done, r
    assert [c.ttype for c in b.drive.pdo.tx][:2] == [3, 3]
    t0 = b.plc.time_ns
    b.step(300)
    tx1 = [e for e in b.bus.trace if e.frame.can_id == 0x181 and e.start_ns >= t0]
    syncs = [e for e in b.bus.trace if e.frame.can_id == 0x080 and e.start_ns >= t0]
    assert abs(len(tx1) - len(syncs) / 3) <= 1 and b["MO1.VALID"]


# ---------------------------------------------------------------- both backends, the same frames
def frames_of_a_sequence(backend: str) -> list[tuple[int, int, bytes]]:
    b = MotionBench(nodes=1, backend=backend).ready()
    assert b.fb("MVA").run(POSITION=12.3, **MOVE).done
    assert b.fb("MVR").run(DISTANCE=1.23456, VELOCITY=50.0, ACCELERATION=500.0, DECELERATION=400.0).done
    assert b.fb("HALT").run(DECELERATION=1000.0).done
    return [(e.start_ns, e.frame.can_id, bytes(e.frame.data)) for e in b.bus.trace]


def test_matiec_and_builtin_put_the_same_frames_on_the_bus():
    from stbench import available_backends

    if len(available_backends()) < 2:
        pytest.skip(f"needs both backends, found {available_backends()} (MatIEC's iec2c: set MATIEC_HOME)")
    assert frames_of_a_sequence("matiec") == frames_of_a_sequence("builtin")


# ---------------------------------------------------------------- a B1100 axis (the ST's LM_B1100 paths)
def test_b1100_curve_motion_refused_before_any_frame(bc):
    """A B1100 has no curves (seed 000 5): FB_LmRunCurve fails NotSupported in the call of the edge and sends no
    motion command (the drive here is an emulated E1100; the refusal depends only on the axis' drive type)."""
    bc["CH1.DRIVE"] = "LM_B1100"
    bc.step(1)
    t0 = bc.plc.time_ns
    r = bc.fb("CURVE").run(CURVEID=1, MODE="LM_CURVE_DEFAULT")
    assert r.error and r.error_id == E["NotSupported"] and r.scans == 1
    bc.step(5)
    assert bc.payloads(0x301, t0) == []
    bc["CH1.DRIVE"] = "LM_E1100"                     # the same FB on an E1100 axis runs the curve
    bc.step(1)
    assert bc.fb("CURVE").run(CURVEID=1, MODE="LM_CURVE_DEFAULT").done


def test_write_live_takes_a_b1100_upid_above_3fffh(b):
    """The motion command 002xh carries a 16-bit UPID; a B1100's live parameters lie up to FFFFh (6198h P gain,
    LinRS p.26), an E1100's below 4000h (2000h + UPID)."""
    r = b.fb("LIVE").run(UPID=0x6198, VALUE=12)
    assert r.error and r.error_id == E["InvalidUpid"] and r.scans == 1
    b["CH1.DRIVE"] = "LM_B1100"
    b.step(1)
    t0 = b.plc.time_ns
    r = b.fb("LIVE").run(UPID=0x6198, VALUE=12)
    assert r.done                                    # the emulated E1100 ignores a UPID it does not know
    (payload,) = [p for p in b.payloads(0x301, t0) if struct.unpack_from("<H", p)[0] >> 4 == 0x002]
    assert struct.unpack_from("<H", payload, 2)[0] == 0x6198


# ================================================================ the PLCopen FBs of issue 22
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
