"""The moving drive served in real time on a python-can bus (drive.attach, `linmot-st emulate`): an independent
CANopen master, python canopen's PDO support with the drive's EDS, enables, homes and moves the axis."""

from __future__ import annotations

import struct
import time
import uuid

import can
import canopen
import pytest

from linmot_st.emulator import DriveTimings, E1100Drive, load_profile
from linmot_st.emulator.cia301.eds import SHIPPED_EDS

OD = canopen.import_od(str(SHIPPED_EDS), node_id=1)


def _od_with_pdo_description() -> canopen.ObjectDictionary:
    """The drive's EDS plus what the master has to describe itself: the E1100 maps its PDOs with LinMot
    parameters, so its EDS lists no PDO communication or mapping objects (docs/emulator.md section 9) and no
    objects for the motion command interface. canopen's PDO classes need them in the OD to create their maps;
    nothing here is read from or written to the drive."""
    from canopen.objectdictionary import INTEGER16, UNSIGNED8, UNSIGNED16, UNSIGNED32, ODRecord, ODVariable

    od = canopen.import_od(str(SHIPPED_EDS), node_id=1)
    # 16-bit views of the words the PDOs carry (the EDS describes each UPID's value as 32 bits: SDO access)
    words = [("Motion Cmd Header", UNSIGNED16), ("Par Word 0", UNSIGNED16), ("Par Word 1", UNSIGNED16),
             ("Par Word 2", UNSIGNED16), ("Slave Header", UNSIGNED16), ("Par Word 3", UNSIGNED16),
             ("Cmd Status", UNSIGNED16), ("Status Word", UNSIGNED16), ("State Var", UNSIGNED16),
             ("Logged Error Code", UNSIGNED16), ("Warn Word", UNSIGNED16), ("Actual Position 16 Bit", INTEGER16),
             ("Demand Current", INTEGER16), ("Demand Position 16 Bit", INTEGER16), ("Control Word", UNSIGNED16)]
    for k, (name, dt) in enumerate(words):
        var = ODVariable(name, 0x5F00 + k, 0)
        var.data_type = dt
        od.add_object(var)
    for base in (0x1400, 0x1600, 0x1800, 0x1A00):
        for n in range(3):
            rec = ODRecord(f"PDO {base + n:04X}h", base + n)
            for sub, dt in ((0, UNSIGNED8), (1, UNSIGNED32 if base in (0x1400, 0x1800) else UNSIGNED32),
                            (2, UNSIGNED8 if base in (0x1400, 0x1800) else UNSIGNED32)):
                var = ODVariable(f"sub {sub}", base + n, sub)
                var.data_type = dt
                rec.add_member(var)
            od.add_object(rec)
    return od


@pytest.fixture
def served():
    channel = f"motion-{uuid.uuid4().hex[:8]}"
    drive_bus = can.Bus(interface="virtual", channel=channel)
    net = canopen.Network()
    net.NOTIFIER_CYCLE = 0.05
    net.connect(interface="virtual", channel=channel)
    node = net.add_node(1, _od_with_pdo_description())
    drive = E1100Drive(1, load_profile().with_defaults({0x1194: 2}), timings=DriveTimings.fast())
    drive.attach(drive_bus)
    yield drive, net, node
    drive.detach()
    net.disconnect()
    drive_bus.shutdown()


def _map(pdo, cob_id: int, entries) -> None:
    pdo.clear()
    for index, sub in entries:
        pdo.add_variable(index, sub, 16)
    pdo.cob_id = cob_id
    pdo.enabled = True


def _wait(predicate, timeout_s: float = 10.0) -> bool:
    end = time.monotonic() + timeout_s
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.005)
    return predicate()


