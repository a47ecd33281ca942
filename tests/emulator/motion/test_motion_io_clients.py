"""The drive's I/O from outside (issue 20 sections 2 and 4): an independent CANopen master (python canopen's PDO
support, python-can's virtual bus) sends a triggered move that runs when the trigger input rises; the rig of the
pytest plugin and `linmot-st emulate` set inputs (an input script, --signal); the parser of input scripts."""

from __future__ import annotations

import struct
import threading
import time
import uuid

import can
import canopen
import pytest
from test_motion_realtime import _map, _od_with_pdo_description, _wait

from linmot_st.emulator import DriveIO, DriveTimings, E1100Drive, load_profile
from linmot_st.emulator.linmot.io_script import ScriptError, apply_line, apply_script

MS = 1_000_000


@pytest.fixture
def served():
    channel = f"io-{uuid.uuid4().hex[:8]}"
    drive_bus = can.Bus(interface="virtual", channel=channel)
    net = canopen.Network()
    net.NOTIFIER_CYCLE = 0.05
    net.connect(interface="virtual", channel=channel)
    node = net.add_node(1, _od_with_pdo_description())
    profile = load_profile().with_defaults({0x1194: 2, 0x170C: 1, 0x14BE: 500_000, 0x14BF: 1_000_000,
                                            0x14C0: 1_000_000})
    drive = E1100Drive(1, profile, timings=DriveTimings.fast())
    drive.attach(drive_bus)
    yield drive, net, node
    drive.detach()
    net.disconnect()
    drive_bus.shutdown()


def test_python_canopen_sends_a_triggered_move(served):
    drive, net, node = served
    assert _wait(lambda: drive.booted)
    _map(node.tpdo[1], 0x181, [(0x5F07, 0), (0x5F08, 0), (0x5F09, 0), (0x5F0A, 0)])
    _map(node.tpdo[2], 0x281, [(0x5F06, 0), (0x5F0B, 0), (0x5F0C, 0), (0x5F0D, 0)])
    for n in (1, 2):
        node.tpdo[n].subscribe()
    _map(node.rpdo[1], 0x201, [(0x5F0E, 0)])
    _map(node.rpdo[2], 0x301, [(0x5F00, 0), (0x5F01, 0), (0x5F02, 0), (0x5F03, 0)])
    _map(node.rpdo[3], 0x401, [(0x5F04, 0), (0x5F05, 0)])
    node.nmt.state = "OPERATIONAL"
    tx1, tx2, rx1, rx2, rx3 = node.tpdo[1], node.tpdo[2], node.rpdo[1], node.rpdo[2], node.rpdo[3]

    def control(word: int) -> None:
        rx1[0].raw = word
        rx1.transmit()

    assert _wait(lambda: tx1.is_received and tx1[1].raw >> 8 == 1)
    control(0x003E)
    control(0x003F)
    assert _wait(lambda: tx1[1].raw >> 8 == 8), hex(tx1[1].raw)
    control(0x083F)
    assert _wait(lambda: tx1[1].raw == 0x090F)
    control(0x003F)
    assert _wait(lambda: tx1[1].raw & 0x80)
    # Predef VAI Go To Pos On Rising Trigger Event (02Axh) to 30 mm, count 1: armed, nothing moves
    target = 300_000
    for k, v in enumerate((0x02A1, target & 0xFFFF, target >> 16, 0)):
        rx2[k].raw = v
    rx3[0].raw, rx3[1].raw = 0x02A1, 0                       # the slave header completes the command
    rx2.transmit()
    rx3.transmit()
    assert _wait(lambda: tx2[0].raw == 0x02A1 and tx1[0].raw & 0x0100)      # echoed; status bit 8: armed
    time.sleep(0.2)
    with drive.lock:
        assert drive.mc.events.fired == [] and abs(drive.mc.axis.position) < 1
        now = drive.clock_now_ns()
        drive.io.set_input("X4.6", 1, now + 50 * MS)
    assert _wait(lambda: tx2[1].raw == 300)                                   # actual position 16 bit, 0.1 mm
    with drive.lock:
        assert len(drive.mc.events.fired) == 1
        assert now + 50 * MS < drive.mc.events.fired[0] <= now + 51 * MS          # within one MC cycle


