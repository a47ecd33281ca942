"""The deterministic simulated CAN bus: timing, arbitration, endpoints, nodes (linmot_st.bus.SimBus)."""

import pytest

from linmot_st.bus import Frame, SimBus
from linmot_st.bus.bits import frame_length_bits
from linmot_st.bus.nodes import EchoNode, ScriptedNode

BIT = 2000  # ns per bit at 500 kbit/s
REQ = Frame(0x601, bytes([0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0]))


def length_ns(f, bit=BIT):
    return frame_length_bits(f) * bit


def test_request_reply_timing_with_latency():
    bus = SimBus()
    plc = bus.endpoint("plc")
    echo = EchoNode()
    bus.attach(echo, "drive", latency_ns=150_000)
    plc.send(REQ, 0)
    bus.run_until(10_000_000)
    req_end = length_ns(REQ)
    reply = Frame(0x581, REQ.data)
    assert [(e.start_ns, e.end_ns, e.sender, e.frame) for e in bus.trace] == [
        (0, req_end, "plc", REQ),
        (req_end + 150_000, req_end + 150_000 + length_ns(reply), "drive", reply),
    ]
    assert plc.receive() == [(req_end + 150_000 + length_ns(reply), reply)]
    assert plc.receive() == []


def test_reply_waits_for_the_interframe_space():
    bus = SimBus()
    plc = bus.endpoint("plc")
    bus.attach(EchoNode(), "drive")   # zero latency: ready at the end of the request
    plc.send(REQ, 0)
    bus.run_until(1_000_000)
    assert bus.trace[1].start_ns == bus.trace[0].end_ns + 3 * BIT


@pytest.mark.parametrize("bitrate", [125_000, 250_000, 500_000, 1_000_000])
def test_bitrates_scale_frame_time(bitrate):
    bus = SimBus(bitrate)
    plc = bus.endpoint()
    bus.attach(EchoNode(), "drive")
    plc.send(REQ, 0)
    bus.run_until(10_000_000)
    assert bus.trace[0].end_ns == frame_length_bits(REQ) * 10**9 // bitrate


def test_bad_bitrate_is_refused():
    with pytest.raises(ValueError, match="bit rate"):
        SimBus(300_001)


def test_arbitration_lowest_identifier_first_when_ready_together():
    frames = [Frame(0x300, b"\x01"), Frame(0x100, b"\x02"), Frame(0x200, b"\x03")]
    bus = SimBus()
    for i, f in enumerate(frames):
        bus.attach(ScriptedNode([(1000, f)]), f"n{i}")
    listener = ScriptedNode()
    bus.attach(listener, "listener")
    bus.run_until(5_000_000)
    assert [f.can_id for _, f in listener.received] == [0x100, 0x200, 0x300]
    assert bus.trace[0].start_ns == 1000
    # back to back: each starts when the previous one's interframe space ends
    for a, b in zip(bus.trace, bus.trace[1:]):
        assert b.start_ns == a.end_ns + 3 * BIT


def test_frames_ready_while_busy_compete_at_idle():
    bus = SimBus()
    # n_hi's frame is ready first (but the bus is busy), n_lo's later: lowest ID still wins at idle
    first = Frame(0x700, bytes(8))
    bus.attach(ScriptedNode([(0, first)]), "busy")
    bus.attach(ScriptedNode([(10_000, Frame(0x500, b"\x01"))]), "n_hi")
    bus.attach(ScriptedNode([(200_000, Frame(0x080, b"\x02"))]), "n_lo")
    bus.run_until(5_000_000)
    assert [e.frame.can_id for e in bus.trace] == [0x700, 0x080, 0x500]
    assert bus.trace[1].start_ns == bus.trace[0].end_ns + 3 * BIT


def test_equal_identifiers_go_in_attach_order():
    bus = SimBus()
    bus.attach(ScriptedNode([(0, Frame(0x123, b"\xbb"))]), "second_by_name")
    bus.attach(ScriptedNode([(0, Frame(0x123, b"\xaa"))]), "a_later")
    bus.run_until(1_000_000)
    assert [e.sender for e in bus.trace] == ["second_by_name", "a_later"]


def test_one_node_sends_in_queue_order_only_its_head_competes():
    bus = SimBus()
    bus.attach(ScriptedNode([(0, Frame(0x600, b"\x01")), (0, Frame(0x050, b"\x02"))]), "fifo")
    bus.attach(ScriptedNode([(0, Frame(0x400, b"\x03"))]), "other")
    bus.run_until(1_000_000)
    # the head 0x600 of 'fifo' loses to 0x400; 0x050 queued behind 0x600 cannot overtake it
    assert [e.frame.can_id for e in bus.trace] == [0x400, 0x600, 0x050]


def test_a_node_with_several_transmit_buffers_sends_its_ready_frame_of_highest_priority_first():
    """`tx_by_priority` (the emulated drive): a heartbeat queued first and starved by a busier node does not hold
    up the SDO answer queued after it; frames not yet ready never overtake."""
    prio = ScriptedNode([(0, Frame(0x705, b"\x05")), (0, Frame(0x585, b"\x60")), (10**6, Frame(0x181, b"\x01"))])
    prio.tx_by_priority = True
    bus = SimBus()
    bus.attach(prio, "drive")
    bus.attach(ScriptedNode([(0, Frame(0x600, b"\x01"))]), "busy")
    bus.run_until(2_000_000)
    assert [e.frame.can_id for e in bus.trace] == [0x585, 0x600, 0x705, 0x181]
    fifo = ScriptedNode([(0, Frame(0x705, b"\x05")), (0, Frame(0x585, b"\x60"))])
    bus = SimBus()
    bus.attach(fifo, "drive")
    bus.attach(ScriptedNode([(0, Frame(0x600, b"\x01"))]), "busy")
    bus.run_until(2_000_000)
    assert [e.frame.can_id for e in bus.trace] == [0x600, 0x705, 0x585]


