"""An independent client: python canopen's SDO client and raw python-can frames against the drive served
in real time on python-can's in-process `virtual` bus (drive.attach), plus the EDS and the CLI."""

from __future__ import annotations

import struct
import threading
import time
import uuid

import can
import canopen
import pytest

from linmot_st.emulator import DriveTimings, E1100Drive, load_profile
from linmot_st.emulator.cia301.eds import SHIPPED_EDS, generate_eds

FAST = DriveTimings.fast()
OD = canopen.import_od(str(SHIPPED_EDS), node_id=1)      # loaded once: the EDS has a record per UPID


def _channel() -> str:
    return f"emu-{uuid.uuid4().hex[:8]}"


def _network(channel: str) -> canopen.Network:
    net = canopen.Network()
    net.NOTIFIER_CYCLE = 0.05                 # so that disconnect() does not wait a second
    return net.connect(interface="virtual", channel=channel)


@pytest.fixture
def served():
    """A drive attached to a fresh virtual channel, a canopen network with the drive as RemoteNode (EDS),
    and a raw python-can bus on the same channel."""
    channel = _channel()
    drive_bus = can.Bus(interface="virtual", channel=channel)
    raw = can.Bus(interface="virtual", channel=channel)
    net = _network(channel)
    node = net.add_node(1, OD)
    node.sdo.RESPONSE_TIMEOUT = 2.0
    drive = E1100Drive(1, timings=FAST)
    drive.attach(drive_bus)
    boot = raw.recv(timeout=2.0)
    assert boot is not None and (boot.arbitration_id, bytes(boot.data)) == (0x701, b"\x00")
    yield drive, node, raw
    drive.detach()
    net.disconnect()
    raw.shutdown()
    drive_bus.shutdown()


def raw_exchange(raw: can.Bus, data: bytes, node_id: int = 1, timeout: float = 2.0) -> bytes | None:
    raw.send(can.Message(arbitration_id=0x600 + node_id, data=data, is_extended_id=False))
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        msg = raw.recv(timeout=max(0.0, deadline - time.monotonic()))
        if msg is not None and msg.arbitration_id == 0x580 + node_id:
            return bytes(msg.data)
    return None


def test_canopen_client_reads_and_writes_parameters(served):
    drive, node, _ = served
    assert node.sdo.upload(0x1018, 1) == struct.pack("<I", 0x156)
    assert node.sdo[0x1008].raw == "1941"
    assert node.sdo[0x33A2][1].raw == 9
    node.sdo[0x33A2][1].raw = 1234                      # live: RAM write
    node.sdo[0x33A2][2].raw = 4321                      # ROM write
    with drive.lock:
        assert (drive.ram(0x13A2), drive.rom(0x13A2)) == (1234, 4321)
    assert node.sdo[0x3505][1].raw == -5                # SINT8, sign-extended, INTEGER32 in the EDS
    assert node.sdo[0x2561][1].raw == 4612              # MC tree ID
    node.sdo[0x346E][2].raw = -100000                   # SINT32 negative
    with drive.lock:
        assert drive.rom(0x146E) == -100000


@pytest.mark.parametrize("index, sub, value, code", [
    (0x3001, 1, None, 0x06020000),                      # unknown UPID
    (0x3194, 7, None, 0x06090011),                      # unknown sub-index
    (0x2539, 2, 1, 0x06010002),                         # read-only
    (0x3194, 1, 2, 0x06010002),                         # RAM of a non-live parameter
    (0x3194, 2, 0x8000, 0x06090030),                    # out of range
    (0x33A2, 6, None, 0x06010001),                      # read of a write-only service
    (0x2000, 0x21, None, 0x08000022),                   # next UPID without start
])
def test_canopen_client_sees_abort_codes(served, index, sub, value, code):
    _, node, _ = served
    with pytest.raises(canopen.SdoAbortedError) as exc:
        if value is None:
            node.sdo.upload(index, sub)
        else:
            node.sdo.download(index, sub, struct.pack("<i", value))
    assert exc.value.code == code


def test_canopen_segmented_transfers():
    channel = _channel()
    drive_bus = can.Bus(interface="virtual", channel=channel)
    net = _network(channel)
    node = net.add_node(1, OD)
    drive = E1100Drive(1, load_profile().with_identity(device_name="LinMot E1100-CO-HC emulated"), FAST)
    drive.attach(drive_bus)
    try:
        time.sleep(0.1)
        assert node.sdo.upload(0x1008, 0) == b"LinMot E1100-CO-HC emulated"        # segmented upload
        node.sdo.download(0x1017, 0, struct.pack("<H", 500), force_segment=True)    # segmented download
        assert node.sdo[0x1017].raw == 500
    finally:
        drive.detach()
        net.disconnect()
        drive_bus.shutdown()


