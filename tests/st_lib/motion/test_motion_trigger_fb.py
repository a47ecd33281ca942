"""FB_LmTriggeredMove (st_lib/motion/trigger.st) against the emulated E1100's event handler (emulator/linmot/
motion/events.py) and its trigger input X4.6 in direct mode (170Ch = 1, [MC] 7.2.2): armed, Active while it
waits, the move runs on the edge the test raises and the FB is Done in target; disarmed by FB_LmAbortTrigger
before its edge nothing moves; the falling-edge, increment, curve and command-table variants; the command each
input set chooses; refusals before any frame. Runs on the backend the suite runs on (MatIEC where installed,
STLIB_BACKEND forces one)."""

from __future__ import annotations

import struct

import pytest

from linmot_st.emulator import Curve, build_entry
from linmot_st.protocol import commands as C
from linmot_st.protocol.commands import Target
from linmot_st.protocol.commands.command_table import START_COMMAND_TABLE
from linmot_st.protocol.commands.curves import TIME_CURVE_OFFSET_TIME_AMP, TIME_CURVE_TO_POS, TIME_CURVE_TO_POS_TIME
from linmot_st.protocol.commands.triggered import TRIGGERED, Units
from linmot_st.protocol.errors import BY_NAME
from motionbench import MM, MotionBench

E = {name: e.value for name, e in BY_NAME.items()}
MOVE = dict(VELOCITY=1000.0, ACCELERATION=10000.0, DECELERATION=10000.0)     # 16-bit exact: 09Axh
TRIGGER_DIRECT = {0x170C: 1}


def bench(**kw) -> MotionBench:
    return MotionBench(nodes=1, defaults=TRIGGER_DIRECT, **kw).ready()


def heads(b: MotionBench, t0: int) -> list[int]:
    return [struct.unpack_from("<H", f)[0] >> 4 for f in b.payloads(0x301, t0)]


def arm(b: MotionBench, **inputs):
    trig = b.fb("TRIG")
    trig.start(**{"ARM": "LM_TRIG_GO_TO_POS", "POSITION": 40.0, **MOVE, **inputs})
    b.sim.run_until(lambda: trig["ACTIVE"] or trig["ERROR"], max_scans=200)
    assert trig["ACTIVE"] and trig["BUSY"] and not trig["TRIGGERED"], trig["ERRORID"]
    return trig


def test_armed_move_waits_active_then_runs_on_the_rising_edge():
    b = bench()
    start = b.drive.mc.axis.position
    t0 = b.plc.time_ns
    trig = arm(b)
    assert b["RSTAT.STATUSWORD"] & 0x0100                               # the drive's event handler is armed
    b.step(100)                                                          # no edge: nothing moves
    assert trig["ACTIVE"] and not trig["DONE"] and b.drive.mc.axis.position == start
    t_edge = b.bus.now
    b.drive.io.set_input("X4.6", 1, t_edge)
    b.sim.run_until(lambda: trig["TRIGGERED"] or trig["ERROR"], max_scans=50)
    assert trig["TRIGGERED"] and trig["ACTIVE"]
    b.sim.run_until(lambda: trig["DONE"] or trig["ERROR"] or trig["COMMANDABORTED"], max_scans=2000)
    assert trig["DONE"] and not trig["ACTIVE"] and not trig["BUSY"]
    assert abs(b.drive.mc.axis.position - 40 * MM) <= 1000
    moving = [s for s in b.drive.mc.trajectory.between(t0) if s.demand != start]
    assert moving and moving[0].t_ns >= t_edge                          # the demand left only after the edge
    assert heads(b, t0) == [0x09A]
    b["TRIG.EXECUTE"] = False
    b.step(1)
    assert not trig["DONE"]


