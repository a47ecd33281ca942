"""Traces written with python-can's writers and read back with its readers; bus statistics."""

import pytest

from linmot_st.bus import Frame, SimBus, match_id
from linmot_st.bus.bits import bus_bits
from linmot_st.bus.nodes import EchoNode, ScriptedNode
from linmot_st.bus.stats import busy_per_window
from linmot_st.bus.trace import read_trace

BIT = 2000


def traffic():
    bus = SimBus()
    plc = bus.endpoint("plc")
    bus.attach(EchoNode(0x601, 0x581), "drive", latency_ns=100_000)
    bus.attach(ScriptedNode([(2_500_000, Frame(0x701, b"", rtr=True)), (3_000_000, Frame(0x080, b""))]), "other")
    bus.corrupt(match_id(0x601), count=1)
    for k in range(5):
        plc.send(Frame(0x601, bytes([0x40, k, 0x20, 1, 0, 0, 0, 0])), k * 1_000_000)
        bus.run_until((k + 1) * 1_000_000)
    return bus


@pytest.mark.parametrize("ext", ["log", "asc", "blf"])
def test_trace_round_trip(tmp_path, ext):
    bus = traffic()
    path = tmp_path / f"trace.{ext}"
    bus.write_trace(path)
    back = read_trace(path)
    assert len(back) == len(bus.trace) == 13   # 5 requests + 5 replies + 1 error + RTR + SYNC
    for entry, msg in zip(bus.trace, back):
        assert msg.timestamp == pytest.approx(entry.end_ns / 1e9, abs=1e-6)
        if entry.status == "error":
            assert msg.is_error_frame
            continue
        assert not msg.is_error_frame
        assert msg.arbitration_id == entry.frame.can_id and not msg.is_extended_id
        assert msg.is_remote_frame == entry.frame.rtr
        assert bytes(msg.data) == entry.frame.data
        assert msg.dlc == entry.frame.dlc


def test_trace_needs_an_extension(tmp_path):
    with pytest.raises(ValueError, match="extension"):
        traffic().write_trace(tmp_path / "trace")


def test_stats_busy_load_and_frames_per_sender():
    bus = SimBus()
    plc = bus.endpoint("plc")
    bus.attach(EchoNode(), "drive", latency_ns=100_000)
    frames = []
    for k in range(10):
        f = Frame(0x601, bytes([k, 0xFF, 0, 0x55, 1, 2, 3, 4]))
        frames += [f, Frame(0x581, f.data)]
        plc.send(f, k * 1_000_000)
        bus.run_until((k + 1) * 1_000_000)
    st = bus.stats()
    busy = sum(bus_bits(f) for f in frames) * BIT
    assert (st.t0_ns, st.t1_ns) == (0, 10_000_000)
    assert st.busy_ns == busy and st.frames == 20 and st.errors == 0
    assert st.load == pytest.approx(busy / 10_000_000)
    assert st.frames_by_sender == {"plc": 10, "drive": 10}
    assert st.lower_bound_ns == 20 * 111 * BIT
    assert st.stuffing_ratio >= 1.0
    # an interval cutting a frame counts only the part inside it
    first = bus.trace[0]
    part = bus.stats(0, first.end_ns - 10_000)
    assert part.busy_ns == first.end_ns - 10_000 and part.frames == 1
    assert bus.stats(first.end_ns + 3 * BIT, first.end_ns + 50_000).busy_ns == 0


@pytest.mark.parametrize("window_ns", [100_000, 333_333, 1_000_000, 20_000_000])
def test_busy_per_window_is_bus_stats_of_each_window(window_ns):
    # the one sweep the motion job's busiest 100 ms uses against the plain bus_stats per window: windows that cut
    # frames (and their interframe space), an error frame, windows with nothing, a last stub, a start before t0
    bus = traffic()
    plc = bus.node("plc")
    for k in range(40):
        plc.send(Frame(0x200 + k % 7, bytes([k] * (k % 9))), 6_000_000 + k * 137_000)
    bus.run_until(12_000_000)
    for t0, t1 in ((0, 12_000_000), (1_234_567, 9_876_543), (5_000_000, 5_000_001)):
        windows = busy_per_window(bus.trace, BIT, t0, t1, window_ns)
        assert windows[0][0] == t0 and windows[-1][1] == t1
        assert all(a[1] == b[0] for a, b in zip(windows, windows[1:]))
        assert [w[2] for w in windows] == [bus.stats(t, e).busy_ns for t, e, _ in windows]
    assert sum(w[2] for w in busy_per_window(bus.trace, BIT, 0, 12_000_000, window_ns)) == bus.stats().busy_ns
    assert busy_per_window(bus.trace, BIT, 5, 5, window_ns) == []
