"""A stream from independent clients: python canopen's PDO support sends a PV stream with SYNC to the drive
served in real time on python-can's virtual bus, and (where a SocketCAN stack runs) to `linmot-st emulate`
on vcan0. Real time: the master's period is 8 ms with the configured-period variant (033xh), so a setpoint may
come up to 4 ms late before the drive's buffer runs dry (0083h)."""

from __future__ import annotations

import math
import time
import uuid

import can
import canopen
import pytest
from test_motion_realtime import _map, _od_with_pdo_description, _wait

from linmot_st.emulator import DriveTimings, E1100Drive, load_profile

PERIOD_S = 0.008
STROKE = 50_000             # 5 mm
N = 76                      # 0.6 s: a cosine from 0 to STROKE


def _setpoint(k: int) -> tuple[int, int]:
    """Position (0.1 um) and velocity (1 um/s) of setpoint k."""
    w = math.pi / ((N - 1) * PERIOD_S)
    tau = k * PERIOD_S
    return round(STROKE * (1 - math.cos(w * tau)) / 2), round(STROKE * w * math.sin(w * tau) / 2 / 10)


def _stream_with_canopen(net: canopen.Network, node, home_offset: int) -> None:
    """Enable, home, then the PV stream (033xh) one setpoint per SYNC, then Stop Streaming (03Fxh)."""
    node.sdo.download(0x1800, 2, bytes([1]))         # TxPDO1/TxPDO2 on every SYNC: RxPDOs taken on SYNC
    node.sdo.download(0x1801, 2, bytes([1]))
    _map(node.tpdo[1], 0x181, [(0x5F07, 0), (0x5F08, 0), (0x5F09, 0), (0x5F0A, 0)])
    _map(node.tpdo[2], 0x281, [(0x5F06, 0), (0x5F0B, 0), (0x5F0C, 0), (0x5F0D, 0)])
    for n in (1, 2):
        node.tpdo[n].subscribe()
    _map(node.rpdo[1], 0x201, [(0x5F0E, 0)])
    _map(node.rpdo[2], 0x301, [(0x5F00, 0), (0x5F01, 0), (0x5F02, 0), (0x5F03, 0)])
    _map(node.rpdo[3], 0x401, [(0x5F04, 0), (0x5F05, 0)])
    node.nmt.state = "OPERATIONAL"
    tx1, rx1, rx2, rx3 = node.tpdo[1], node.rpdo[1], node.rpdo[2], node.rpdo[3]

    def control(word: int) -> None:
        rx1[0].raw = word
        rx1.transmit()

    net.sync.start(PERIOD_S)                          # SYNC while enabling and homing
    try:
        assert _wait(lambda: tx1.is_received and tx1[1].raw >> 8 == 1)
        control(0x003E)
        time.sleep(3 * PERIOD_S)
        control(0x003F)
        assert _wait(lambda: tx1[1].raw >> 8 == 8), hex(tx1[1].raw)
        control(0x083F)
        assert _wait(lambda: tx1[1].raw == 0x090F)
        control(0x003F)
        assert _wait(lambda: tx1[1].raw & 0x80)       # homed
    finally:
        net.sync.stop()

    def send(header: int, words: list[int]) -> None:
        for k, v in enumerate(words[:3]):
            rx2[k + 1].raw = v & 0xFFFF
        rx2[0].raw = header
        rx3[0].raw, rx3[1].raw = header, words[3] & 0xFFFF
        rx2.transmit()
        rx3.transmit()

    t0 = time.monotonic() + 0.05
    for k in range(N + 1):
        count = k % 15 + 1
        if k < N:
            p, v = _setpoint(k)
            p += home_offset
            send(0x0330 | count, [p & 0xFFFF, p >> 16 & 0xFFFF, v & 0xFFFF, v >> 16 & 0xFFFF])
        else:
            send(0x03F0 | count, [0, 0, 0, 0])
        deadline = t0 + k * PERIOD_S
        time.sleep(max(0.0, deadline - time.monotonic()))
        net.sync.transmit()
    time.sleep(0.2)


@pytest.fixture
def served():
    channel = f"stream-{uuid.uuid4().hex[:8]}"
    drive_bus = can.Bus(interface="virtual", channel=channel)
    net = canopen.Network()
    net.NOTIFIER_CYCLE = 0.05
    net.connect(interface="virtual", channel=channel)
    node = net.add_node(1, _od_with_pdo_description())
    node.sdo.RESPONSE_TIMEOUT = 2.0
    drive = E1100Drive(1, load_profile().with_defaults({0x1194: 2, 0x14E6: 8_000}), timings=DriveTimings.fast())
    drive.attach(drive_bus)
    yield drive, net, node
    drive.detach()
    net.disconnect()
    drive_bus.shutdown()