def test_disarmed_before_its_edge_moves_nothing():
    b = bench()
    start = b.drive.mc.axis.position
    trig = arm(b)
    t0 = b.plc.time_ns
    r = b.fb("ABORTTRIG").run()
    assert r.done, r
    b.step(2)
    assert trig["COMMANDABORTED"] and not trig["BUSY"] and not trig["ACTIVE"]
    assert heads(b, t0) == [0x008] and not b["RSTAT.STATUSWORD"] & 0x0100
    b.drive.io.set_input("X4.6", 1)
    b.step(300)
    b.drive.io.set_input("X4.6", 0)
    b.step(50)
    assert b.drive.mc.axis.position == start and b.drive.mc.events.fired == []
    assert all(s.demand == start for s in b.drive.mc.trajectory.between(t0))


def test_falling_edge_increment_from_the_last_target():
    b = bench()
    assert b.fb("MVA").run(POSITION=50.0, **MOVE).done
    b.drive.io.set_input("X4.6", 1)
    b.step(5)
    t0 = b.plc.time_ns
    trig = arm(b, ARM="LM_TRIG_INCREMENT", FALLING=True, POSITION=-12.3456, VELOCITY=333.3,
               ACCELERATION=7777.0, DECELERATION=6666.0)
    assert heads(b, t0) == [0x002, 0x002, 0x002, 0x02D]                  # 32-bit values: the predefined VAI
    b.drive.io.set_input("X4.6", 0)                                      # the falling edge
    b.sim.run_until(lambda: trig["DONE"] or trig["ERROR"], max_scans=2000)
    assert trig["DONE"], trig["ERRORID"]
    assert abs(b.drive.mc.dem_p - (50 * MM - 123456)) < 1
    assert b.drive.mc.params[0x14BE].ram == 333_300


def test_predefined_limits_send_only_the_position():
    b = bench()
    t0 = b.plc.time_ns
    trig = arm(b, POSITION=25.0, PREDEFINEDLIMITS=True, VELOCITY=0.0)
    frames = b.payloads(0x301, t0)
    assert heads(b, t0) == [0x02A] and struct.unpack_from("<i", frames[0], 2)[0] == 25 * MM
    b.drive.io.set_input("X4.6", 1)
    b.sim.run_until(lambda: trig["DONE"] or trig["ERROR"], max_scans=2000)
    assert trig["DONE"] and abs(b.drive.mc.axis.position - 25 * MM) <= 1000


def test_a_second_edge_runs_the_armed_command_again_until_disarmed():
    """The drive keeps the command armed after it ran ([MC] 4.3.6): an increment runs on every edge."""
    b = bench()
    start = b.drive.mc.dem_p
    trig = arm(b, ARM="LM_TRIG_INCREMENT", POSITION=5.0)
    for k in (1, 2):
        b.drive.io.set_input("X4.6", 1)
        b.step(200)
        b.drive.io.set_input("X4.6", 0)
        b.step(10)
        assert abs(b.drive.mc.dem_p - (start + k * 5 * MM)) < 1
    assert trig["DONE"]
    assert b.fb("ABORTTRIG").run().done
    b.drive.io.set_input("X4.6", 1)
    b.step(200)
    assert abs(b.drive.mc.dem_p - (start + 10 * MM)) < 1


def curves_and_table(b: MotionBench) -> None:
    b.drive.curves.ram[1] = Curve.build(1, [k * k * 1000 for k in range(11)], x_length=5000)  # 0 .. 10 mm, 50 ms
    params = C.encode(C.VAI16_INCREMENT_DEM_POS, 0, target=100, vmax=500, acc=100, dec=100)[2:]
    b.drive.ct.ram[5] = build_entry(C.VAI16_INCREMENT_DEM_POS << 4, params)                    # +10 mm