def test_canopen_pdos_enable_home_and_move(served):
    drive, net, node = served
    assert _wait(lambda: drive.booted)
    # TxPDO1: status word, state var, logged error, warn word
    _map(node.tpdo[1], 0x181, [(0x5F07, 0), (0x5F08, 0), (0x5F09, 0), (0x5F0A, 0)])
    # TxPDO2: command status, actual position 16 bit, demand current, demand position 16 bit
    _map(node.tpdo[2], 0x281, [(0x5F06, 0), (0x5F0B, 0), (0x5F0C, 0), (0x5F0D, 0)])
    for n in (1, 2):
        node.tpdo[n].subscribe()
    _map(node.rpdo[1], 0x201, [(0x5F0E, 0)])
    _map(node.rpdo[2], 0x301, [(0x5F00, 0), (0x5F01, 0), (0x5F02, 0), (0x5F03, 0)])
    _map(node.rpdo[3], 0x401, [(0x5F04, 0), (0x5F05, 0)])
    node.nmt.state = "OPERATIONAL"
    tx1, tx2, rx1, rx2, rx3 = node.tpdo[1], node.tpdo[2], node.rpdo[1], node.rpdo[2], node.rpdo[3]

    def state_var() -> int:
        return tx1[1].raw

    def control(word: int) -> None:
        rx1[0].raw = word
        rx1.transmit()

    assert _wait(lambda: tx1.is_received and state_var() >> 8 == 1)
    control(0x003E)
    control(0x003F)
    assert _wait(lambda: state_var() >> 8 == 8), hex(state_var())
    assert tx1[0].raw & 0x0001                                     # status word: operation enabled
    control(0x083F)
    assert _wait(lambda: state_var() == 0x090F)
    control(0x003F)
    assert _wait(lambda: state_var() & 0x80)                        # homed
    # VAI 16 bit go to 50 mm at 1 m/s, 10 m/s^2 ([CO1100] 14), count 1
    for k, v in enumerate((0x0901, 500, 1000, 100)):
        rx2[k].raw = v
    rx3[0].raw, rx3[1].raw = 0x0901, 100
    rx2.transmit()
    rx3.transmit()
    assert _wait(lambda: tx2[0].raw == 0x0901 and state_var() & 0x4F == 0x41)      # echo, in target
    assert tx2[3].raw == 500                                        # demand position 16 bit, 0.1 mm
    assert _wait(lambda: tx2[1].raw == 500)                         # the actual one, once settled
    with drive.lock:
        assert abs(drive.mc.axis.position - 500_000) < 1000
    assert node.sdo[0x3B8D][1].raw == pytest.approx(500_000, abs=1000)   # actual position 1B8Dh by SDO


def test_emulate_command_serves_pdos():
    """`linmot-st emulate` (in-process, virtual bus): the served drive answers RxPDO1 with its TxPDO1."""
    import threading

    from linmot_st.cli import main as cli_main

    def emulate_main(args):
        return cli_main(["emulate", *args])

    channel = f"emu-{uuid.uuid4().hex[:8]}"
    bus = can.Bus(interface="virtual", channel=channel)
    t = threading.Thread(target=emulate_main, args=(["--interface", "virtual", "--channel", channel, "--fast",
                                                     "--duration", "4"],), daemon=True)
    t.start()
    try:
        deadline = time.monotonic() + 5
        boot = None
        while time.monotonic() < deadline and boot is None:
            msg = bus.recv(timeout=0.5)
            if msg is not None and msg.arbitration_id == 0x701:
                boot = msg
        assert boot is not None
        bus.send(can.Message(arbitration_id=0x000, data=b"\x01\x01", is_extended_id=False))
        bus.send(can.Message(arbitration_id=0x201, data=struct.pack("<H", 0x003E), is_extended_id=False))
        states = []
        deadline = time.monotonic() + 3
        while time.monotonic() < deadline and 2 not in states:
            msg = bus.recv(timeout=0.5)
            if msg is not None and msg.arbitration_id == 0x181:
                states.append(struct.unpack("<HHHH", msg.data)[1] >> 8)
        # the default drive has no motor: setup error 3; a motor-less drive does not leave it
        assert states and set(states) <= {3}
    finally:
        t.join(timeout=10)
        bus.shutdown()
