"""FB_LmStream (st_lib/motion/stream.st): the PLC streams PV setpoints to the emulated drive, one per SYNC of
the library's SYNC producer (FB_LmSync, 2 ms), with the drive's TxPDOs on SYNC (FB_LmPdoSetup LM_PDO_SYNC);
Enable falling sends Stop Streaming; a PLC whose SYNC slows down gets the drive's 0083h on DriveError."""

from __future__ import annotations

import math

import pytest

from linmot_st.protocol import words as W
from motionbench import MotionBench

MS = 1_000_000
MM = 10_000
STROKE = 10 * MM                      # a 10 mm cosine over 0.4 s
DURATION_S = 0.4


def _bench() -> MotionBench:
    b = MotionBench(nodes=1, pdo={"PDOTIMEOUT": 50 * MS})
    b["SYNC.PERIOD"] = 2 * MS
    b["SYNC.ENABLE"] = True
    r = b.fb("SETUP").run(MODE="LM_PDO_SYNC", EVENTTIMERMS=0)
    assert r.done, r
    assert b.drive.pdo.rx_on_sync
    b.ready()
    return b


def _shape(tau: float) -> tuple[int, int]:
    tau = min(max(tau, 0.0), DURATION_S)
    w = math.pi / DURATION_S
    return round(STROKE * (1 - math.cos(w * tau)) / 2), round(STROKE * w * math.sin(w * tau) / 2 / 10)


def _stream(b: MotionBench, start: float, scans: int) -> int:
    """Enable the stream and feed it the shape from the PLC's clock, scan by scan; returns the start time."""
    t0 = b.plc.time_ns
    b["STRM.CID"] = 0x031
    for _ in range(scans):
        p, v = _shape((b.plc.time_ns - t0) * 1e-9)
        b["STRM.POSITION"], b["STRM.VELOCITY"] = round(start) + p, v
        b["STRM.ENABLE"] = True
        b.step(1)
    return t0


def test_the_plc_streams_and_stops():
    b = _bench()
    mc = b.drive.mc
    start = mc.axis.position
    t0 = _stream(b, start, 500)                       # 0.5 s: the stroke, then 0.1 s at rest
    assert b["STRM.ACTIVE"] and not b["STRM.ERROR"] and b["STRM.SETPOINTS"] >= 240
    assert mc.gen.kind == "stream" and mc.error_code == 0
    # the demand followed the shape about 1.5 SYNC periods (+ the scan that sends it) late
    demand = [s.demand for s in mc.trajectory.between(t0)]
    assert max(demand) - start == pytest.approx(STROKE, abs=2)
    b["STRM.ENABLE"] = False
    b.step(100)
    assert not b["STRM.ACTIVE"] and not b["STRM.ERROR"]
    assert mc.error_code == 0 and mc.state == W.OPERATION_ENABLED and not mc.status_word & W.SW_MOTION_ACTIVE
    assert abs(mc.axis.position - (start + STROKE)) <= 10
    assert [h >> 4 for t, h, _ in mc.executed if t >= t0][-1] == 0x03F


def test_a_plc_that_sends_too_slowly_gets_the_underflow():
    """The first two setpoints fixed the period at 2 ms; SYNC every 4 ms from then on brings each setpoint a
    millisecond after the one before it has played out."""
    b = _bench()
    start = b.drive.mc.axis.position
    _stream(b, start, 50)
    b["SYNC.PERIOD"] = 4 * MS
    b.step(50)
    assert b["STRM.ERROR"] and b["STRM.ERRORID"] == 0x0706 and b["STRM.DRIVEERROR"] == W.ERR_PVT_BUFFER_UNDERFLOW


def test_a_pva_stream_needs_rx3bytes_8():
    b = _bench()
    b["STRM.CID"] = 0x034
    b["STRM.ENABLE"] = True
    b.step(2)
    assert b["STRM.ERROR"] and b["STRM.ERRORID"] == 0x070E and not b["STRM.ACTIVE"]   # CommandNotMapped