@pytest.mark.parametrize("inputs, cid, moved_mm", [
    (dict(ARM="LM_TRIG_CURVE_TO_POS", CURVEID=1), 0x04A, 15.0),        # the curve scaled to end 15 mm on
    (dict(ARM="LM_TRIG_COMMAND_TABLE", ENTRY=5), 0x201, 10.0),
])
def test_curve_and_command_table_start_on_the_edge(inputs, cid, moved_mm):
    b = bench()
    curves_and_table(b)
    start = b.drive.mc.dem_p
    t0 = b.plc.time_ns
    trig = arm(b, **{"POSITION": start / MM + moved_mm, **inputs})
    assert heads(b, t0) == [cid]
    b.step(50)
    assert b.drive.mc.dem_p == start
    b.drive.io.set_input("X4.6", 1)
    b.sim.run_until(lambda: trig["DONE"] or trig["ERROR"], max_scans=3000)
    assert trig["DONE"], (trig["ERRORID"], trig["DRIVEERROR"])
    assert abs(b.drive.mc.dem_p - start - moved_mm * MM) < 2


@pytest.mark.parametrize("inputs, error", [
    (dict(VELOCITY=0.0), "InvalidVelocity"),
    (dict(DECELERATION=-1.0), "InvalidDeceleration"),
    (dict(POSITION=1.0e6), "PositionRange"),
    (dict(ARM="LM_TRIG_CURVE_TO_POS", CURVEID=0), "InvalidCurveId"),
    (dict(ARM="LM_TRIG_COMMAND_TABLE", ENTRY=256), "InvalidCtEntry"),
    (dict(COMMAND="LM_VAI_DEC_ACC"), "CommandNotMapped"),               # 12 bytes: the default RxPDOs carry 8
])
def test_invalid_inputs_refused_before_any_frame(inputs, error):
    b = bench()
    t0 = b.plc.time_ns
    r = b.fb("TRIG").run(**{"ARM": "LM_TRIG_GO_TO_POS", "POSITION": 40.0, **MOVE, **inputs}, max_scans=5)
    assert r.error and r.error_id == E[error]
    assert b.payloads(0x301, t0) == [] and b.payloads(0x401, t0) == []


def test_not_homed_refused_before_any_frame():
    b = MotionBench(nodes=1, defaults=TRIGGER_DIRECT)
    b.power()
    t0 = b.plc.time_ns
    r = b.fb("TRIG").run(ARM="LM_TRIG_GO_TO_POS", POSITION=40.0, **MOVE, max_scans=5)
    assert r.error and r.error_id == E["AxisNotHomed"] and b.payloads(0x301, t0) == []


# ---------------------------------------------------------------- the command each input set sends, by the catalogue
def bench12() -> MotionBench:
    """RxPDO3 maps parameter bytes 6..11: VAI Dec=Acc's 12 bytes fit."""
    return MotionBench(nodes=1, defaults={**TRIGGER_DIRECT, 0x2041: 2}, pdo={"RX3BYTES": 8}).ready()


FAMILIES = {                     # the move's values -> the family FB_LmMoveAbsolute's plan picks, its catalogue units
    "16 bit": (MOVE, Units.V16),
    "predefined": (dict(VELOCITY=333.3, ACCELERATION=7777.0, DECELERATION=6666.0), Units.P32),
    "dec=acc": (dict(VELOCITY=333.3, ACCELERATION=7777.0, DECELERATION=7777.0), Units.DA),
}