def test_raw_frames_of_the_spec_on_the_virtual_bus(served):
    _, _, raw = served
    pairs = [
        ("23 01 20 50 46 00 A4 00", "60 01 20 50 00 00 00 00"),
        ("23 01 20 51 00 00 46 00", "60 01 20 51 00 00 04 00"),
        ("23 01 20 52 00 00 10 27", "60 01 20 52 00 00 04 00"),
        ("23 01 20 53 00 2D 31 01", "60 01 20 53 00 00 04 00"),
        ("23 00 20 20 00 00 00 10", "60 00 20 20 00 00 04 00"),
        ("40 00 20 21 00 00 00 00", "43 00 20 21 0D 00 04 10"),
        ("40 64 20 74 00 00 00 00", "43 64 20 74 43 66 67 20"),
        ("40 00 20", "80 00 20 00 00 00 00 08"),                      # short DLC: abort
        ("E0 00 20 00 00 00 00 00", "80 00 20 00 01 00 04 05"),       # unknown command specifier: abort
    ]
    for request, response in pairs:
        assert raw_exchange(raw, bytes.fromhex(request)) == bytes.fromhex(response), request


def test_curve_download_through_canopen_and_flash_save(served):
    drive, node, _ = served
    from linmot_st.emulator import Curve
    curve = Curve.build(12, list(range(0, 50_000, 1_000)), name="ramp")
    sdo = node.sdo

    def result(sub, payload):      # canopen's client ignores the E1100 result in byte 6: the drive state tells
        sdo.download(0x2000 + 12, sub, payload)

    result(0x50, struct.pack("<HH", 70, len(curve.data)))
    info = curve.info + b"\0\0"
    for k in range(0, 72, 4):
        result(0x54, info[k:k + 4])
    for k in range(0, len(curve.data), 4):
        result(0x53, curve.data[k:k + 4])
    with drive.lock:
        assert drive.curves.ram[12] == curve
    sdo.download(0x2000, 0x35, bytes(4))                                  # stop MC (answered when stopped)
    sdo.download(0x2000, 0x40, bytes(4))                                  # save
    deadline = time.monotonic() + 2
    while sdo.upload(0x2000, 0x42)[0] == 4 and time.monotonic() < deadline:
        time.sleep(0.005)
    with drive.lock:
        assert drive.curves.flash[12] == curve
    sdo.download(0x2000, 0x36, bytes(4))
    assert struct.unpack("<BBH", sdo.upload(0x200C, 0x60)) == (0, 70, len(curve.data))


def test_reset_over_the_bus_and_boot_up(served):
    drive, node, raw = served
    node.sdo[0x33A2][2].raw = 77
    raw.send(can.Message(arbitration_id=0x000, data=bytes([0x81, 0x01]), is_extended_id=False))
    deadline = time.monotonic() + 2
    boot = None
    while time.monotonic() < deadline:
        msg = raw.recv(timeout=0.1)
        if msg is not None and msg.arbitration_id == 0x701:
            boot = bytes(msg.data)
            break
    assert boot == b"\x00"
    assert node.sdo[0x33A2][1].raw == 77


def test_shipped_eds_is_current_and_loads():
    text = generate_eds()
    assert SHIPPED_EDS.read_text(encoding="ascii").replace("\r\n", "\n") == text, \
        "regenerate: python -m linmot_st.emulator.cia301.eds"
    od = canopen.import_od(str(SHIPPED_EDS), node_id=1)
    drive = E1100Drive(1)
    assert od.device_information.vendor_number == 0x156
    # every UPID is an object; every sub the EDS lists is one the server answers (and the reverse for services)
    for p in drive.params:
        assert (0x2000 + p.upid in od) == (p.upid <= 0x3FFF)      # 6300h lies beyond the 2000h+UPID window
    for index in range(0x2000, 0x2100):
        services = {s.sub for s in drive.mfr.subs_at(index)}
        listed = {v.subindex for v in od[index].values()} if index in od else set()
        upid = index - 0x2000
        if upid in drive.params:
            continue
        assert listed == services | {0}, hex(index)
    assert od[0x33A2][1].default == 9 and od[0x33A2][1].access_type == "rw"
    assert od[0x3194][1].access_type == "ro" and od[0x3194][2].access_type == "rw"   # non-live
    assert od[0x1018][1].default == 0x156 and od[0x1017].access_type == "rw"
    assert 0x1400 not in od                                      # no mapping objects: comm objects not listed


def test_emulate_cli_serves_on_a_virtual_bus():
    from linmot_st.cli import main

    channel = _channel()
    raw = can.Bus(interface="virtual", channel=channel)
    rc: list[int] = []
    t = threading.Thread(target=lambda: rc.append(main(["emulate", "--interface", "virtual", "--channel", channel,
                                                          "--node-id", "3", "--fast", "--duration", "1.5"])))
    t.start()
    try:
        msg = raw.recv(timeout=2.0)
        assert msg is not None and (msg.arbitration_id, bytes(msg.data)) == (0x703, b"\x00")
        assert raw_exchange(raw, bytes.fromhex("40 18 10 01 00 00 00 00"), node_id=3) == \
            bytes.fromhex("43 18 10 01 56 01 00 00")
    finally:
        t.join(5)
        raw.shutdown()
    assert rc == [0]