def test_emulate_serves_the_inputs_of_its_script(tmp_path):
    """`linmot-st emulate --input FILE --signal LINE` (in process, virtual bus): the drive's X4 input word
    (1DA0h) and analog value (1DA3h) read by SDO follow the script."""
    from linmot_st.cli import main as cli_main

    script = tmp_path / "inputs.txt"
    script.write_text("# the home switch closes at 0.1 s\n0.1 X4.7 1\n0.2 X4.4 2.5   # volts\n")
    channel = f"emu-{uuid.uuid4().hex[:8]}"
    bus = can.Bus(interface="virtual", channel=channel)
    rc = []
    t = threading.Thread(target=lambda: rc.append(cli_main(
        ["emulate", "--interface", "virtual", "--channel", channel, "--fast", "--duration", "4",
         "--input", str(script), "--signal", "0.3 X4.6 1"])), daemon=True)
    t.start()

    def sdo_read(index: int) -> int | None:
        bus.send(can.Message(arbitration_id=0x601, data=bytes([0x40, index & 0xFF, index >> 8, 1, 0, 0, 0, 0]),
                             is_extended_id=False))
        end = time.monotonic() + 2
        while time.monotonic() < end:
            msg = bus.recv(timeout=0.2)
            if msg is not None and msg.arbitration_id == 0x581:
                return struct.unpack_from("<i", bytes(msg.data), 4)[0]
        return None

    try:
        end = time.monotonic() + 5
        while time.monotonic() < end:
            msg = bus.recv(timeout=0.5)
            if msg is not None and msg.arbitration_id == 0x701:
                break
        time.sleep(0.5)                               # past every signal of the script
        assert sdo_read(0x3DA0) == (1 << 4) | (1 << 3)          # X4.7 (bit 4) and X4.6 (bit 3)
        assert sdo_read(0x3DA3) == 2500                          # mV
    finally:
        t.join(timeout=10)
        bus.shutdown()
    assert rc == [0]


def test_emulate_refuses_a_bad_input_script(tmp_path, capsys):
    from linmot_st.cli import main as cli_main

    rc = cli_main(["emulate", "--interface", "virtual", "--channel", "x", "--signal", "1.0 X9.9 1"])
    assert rc == 2 and "X9.9" in capsys.readouterr().err


def test_input_script_lines():
    io = DriveIO()
    assert apply_script(io, "# a comment\n\n0.5 X4.6 1\npulse X4.5 1.0 0.1 0.02 3\nramp 2 3 0 10 10\n") == 3
    io.on_timer(4_000_000_000)
    assert io.input("X4.6") == 1 and io.input("X4.5") == 0 and io.analog() == 10.0
    assert [c.t_ns for c in io.changes if c.name == "X4.5"] == [1_000_000_000, 1_020_000_000, 1_100_000_000,
                                                                1_120_000_000, 1_200_000_000, 1_220_000_000]
    for bad in ("1.0 X4.6", "pulse X4.6 1 0.1 0.2 3", "x X4.6 1", "1.0 X4.4"):
        with pytest.raises(ScriptError):
            apply_line(io, bad, 5_000_000_000)


def test_the_rig_sets_and_reads_drive_inputs(station):
    """The pytest plugin's rig (examples/user_project's station): an input set at a rig time changes then, in
    step with the PLC's scans, and is recorded beside the drive's trajectory."""
    from linmot_st.plctest import Rig

    rig = Rig(station, timings="fast")
    rig.set_input("X4.6", 1, at_ms=5.5)
    rig.set_input("X4.4", 7.5, at_ms=8)
    rig.step(5)
    assert rig.io().input("X4.6") == 0
    rig.step(5)
    assert rig.io().input("X4.6") == 1 and rig.io(1).analog() == 7.5
    assert rig.drive.mc.trajectory.io_at("X4.6", 5_500_000) == 1
    assert rig.drive.mc.trajectory.io_at("X4.6", 5_499_999) is None
    rig.set_input("X4.6", 0)                                   # now
    rig.step(1)
    assert rig.io().input("X4.6") == 0


def test_the_real_time_rig_sets_an_input_now(station):
    from linmot_st.plctest import RealTimeRig

    with RealTimeRig(station) as rig:
        rig.step(5)
        rig.set_input("X4.7", 1)
        with pytest.raises(ValueError):
            rig.set_input("X4.7", 0, at_ms=100)
        assert _wait(lambda: rig.io().input("X4.7") == 1, 2.0)