@pytest.mark.parametrize("falling", [False, True], ids=["rising", "falling"])
@pytest.mark.parametrize("arm_input", ["LM_TRIG_GO_TO_POS", "LM_TRIG_INCREMENT"])
@pytest.mark.parametrize("family", list(FAMILIES))
def test_the_vai_command_sent_is_the_catalogue_row_of_that_edge_target_and_family(family, arm_input, falling):
    """F_LmTriggerCid's IDs against protocol/commands/triggered.py: the row sent is a triggered one of that edge,
    its units the family's, an increment row for LM_TRIG_INCREMENT; on that edge the axis ends where the inputs
    say (12.5 mm, or 12.5 mm on from the last target)."""
    values, units = FAMILIES[family]
    b = bench12() if units is Units.DA else bench()
    assert b.fb("MVA").run(POSITION=30.0, **MOVE).done           # the last target 30 mm: go to / increment differ
    start = b.drive.mc.dem_p
    if falling:
        b.drive.io.set_input("X4.6", 1)
        b.step(5)
    t0 = b.plc.time_ns
    trig = arm(b, ARM=arm_input, FALLING=falling, POSITION=12.5, **values)
    cid = heads(b, t0)[-1]
    row = C.COMMANDS[cid]
    assert (TRIGGERED[cid].rising, TRIGGERED[cid].units) == (not falling, units)
    assert (row.target is Target.FROM_LAST_TARGET) == (arm_input == "LM_TRIG_INCREMENT")
    b.step(20)
    assert b.drive.mc.dem_p == start
    b.drive.io.set_input("X4.6", 0 if falling else 1)
    b.sim.run_until(lambda: trig["DONE"] or trig["ERROR"], max_scans=2000)
    assert trig["DONE"], (trig["ERRORID"], trig["DRIVEERROR"])
    expected = 12.5 * MM + (start if arm_input == "LM_TRIG_INCREMENT" else 0)
    assert abs(b.drive.mc.dem_p - expected) < 1


@pytest.mark.parametrize("falling", [False, True], ids=["rising", "falling"])
@pytest.mark.parametrize("arm_input, base", [("LM_TRIG_CURVE_TO_POS", TIME_CURVE_TO_POS),
                                             ("LM_TRIG_CURVE_TO_POS_TIME", TIME_CURVE_TO_POS_TIME),
                                             ("LM_TRIG_CURVE_TIMED", TIME_CURVE_OFFSET_TIME_AMP),
                                             ("LM_TRIG_COMMAND_TABLE", START_COMMAND_TABLE)])
def test_curve_and_table_starts_are_the_catalogue_rows_of_that_edge(arm_input, base, falling):
    b = bench12()
    curves_and_table(b)
    t0 = b.plc.time_ns
    arm(b, ARM=arm_input, FALLING=falling, CURVEID=1, ENTRY=5, POSITION=b.drive.mc.dem_p / MM + 15.0, CURVETIME=0.1)
    cid = heads(b, t0)[-1]
    assert (TRIGGERED[cid].rising, TRIGGERED[cid].base) == (not falling, base)


# ---------------------------------------------------------------- the curves with a time, offset and amplitude
def test_curve_to_position_in_a_curve_time_on_the_edge():
    """04Exh (10 parameter bytes, RxPDO3 carrying bytes 6..9): the curve scaled to end 15 mm on, in 0.2 s."""
    b = MotionBench(nodes=1, defaults={**TRIGGER_DIRECT, 0x2041: 1}, pdo={"RX3BYTES": 6}).ready()
    curves_and_table(b)
    start = b.drive.mc.dem_p
    t0 = b.plc.time_ns
    trig = arm(b, ARM="LM_TRIG_CURVE_TO_POS_TIME", CURVEID=1, POSITION=start / MM + 15.0, CURVETIME=0.2)
    assert heads(b, t0) == [0x04E]
    t_edge = b.bus.now
    b.drive.io.set_input("X4.6", 1, t_edge)
    b.sim.run_until(lambda: trig["DONE"] or trig["ERROR"], max_scans=3000)
    assert trig["DONE"], (trig["ERRORID"], trig["DRIVEERROR"])
    assert abs(b.drive.mc.dem_p - start - 15 * MM) < 2
    moving = [s.t_ns for s in b.drive.mc.trajectory.between(t0) if s.demand_velocity != 0]
    assert moving[0] >= t_edge and (moving[-1] - moving[0]) / 1e9 == pytest.approx(0.2, abs=0.01)


