"""Fault hooks of the simulated bus: drop, delay, duplicate, corrupt, mutate_payload, node reset/removal."""

import pytest

from linmot_st.bus import Frame, SimBus, flip_bit, match_id, with_data
from linmot_st.bus.bits import ERROR_FRAME_BITS, frame_length_bits
from linmot_st.bus.nodes import EchoNode, ScriptedNode

BIT = 2000
REQ = Frame(0x601, bytes([0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0]))


def setup(latency=100_000):
    bus = SimBus()
    plc = bus.endpoint("plc")
    echo = EchoNode()
    bus.attach(echo, "drive", latency_ns=latency)
    return bus, plc, echo


def exchange(bus, plc, t, n=1):
    for _ in range(n):
        plc.send(REQ, t)
    bus.run_until(t + 5_000_000)
    return plc.receive()


def test_drop_limited_to_count():
    bus, plc, echo = setup()
    fault = bus.drop(match_id(0x601), count=1)
    assert exchange(bus, plc, 0) == []
    assert echo.count == 0 and bus.trace == []          # no bus time, not in the trace
    assert len(exchange(bus, plc, 10_000_000)) == 1     # the second request passes
    assert [(t, s) for t, s, _ in fault.hits] == [(0, "plc")]


def test_drop_by_sender_only():
    bus, plc, echo = setup()
    bus.drop(lambda f: True, sender="drive")
    assert exchange(bus, plc, 0) == []
    assert echo.count == 1 and [e.sender for e in bus.trace] == ["plc"]


def test_delay_shifts_ready_time():
    bus, plc, _ = setup(latency=0)
    bus.delay(match_id(0x581), 2_000_000, count=1)
    got = exchange(bus, plc, 0)
    req_end = frame_length_bits(REQ) * BIT
    assert bus.trace[1].start_ns == req_end + 2_000_000
    assert len(got) == 1


def test_duplicate_is_received_twice_back_to_back():
    bus, plc, echo = setup()
    bus.duplicate(match_id(0x601), count=1)
    got = exchange(bus, plc, 0)
    assert echo.count == 2 and len(got) == 2
    first, second = bus.trace[0], bus.trace[1]
    assert second.frame == first.frame == REQ
    assert second.start_ns == first.end_ns + 3 * BIT


def test_corrupt_costs_an_error_frame_and_is_retransmitted():
    bus, plc, echo = setup()
    bus.corrupt(match_id(0x601), count=1)
    got = exchange(bus, plc, 0)
    err, ok = bus.trace[0], bus.trace[1]
    assert err.status == "error" and ok.status == "ok" and ok.frame == REQ
    # SOF .. ACK delimiter, then the error flag (6) and delimiter (8), then the interframe space
    assert err.end_ns == (frame_length_bits(REQ) - 7 + ERROR_FRAME_BITS) * BIT
    assert ok.start_ns == err.end_ns + 3 * BIT
    assert echo.count == 1 and len(got) == 1             # nobody saw the corrupted one
    assert bus.stats().errors == 1


def test_endless_corruption_ends_in_bus_off():
    bus, plc, echo = setup()
    bus.corrupt(match_id(0x601))
    plc.send(REQ, 0)
    bus.run_until(50_000_000)
    errors = [e for e in bus.trace if e.status == "error"]
    assert len(errors) == 32                             # 32 * 8 = 256: bus-off
    assert echo.count == 0
    plc.send(REQ, bus.now)                               # a bus-off controller sends nothing more
    bus.run_until(bus.now + 5_000_000)
    assert len(bus.trace) == 32


def test_mutate_payload_reaches_receivers_and_trace():
    bus, plc, _ = setup()
    bus.mutate_payload(match_id(0x581), flip_bit(0, 0), count=1)
    got = exchange(bus, plc, 0)
    assert got[0][1].data[0] == REQ.data[0] ^ 1
    assert bus.trace[1].status == "mutated"
    bus.mutate_payload(match_id(0x581), with_data(b"\x43\x18"), count=1)
    got = exchange(bus, plc, 10_000_000)
    assert got[0][1].data == b"\x43\x18"


def test_cancel_fault():
    bus, plc, _ = setup()
    fault = bus.drop(match_id(0x601))
    fault.cancel()
    assert len(exchange(bus, plc, 0)) == 1


def test_reset_node_calls_power_on_and_flushes_its_queue():
    node = ScriptedNode([(0, Frame(0x700, bytes(8)))] + [(1000, Frame(0x181, bytes([i]))) for i in range(3)])
    bus = SimBus()
    plc = bus.endpoint()
    bus.attach(node, "drive")
    start_of_second = frame_length_bits(Frame(0x700, bytes(8))) * BIT + 3 * BIT
    bus.reset_node("drive", start_of_second + 10 * BIT)   # while its first 0x181 is on the bus
    bus.run_until(10_000_000)
    assert node.resets == [start_of_second + 10 * BIT]
    assert [e.status for e in bus.trace] == ["ok", "error"]
    assert [f.can_id for _, f in plc.receive()] == [0x700]


def test_reset_node_needs_the_hook():
    bus = SimBus()
    bus.attach(EchoNode(), "echo")
    with pytest.raises(AttributeError, match="power_on"):
        bus.reset_node("echo", 100)
    bus.reset_node("echo", 100, hook=None)
    bus.run_until(200)


def test_remove_node_at_time():
    bus, plc, echo = setup()
    bus.remove_node("drive", 3_000_000)
    assert len(exchange(bus, plc, 0)) == 1
    assert exchange(bus, plc, 10_000_000) == []
    assert echo.count == 1 and "drive" not in bus.names
    with pytest.raises(KeyError, match="drive"):
        bus.node("drive")


def test_a_node_removed_while_its_frame_goes_bus_off_leaves_the_others_queues_alone():
    # the sender's last transmit error (bus-off) ends after its removal: the bus must not clear the queue head of the
    # participant that took its place in the bus's lists (the frame of "later" waits behind the doomed node's
    # retransmissions, which win arbitration with 0x100)
    def bus_with(remove_at=None):
        bus = SimBus()
        bus.attach(ScriptedNode([(0, Frame(0x100, bytes(8)))]), "doomed")
        bus.attach(ScriptedNode([(0, Frame(0x200, b"\x01"))]), "later")
        bus.corrupt(match_id(0x100), count=31)               # 31 * 8 = 248: the 32nd error is bus-off
        if remove_at is not None:
            bus.remove_node("doomed", remove_at)
        bus.run_until(50_000_000)
        return bus

    plain = bus_with()
    assert [e.status for e in plain.trace] == ["error"] * 31 + ["ok", "ok"]
    bus = bus_with(plain.trace[31].start_ns + 10 * BIT)      # while its 32nd attempt is on the bus
    assert [(e.sender, e.status) for e in bus.trace] == [("doomed", "error")] * 32 + [("later", "ok")]

