"""MC_CamTableSelect / MC_CamIn / MC_CamOut (st_lib/motion/cam.st) against the emulated E1100's encoder cams: the
PLC selects a cam curve (object type 0103h) in the drive's RAM, couples the axis to the master encoder, and the
drive's demand follows the curve as written at the encoder's counter (computed here from the setpoints, not from
the emulator's cam model); EndOfProfile at the cycle end; CamOut brakes to standstill; refusals before any
frame."""

from __future__ import annotations

import struct

import pytest

from linmot_st.emulator import Curve
from linmot_st.emulator.linmot.master_encoder import SpeedProfile
from linmot_st.protocol import upids as U
from linmot_st.protocol.errors import BY_NAME
from motionbench import MM, MotionBench

E = {name: e.value for name, e in BY_NAME.items()}
MS = 1_000_000
CAM_ID = 7
SETPOINTS = [0, 20 * MM, 60 * MM, 80 * MM, 60 * MM, 20 * MM, 0]      # a closed cam: 0 -> 80 mm -> 0
LENGTH = 8000                                                          # counts: one revolution


def bench() -> MotionBench:
    b = MotionBench(nodes=1, defaults={U.P_MASTER_ENCODER_SOURCE: 1, U.P_MASTER_ENCODER_COUNTS_PER_REV: LENGTH})
    b.drive.curves.ram[CAM_ID] = Curve.build(CAM_ID, SETPOINTS, name="cam", x_length=LENGTH, object_type=0x0103,
                                             x_dim=0x001B)
    return b.ready()


def cam_at(count: float, start: int, offset: float) -> float:
    rel = (count - start) % LENGTH
    x = rel / LENGTH * (len(SETPOINTS) - 1)
    i = min(int(x), len(SETPOINTS) - 2)
    return offset + SETPOINTS[i] + (x - i) * (SETPOINTS[i + 1] - SETPOINTS[i])


def heads(b: MotionBench, t0: int) -> list[int]:
    return [struct.unpack_from("<H", f)[0] >> 4 for f in b.payloads(0x301, t0)]


def test_cam_in_follows_the_master_encoder_and_cam_out_stops():
    b = bench()
    mc = b.drive.mc
    start_pos = mc.dem_p
    t0 = b.plc.time_ns
    r = b.fb("CAMSEL").run(CAMTABLE=CAM_ID, CAM=1, MASTERSTART=0, PERIODIC=True)
    assert r.done and r["CAMTABLEID"] == 1, r
    assert mc.params[U.P_CAM_MODE].ram == 1                             # periodic: modulo cam length
    cam_in = b.fb("CAMIN")
    cam_in.start(CAMTABLEID=1, MASTERSTART=0, MASTERLENGTH=LENGTH)
    b.sim.run_until(lambda: cam_in["INSYNC"] or cam_in["ERROR"], max_scans=100)
    assert cam_in["INSYNC"] and cam_in["BUSY"], (cam_in["ERRORID"], cam_in["DRIVEERROR"])
    assert heads(b, t0) == [0x002, 0x111, 0x116, 0x100]
    # the conveyor turns: 1.5 revolutions at 10 000 counts/s
    t1 = b.bus.now
    mc.encoder.drive_with(SpeedProfile([(t1, 10_000)]), t1)
    pulses = []
    for _ in range(1200):
        b.step(1)
        if cam_in["ENDOFPROFILE"]:
            pulses.append(mc.encoder.counts(b.bus.now))
    # one cycle end (8000 counts, at 0.8 s), seen within two SDO reads of the master count (1BA0h)
    assert len(pulses) == 1 and 8000 <= pulses[0] <= 8000 + 10_000 * 0.010, pulses
    samples = mc.trajectory.between(t1 + 2 * MS, b.bus.now)
    assert len(samples) > 100
    for s in samples:
        assert s.demand == pytest.approx(cam_at(mc.encoder.counts(s.t_ns), 0, start_pos), abs=1e-3)
    assert max(s.demand for s in samples) - start_pos == pytest.approx(80 * MM, abs=200)   # the top, 80 mm
    assert cam_in["INSYNC"] and not cam_in["ERROR"]
    r = b.fb("CAMOUT").run()
    assert r.done, r
    assert cam_in["COMMANDABORTED"] and not cam_in["INSYNC"] and not cam_in["BUSY"]
    assert mc.trajectory.samples[-1].demand_velocity == 0


def test_cam_select_of_a_missing_curve_is_the_drive_error():
    b = bench()
    r = b.fb("CAMSEL").run(CAMTABLE=9, CAM=2)
    assert r.error and r.error_id == E["DriveError"] and r["DRIVEERROR"] == 0x0062


def test_cam_refusals_before_any_frame():
    b = bench()
    t0 = b.plc.time_ns
    r = b.fb("CAMSEL").run(CAMTABLE=0, max_scans=5)
    assert r.error and r.error_id == E["InvalidCurveId"]
    r = b.fb("CAMSEL").run(CAMTABLE=CAM_ID, CAM=3, max_scans=5)
    assert r.error and r.error_id == E["InvalidMode"]
    f = b.fb("CAMIN")
    f.start(CAMTABLEID=0)
    b.step(2)
    assert f["ERROR"] and f["ERRORID"] == E["InvalidMode"]
    assert b.payloads(0x301, t0) == [] and b.payloads(0x401, t0) == []