def test_curve_with_offset_time_and_amplitude_on_the_falling_edge():
    """047xh (12 bytes): curve 1 (0 .. 10 mm) at 50 %, from 20 mm (where the axis stands: the curve starts at its
    offset), in 0.1 s: it ends at 25 mm."""
    b = bench12()
    curves_and_table(b)
    assert b.fb("MVA").run(POSITION=20.0, **MOVE).done
    b.drive.io.set_input("X4.6", 1)
    b.step(5)
    t0 = b.plc.time_ns
    trig = arm(b, ARM="LM_TRIG_CURVE_TIMED", FALLING=True, CURVEID=1, OFFSET=20.0, CURVETIME=0.1,
               AMPLITUDESCALE=50.0)
    frame = b.payloads(0x301, t0)[-1] + b.payloads(0x401, t0)[-1][2:]
    assert heads(b, t0) == [0x047] and struct.unpack_from("<HiiH", frame, 2) == (1, 20 * MM, 10_000, 500)
    b.drive.io.set_input("X4.6", 0)
    b.sim.run_until(lambda: trig["DONE"] or trig["ERROR"], max_scans=3000)
    assert trig["DONE"], (trig["ERRORID"], trig["DRIVEERROR"])
    assert abs(b.drive.mc.dem_p - 25 * MM) < 2


@pytest.mark.parametrize("inputs, error", [
    (dict(ARM="LM_TRIG_CURVE_TO_POS_TIME", CURVEID=1, CURVETIME=0.1), "CommandNotMapped"),   # default: 8 bytes
    (dict(ARM="LM_TRIG_CURVE_TIMED", CURVEID=1, CURVETIME=0.1), "CommandNotMapped"),
])
def test_curve_variants_beyond_the_default_rxpdos_refused_before_any_frame(inputs, error):
    b = bench()
    t0 = b.plc.time_ns
    r = b.fb("TRIG").run(**inputs, max_scans=5)
    assert r.error and r.error_id == E[error] and b.payloads(0x301, t0) == []


@pytest.mark.parametrize("inputs, error", [
    (dict(ARM="LM_TRIG_CURVE_TO_POS_TIME", CURVEID=1, CURVETIME=0.0), "InvalidCurveTime"),
    (dict(ARM="LM_TRIG_CURVE_TIMED", CURVEID=1, CURVETIME=0.1, AMPLITUDESCALE=2500.0), "ScaleRange"),
    (dict(ARM="LM_TRIG_CURVE_TIMED", CURVEID=1, CURVETIME=0.1, OFFSET=1.0e6), "PositionRange"),
])
def test_curve_variant_inputs_refused_before_any_frame(inputs, error):
    b = bench12()
    t0 = b.plc.time_ns
    r = b.fb("TRIG").run(**inputs, max_scans=5)
    assert r.error and r.error_id == E[error] and b.payloads(0x301, t0) == [] and b.payloads(0x401, t0) == []


def test_b1100_axis_curve_and_table_refused_and_auto_goes_predefined():
    """A B1100 has only the predefined triggered VAIs (02Axh..02Dxh, seed 004 4.2's B1100 column); the refusal
    and the choice depend only on the axis' drive type (the drive here is an emulated E1100)."""
    b = bench()
    b["CH1.DRIVE"] = "LM_B1100"
    b.step(1)
    t0 = b.plc.time_ns
    for inputs in (dict(ARM="LM_TRIG_CURVE_TO_POS", CURVEID=1), dict(ARM="LM_TRIG_COMMAND_TABLE", ENTRY=5)):
        r = b.fb("TRIG").run(**inputs, POSITION=10.0, max_scans=5)
        assert r.error and r.error_id == E["NotSupported"]
    assert b.payloads(0x301, t0) == []
    trig = arm(b, POSITION=20.0)                   # AUTO, values the 16-bit scaling (still set) would carry
    assert heads(b, t0) == [0x002, 0x002, 0x002, 0x02A]
    assert [struct.unpack_from("<H", f, 2)[0] for f in b.payloads(0x301, t0)[:3]] == [0xD4BE, 0xD4BF, 0xD4C0]
    b.drive.io.set_input("X4.6", 1)
    b.sim.run_until(lambda: trig["DONE"] or trig["ERROR"], max_scans=2000)
    assert trig["DONE"] and abs(b.drive.mc.dem_p - 20 * MM) < 1
