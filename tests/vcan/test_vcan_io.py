"""A triggered move on a real Linux SocketCAN stack (vcan0): `linmot-st emulate` with an input signal
(--signal, a rising edge on the trigger input X4.6) and a profile with a motor and trigger mode direct; the
test is the CANopen master with raw python-can frames. Runs inside the User-Mode Linux guest
(linmot_st_vcan.pytest_plugin; docs/bus.md "A real SocketCAN stack"); skips where there is none."""

from __future__ import annotations

import json
import struct
import time
from pathlib import Path

import can
import pytest

from linmot_st.emulator.linmot.profile import DEFAULT_PROFILE
from linmot_st_vcan.testing import EmulatedDrives

pytestmark = pytest.mark.socketcan

EDGE_S = 8.0            # the trigger input rises 8 s after the drive's power-on: it is homed and armed by then


def _profile(tmp: Path, defaults: dict[int, int]) -> Path:
    """The default E1100 profile with other parameter defaults (a copy of its parameter table)."""
    spec = json.loads(DEFAULT_PROFILE.read_text())
    rows = []
    for line in (DEFAULT_PROFILE.parent / spec["parameter_file"]).read_text().splitlines():
        cells = line.split(",")
        if line and not line.startswith(("#", "upid,")) and int(cells[0], 16) in defaults:
            cells[5] = str(defaults[int(cells[0], 16)])
        rows.append(",".join(cells))
    (tmp / "parameters.csv").write_text("\n".join(rows) + "\n")
    spec["parameter_file"] = "parameters.csv"
    spec["error_text_file"] = str(DEFAULT_PROFILE.parent / spec["error_text_file"])
    path = tmp / "profile.json"
    path.write_text(json.dumps(spec))
    return path


def test_triggered_move_on_vcan0(tmp_path):
    profile = _profile(tmp_path, {0x1194: 2, 0x170C: 1, 0x14BE: 500_000, 0x14BF: 1_000_000, 0x14C0: 1_000_000})
    args = ("--profile", str(profile), "--signal", f"{EDGE_S} X4.6 1")
    with can.Bus(interface="socketcan", channel="vcan0") as bus, \
            EmulatedDrives([1], tmp_path, extra_args=args) as drives:
        t_boot = time.monotonic()

        def send(can_id: int, data: bytes) -> None:
            bus.send(can.Message(arbitration_id=can_id, data=data, is_extended_id=False))

        def wait_state_var(pred, timeout_s: float = 5.0) -> int | None:
            end = time.monotonic() + timeout_s
            while time.monotonic() < end:
                msg = bus.recv(timeout=0.1)
                if msg is not None and msg.arbitration_id == 0x181:
                    sv = struct.unpack_from("<H", msg.data, 2)[0]
                    if pred(sv):
                        return sv
            return None

        send(0x000, b"\x01\x01")                                           # NMT start
        send(0x201, struct.pack("<H", 0x003E))
        send(0x201, struct.pack("<H", 0x003F))
        assert wait_state_var(lambda sv: sv >> 8 == 8), drives.logs()
        send(0x201, struct.pack("<H", 0x083F))
        assert wait_state_var(lambda sv: sv == 0x090F, 10), drives.logs()
        send(0x201, struct.pack("<H", 0x003F))
        # Predef VAI Go To Pos On Rising Trigger Event (02Axh), 30 mm, count 1
        frame = struct.pack("<Hi", 0x02A1, 300_000).ljust(8, b"\0")
        send(0x301, frame)
        send(0x401, frame[:2] + b"\0\0")
        assert wait_state_var(lambda sv: sv & 0xFF == 0x91), drives.logs()    # count 1, armed (bit 4), homed
        assert time.monotonic() - t_boot < EDGE_S - 1, "too slow to arm before the edge"
        # TxPDO2's actual position (16 bit, 0.1 mm) stays 0 until the edge, then reaches 30 mm
        end = t_boot + EDGE_S + 5
        moved_at = None
        while time.monotonic() < end and moved_at is None:
            msg = bus.recv(timeout=0.1)
            if msg is not None and msg.arbitration_id == 0x281 and struct.unpack_from("<h", msg.data, 2)[0] == 300:
                moved_at = time.monotonic()
        assert moved_at is not None and moved_at - t_boot > EDGE_S - 1, drives.logs()
    assert drives.clean_exit() == ""