def test_run_until_delivers_frames_ending_at_t_but_leaves_a_start_at_t_open():
    bus = SimBus()
    plc = bus.endpoint("plc")
    end = length_ns(REQ)
    bus.attach(ScriptedNode([(0, REQ)]), "a")
    bus.run_until(end)
    assert plc.receive() == [(end, REQ)]           # ended exactly at t: delivered
    late = ScriptedNode([(end + 3 * BIT, Frame(0x700, b"\x01"))])
    bus.attach(late, "late")
    bus.run_until(end + 3 * BIT)                   # the 0x700 is ready at t but not started yet
    assert len(bus.trace) == 1
    plc.send(Frame(0x010, b"\x09"), end + 3 * BIT)  # a frame sent at t joins the arbitration at t
    bus.run_until(end + 1_000_000)
    assert [e.frame.can_id for e in bus.trace] == [0x601, 0x010, 0x700]
    assert bus.trace[1].start_ns == end + 3 * BIT


def test_sender_does_not_receive_its_own_frame():
    bus = SimBus()
    a, b = ScriptedNode([(0, REQ)]), ScriptedNode()
    bus.attach(a, "a")
    bus.attach(b, "b")
    bus.run_until(1_000_000)
    assert a.received == [] and [f for _, f in b.received] == [REQ]


def test_periodic_timer_node():
    class Heartbeat:
        def __init__(self):
            self.t = 0

        def on_frame(self, frame, t):
            return ()

        def on_timer(self, t):
            self.t = t + 100_000_000
            return [(t, Frame(0x701, b"\x05"))]

        def next_timer_ns(self):
            return self.t

    bus = SimBus()
    plc = bus.endpoint()
    bus.attach(Heartbeat(), "hb")
    bus.run_until(1_000_000_000)
    got = plc.receive()
    assert len(got) == 10  # sent at 0, 100, ..., 900 ms; the one due at 1000 ms has not ended yet
    assert got[1][0] - got[0][0] == 100_000_000


def test_node_must_advance_its_timer():
    class Stuck:
        def on_frame(self, f, t):
            return ()

        def on_timer(self, t):
            return ()

        def next_timer_ns(self):
            return 5

    bus = SimBus()
    bus.attach(Stuck(), "stuck")
    with pytest.raises(RuntimeError, match="timer"):
        bus.run_until(10)


def test_frames_in_the_past_are_refused():
    bus = SimBus()
    plc = bus.endpoint()
    bus.run_until(1000)
    with pytest.raises(ValueError, match="past"):
        plc.send(REQ, 999)
    with pytest.raises(ValueError):
        bus.run_until(500)


def test_duplicate_names_and_non_nodes_are_refused():
    bus = SimBus()
    bus.endpoint("plc")
    with pytest.raises(ValueError, match="already"):
        bus.attach(EchoNode(), "plc")
    with pytest.raises(TypeError, match="on_frame"):
        bus.attach(object(), "x")


def scenario():
    bus = SimBus()
    plc = bus.endpoint("plc")
    bus.attach(EchoNode(0x601, 0x581), "d1", latency_ns=120_000)
    bus.attach(EchoNode(0x602, 0x582), "d2", latency_ns=80_000)
    for k in range(50):
        plc.send(Frame(0x601, bytes([k] * 8)), k * 1_000_000)
        plc.send(Frame(0x602, bytes([k, 1, 2])), k * 1_000_000)
        bus.run_until((k + 1) * 1_000_000)
    return bus.trace


def test_deterministic():
    assert scenario() == scenario()


def test_endpoint_latency_and_next_event():
    bus = SimBus()
    plc = bus.endpoint("plc", latency_ns=50_000)
    bus.attach(EchoNode(), "d")
    assert bus.next_event_ns() is None
    plc.send(REQ, 0)
    assert bus.next_event_ns() == 50_000


@pytest.mark.parametrize("order", ["attach-then-power_on", "power_on-then-attach"])
def test_node_changed_outside_the_bus_is_served_in_either_order(order):
    # a drive powered on after it was attached must boot like one powered on first (its timer is read
    # again by run_until, not only when the bus calls the node)
    from linmot_st.emulator import E1100Drive

    bus = SimBus()
    drive = E1100Drive(1)
    if order == "attach-then-power_on":
        bus.attach(drive, "drive")
        drive.power_on(0)
    else:
        drive.power_on(0)
        bus.attach(drive, "drive")
    plc = bus.endpoint("plc")
    bus.run_until(6_000_000_000)
    boot = Frame(0x701, b"\x00")
    assert plc.receive() == [(drive.timings.boot_ns + length_ns(boot), boot)]
    assert drive.nmt_state == "PRE-OPERATIONAL"


def test_node_powered_on_while_the_bus_runs():
    from linmot_st.emulator import E1100Drive

    bus = SimBus()
    drive = E1100Drive(1)
    bus.attach(drive, "drive")
    plc = bus.endpoint("plc")
    bus.run_until(1_000_000_000)
    drive.power_on(bus.now)
    bus.run_until(6_000_000_000)
    boot = Frame(0x701, b"\x00")
    assert plc.receive() == [(1_000_000_000 + drive.timings.boot_ns + length_ns(boot), boot)]