def test_canopen_sends_a_pv_stream_with_sync(served):
    """Real time (fails only when the master's loop is more than half a period late, e.g. on a machine under
    heavy load)."""
    drive, net, node = served
    assert _wait(lambda: drive.booted)
    _stream_with_canopen(net, node, 0)
    with drive.lock:
        mc = drive.mc
        period = round(PERIOD_S * 1e9)
        stamps = [t for t, h, _ in mc.executed if h >> 4 == 0x033]
        failed = [s.t_ns for s in mc.trajectory.samples if s.state in (4, 14)]     # error (quick stop)
        # how late each setpoint reached the drive's thread on the configured timeline (the first one's stamp +
        # k periods), the one that did not come before the drive stopped included
        late = max(t - (stamps[0] + k * period) for k, t in enumerate(stamps + failed[:1]))
        # the first two setpoints' distance (or, where the drive stopped before the second, at least this)
        first_gap = stamps[1] - stamps[0] if len(stamps) >= 2 else (failed[0] - stamps[0] if failed else None)
        if (mc.error_code == 0x0083 and late > period // 2) or (
                mc.error_code in (0x0084, 0x0085) and first_gap is not None
                and not 400_000 <= first_gap <= 10_000_000):
            # the machine did not keep real time (a setpoint more than half a period late, or the first two,
            # sent 8 ms apart, taken outside the 0.4..10 ms that 033xh accepts): the drive's error is its right
            # answer to that
            pytest.skip(f"real time not kept: a setpoint {late / 1e6:.1f} ms late, the first two "
                        f"{(first_gap or 0) / 1e6:.1f} ms apart")
        assert mc.error_code == 0, f"drive error {mc.error_code:04X}h, latest setpoint {late / 1e6:.1f} ms late"
        assert [h >> 4 for _, h, _ in mc.executed].count(0x033) == N
        assert abs(mc.gen.target - STROKE) <= 1 and not mc.status_word & 0x2000      # rests on the last one
        assert abs(mc.axis.position - STROKE) < 100
        demands = [s.demand for s in mc.trajectory.samples if s.demand > 10]
        assert len(demands) > 30 and max(demands) <= STROKE + 1         # a cosine: no overshoot


@pytest.mark.socketcan
def test_canopen_sends_a_pv_stream_on_vcan0(tmp_path):
    """The same stream to `linmot-st emulate` on vcan0 (a drive with a motor: its profile sets 1194h)."""
    import json

    from linmot_st.emulator.linmot.profile import DEFAULT_PROFILE
    from linmot_st_vcan.testing import EmulatedDrives

    # the shipped profile with its parameter table's defaults for 1194h (a motor) and 14E6h (10 ms) changed
    data = DEFAULT_PROFILE.parent
    spec = json.loads(DEFAULT_PROFILE.read_text())
    rows = []
    for line in (data / spec["parameter_file"]).read_text().splitlines():
        cells = line.split(",")
        if cells[0] in ("1194", "14E6"):
            cells[5] = {"1194": "2", "14E6": "8000"}[cells[0]]
        rows.append(",".join(cells))
    (tmp_path / "parameters.csv").write_text("\n".join(rows) + "\n")
    spec["parameter_file"] = str(tmp_path / "parameters.csv")
    spec["error_text_file"] = str(data / spec["error_text_file"])
    profile = tmp_path / "profile.json"
    profile.write_text(json.dumps(spec))
    assert {d.upid: d.default for d in load_profile(profile).all_definitions()}[0x1194] == 2
    with EmulatedDrives([1], tmp_path, extra_args=("--profile", str(profile))) as drives:
        net = canopen.Network()
        net.NOTIFIER_CYCLE = 0.05
        net.connect(interface="socketcan", channel="vcan0")
        try:
            node = net.add_node(1, _od_with_pdo_description())
            node.sdo.RESPONSE_TIMEOUT = 5.0
            _stream_with_canopen(net, node, 0)
            node.nmt.state = "PRE-OPERATIONAL"
            assert node.sdo[0x3D96][1].raw == 0                            # logged error: none
            assert abs(node.sdo[0x3B8D][1].raw - STROKE) < 100             # actual position 1B8Dh
        finally:
            net.disconnect()
    assert drives.clean_exit() == ""
