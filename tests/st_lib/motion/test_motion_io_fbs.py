"""MC_WriteDigitalOutput / MC_ReadDigitalOutput / MC_ReadDigitalInput and MC_TouchProbe / MC_AbortTrigger
(st_lib/motion/io.st) against the emulated E1100's I/O (emulator/linmot/io.py): an output set and cleared by bit
with the mask command (003xh / 004xh) and the others kept, the levels read back by SDO, an input the test drives,
a capture on X4.5 during a move, a probe ended by AbortTrigger (and 008xh sent), refusals before any frame."""

from __future__ import annotations

import struct

import pytest

from linmot_st.protocol.errors import BY_NAME
from motionbench import MM, MotionBench

E = {name: e.value for name, e in BY_NAME.items()}
MS = 1_000_000


def bench() -> MotionBench:
    return MotionBench(nodes=1).ready()


def test_write_outputs_by_bit_and_read_them_back():
    b = bench()
    io = b.drive.io
    t0 = b.plc.time_ns
    assert b.fb("WDO").run(CONNECTOR="LM_IO_X4", OUTPUTNUMBER=0, VALUE=True).done          # X4.3
    assert b.fb("WDO").run(CONNECTOR="LM_IO_X4", OUTPUTNUMBER=5, VALUE=True).done          # X4.8
    assert io.output("X4.3") == 1 and io.output("X4.8") == 1 and io.outputs("X4") == 0b100001
    assert b.fb("WDO").run(CONNECTOR="LM_IO_X4", OUTPUTNUMBER=0, VALUE=False).done
    assert io.outputs("X4") == 0b100000                                                      # X4.8 kept
    assert b.fb("WDO").run(CONNECTOR="LM_IO_X6", OUTPUTNUMBER=15, VALUE=True).done
    assert io.outputs("X6") == 0x8000
    frames = b.payloads(0x301, t0)
    assert [struct.unpack_from("<HHH", f) for f in frames] == [
        (0x0031, 0x0001, 0x0001), (0x0032, 0x0020, 0x0020), (0x0033, 0x0001, 0x0000), (0x0044, 0x8000, 0x8000)]
    b["RDO.CONNECTOR"] = "LM_IO_X4"
    b["RDO.OUTPUTNUMBER"] = 5
    b["RDO.ENABLE"] = True
    b.sim.run_until(lambda: b["RDO.VALID"], max_scans=200)
    assert b["RDO.VALUE"]
    b["RDO.OUTPUTNUMBER"] = 0
    b.step(30)
    assert not b["RDO.VALUE"]
    b["RDO.CONNECTOR"] = "LM_IO_X6"
    b["RDO.OUTPUTNUMBER"] = 15
    b.step(30)
    assert b["RDO.VALUE"]


def test_read_an_input_the_machine_drives():
    b = bench()
    b["RDI.INPUTNUMBER"] = 4                                   # X4.7 (home switch pin, a general input here)
    b["RDI.ENABLE"] = True
    b.sim.run_until(lambda: b["RDI.VALID"], max_scans=200)
    assert not b["RDI.VALUE"]
    b.drive.io.set_input("X4.7", 1)
    b.step(30)
    assert b["RDI.VALUE"]
    b.drive.io.set_input("X4.7", 0)
    b.step(30)
    assert not b["RDI.VALUE"]


def test_io_numbers_out_of_range_refused_before_any_frame():
    b = bench()
    t0 = b.plc.time_ns
    r = b.fb("WDO").run(CONNECTOR="LM_IO_X4", OUTPUTNUMBER=9, VALUE=True, max_scans=5)
    assert r.error and r.error_id == E["InvalidIoNumber"]
    r = b.fb("WDO").run(CONNECTOR="LM_IO_X6", OUTPUTNUMBER=16, VALUE=True, max_scans=5)
    assert r.error and r.error_id == E["InvalidIoNumber"]
    assert b.payloads(0x301, t0) == []
    b["RDI.INPUTNUMBER"] = 10
    b["RDI.ENABLE"] = True
    b.step(3)
    assert b["RDI.ERROR"] and b["RDI.ERRORID"] == E["InvalidIoNumber"] and b.sdo_trace(since_ns=t0) == []


def test_touch_probe_records_the_position_of_the_capture_edge():
    b = bench()
    probe = b.fb("PROBE")
    probe.start()
    b.step(20)
    assert probe["BUSY"] and not probe["DONE"]
    b.fb("MVA").start(POSITION=100.0, VELOCITY=500.0, ACCELERATION=10000.0, DECELERATION=10000.0)
    b.step(80)
    t_edge = b.bus.now
    b.drive.io.set_input("X4.5", 1, t_edge)
    at_edge = b.drive.mc.axis.position
    b.sim.run_until(lambda: probe["DONE"] or probe["ERROR"], max_scans=200)
    assert probe["DONE"], probe["ERRORID"]
    assert probe["RECORDEDPOSITION"] == pytest.approx(at_edge / MM, abs=0.001)
    assert 10.0 < probe["RECORDEDPOSITION"] < 100.0                 # captured during the move, not at its end


def test_abort_trigger_ends_a_probe_and_clears_the_events():
    b = bench()
    probe = b.fb("PROBE")
    probe.start()
    b.step(20)
    t0 = b.plc.time_ns
    r = b.fb("ABORTTRIG").run()
    assert r.done, r
    b.step(2)
    assert probe["COMMANDABORTED"] and not probe["BUSY"]
    assert [struct.unpack_from("<H", f)[0] >> 4 for f in b.payloads(0x301, t0)] == [0x008]
    b.drive.io.set_input("X4.5", 1)                                # a capture after the abort: nothing
    b.step(30)
    assert not probe["DONE"]
