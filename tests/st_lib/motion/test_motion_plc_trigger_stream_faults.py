"""Issue 22 from the PLC side: a move armed on the trigger (FB_LmMotionCommand with 02Axh, Predef VAI Go To Pos
On Rising Trigger Event) and disarmed with FB_LmAbortTrigger (008xh, Clear Event Evaluation, [MC] 4.3.6) before
its edge moves nothing, even when the edge comes afterwards; FB_LmStream under a lost SYNC and a lost RxPDO
(the simulated bus's drop fault, harness/linmot_st/bus/faults.py) ends in the drive's 0083h (PVT Buffer
Underflow, docs/emulator.md "Streams") on the FB's Error/ErrorID/DriveError, while the same stream without
losses does not."""

from __future__ import annotations

import math

from linmot_st.bus.faults import match_id
from linmot_st.protocol import words as W
from linmot_st.protocol.errors import BY_NAME
from motionbench import MM, MotionBench

E = {name: e.value for name, e in BY_NAME.items()}
MS = 1_000_000
SYNC_COB = 0x080
RXPDO2_COB = 0x301            # node 1's motion command mailbox (the FBs' frames, as tests/st_lib/motion/test_motion_io_fbs.py)


# X4.6 as trigger input (170Ch = 1, docs/emulator.md "Trigger X4.6") and the predefined VAI (14BEh..14C0h:
# 0.5 m/s, 5 m/s^2) the 02Axh runs with
TRIGGER_DEFAULTS = {0x170C: 1, 0x14BE: 500_000, 0x14BF: 500_000, 0x14C0: 500_000}


def _trigger_bench() -> MotionBench:
    return MotionBench(nodes=1, defaults=TRIGGER_DEFAULTS).ready()


def _moved(b: MotionBench, t0: int) -> bool:
    return any(s.status_word & W.SW_MOTION_ACTIVE for s in b.drive.mc.trajectory.between(t0))


def _arm(b: MotionBench, target_mm: float) -> None:
    r = b.fb("CMD").run(CID=0x02A, A=round(target_mm * MM), FOLLOW=False)
    assert r.done, r
    b.step(10)
    assert b.drive.mc.status_word & W.SW_EVENT_HANDLER           # armed in the drive's event handler


def test_an_armed_move_runs_on_its_edge():
    """The control: the same arming without the disarm moves on the edge (so the test below can fail)."""
    b = _trigger_bench()
    p0 = b.drive.mc.axis.position
    _arm(b, 40.0)
    t0 = b.plc.time_ns
    b.step(30)
    assert not _moved(b, t0)                                     # armed: nothing before the edge
    b.drive.io.set_input("X4.6", 1, b.bus.now)
    b.step(400)
    assert _moved(b, t0) and abs(b.drive.mc.axis.position - 40 * MM) < 10 and p0 != 40 * MM


def test_a_move_disarmed_before_its_edge_moves_nothing():
    b = _trigger_bench()
    p0 = b.drive.mc.axis.position
    _arm(b, 40.0)
    t0 = b.plc.time_ns
    r = b.fb("ABORTTRIG").run()
    assert r.done, r
    b.step(5)
    assert not b.drive.mc.status_word & W.SW_EVENT_HANDLER
    b.drive.io.set_input("X4.6", 1, b.bus.now)                   # the edge after the disarm
    b.step(200)
    b.drive.io.set_input("X4.6", 0, b.bus.now)
    b.step(20)
    b.drive.io.set_input("X4.6", 1, b.bus.now)                   # and a second one
    b.step(200)
    assert not _moved(b, t0) and b.drive.mc.axis.position == p0
    assert b.drive.mc.events.fired == []


# --- FB_LmStream under losses (the bench of tests/st_lib/motion/test_motion_stream_fb.py: PV stream at a 2 ms SYNC) ---

STROKE = 10 * MM
DURATION_S = 0.4


def _stream_bench() -> MotionBench:
    b = MotionBench(nodes=1, pdo={"PDOTIMEOUT": 50 * MS})
    b["SYNC.PERIOD"] = 2 * MS
    b["SYNC.ENABLE"] = True
    assert b.fb("SETUP").run(MODE="LM_PDO_SYNC", EVENTTIMERMS=0).done
    assert b.drive.pdo.rx_on_sync
    return b.ready()


def _stream(b: MotionBench, scans: int, fault=None, after_scans: int = 100) -> None:
    """Streams a cosine from the PLC's clock; `fault(bus)` is installed after `after_scans` scans."""
    start = b.drive.mc.axis.position
    t0 = b.plc.time_ns
    w = math.pi / DURATION_S
    b["STRM.CID"] = 0x031
    for i in range(scans):
        if i == after_scans and fault is not None:
            fault(b.bus)
        tau = min((b.plc.time_ns - t0) * 1e-9, DURATION_S)
        b["STRM.POSITION"] = round(start + STROKE * (1 - math.cos(w * tau)) / 2)
        b["STRM.VELOCITY"] = round(STROKE * w * math.sin(w * tau) / 2 / 10)
        b["STRM.ENABLE"] = True
        b.step(1)


def test_a_stream_without_losses_has_no_error():
    b = _stream_bench()
    _stream(b, 300)
    assert b["STRM.ACTIVE"] and not b["STRM.ERROR"] and b["STRM.DRIVEERROR"] == 0
    assert b.drive.mc.error_code == 0


def test_a_lost_sync_ends_the_stream_in_the_underflow():
    b = _stream_bench()
    lost = []
    _stream(b, 300, fault=lambda bus: lost.append(bus.drop(match_id(SYNC_COB), count=1)))
    assert len(lost[0].hits) == 1
    assert b["STRM.ERROR"] and not b["STRM.ACTIVE"]
    assert b["STRM.ERRORID"] == E["DriveError"] and b["STRM.DRIVEERROR"] == W.ERR_PVT_BUFFER_UNDERFLOW
    assert b.drive.mc.error_code == W.ERR_PVT_BUFFER_UNDERFLOW


def test_a_lost_rxpdo_ends_the_stream_in_the_underflow():
    b = _stream_bench()
    lost = []
    _stream(b, 300, fault=lambda bus: lost.append(bus.drop(match_id(RXPDO2_COB), count=1)))
    assert len(lost[0].hits) == 1
    assert b["STRM.ERROR"] and not b["STRM.ACTIVE"]
    assert b["STRM.ERRORID"] == E["DriveError"] and b["STRM.DRIVEERROR"] == W.ERR_PVT_BUFFER_UNDERFLOW
    assert b.drive.mc.error_code == W.ERR_PVT_BUFFER_UNDERFLOW
