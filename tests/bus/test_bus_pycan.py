"""Serving sans-I/O nodes on python-can buses in real time (python-can's in-process virtual bus)."""

import time
import uuid

import can
import pytest

from linmot_st.bus import Frame, NodeServer, open_bus
from linmot_st.bus.nodes import EchoNode


@pytest.fixture
def channel():
    return f"linmot-st-test-{uuid.uuid4().hex}"


class Booting(EchoNode):
    def __init__(self):
        super().__init__()
        self.timer = None
        self.beats = 0

    def power_on(self, t):
        self.timer = t + 20_000_000   # a heartbeat every 20 ms, first one after 20 ms
        return [(t, Frame(0x701, b"\x00"))]   # boot-up message

    def on_timer(self, t):
        self.beats += 1
        self.timer = t + 20_000_000
        return [(t, Frame(0x701, b"\x7f"))]

    def next_timer_ns(self):
        return self.timer


def recv_until(bus, pred, timeout=2.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        msg = bus.recv(0.05)
        if msg is not None and pred(msg):
            return msg
    return None


def test_node_server_answers_boots_and_beats(channel):
    node = Booting()
    with open_bus(f"virtual:{channel}") as served, open_bus(f"virtual:{channel}") as client:
        with NodeServer(node, served, on_start=node.power_on) as server:
            boot = recv_until(client, lambda m: m.arbitration_id == 0x701)
            assert boot is not None and bytes(boot.data) == b"\x00"
            for k in range(20):
                client.send(can.Message(arbitration_id=0x601, data=bytes([k] * 8), is_extended_id=False))
                reply = recv_until(client, lambda m: m.arbitration_id == 0x581)
                assert reply is not None and bytes(reply.data) == bytes([k] * 8)
            # ignored: extended identifiers and error frames
            client.send(can.Message(arbitration_id=0x601, data=b"\x01", is_extended_id=True))
            beat = recv_until(client, lambda m: m.arbitration_id == 0x701 and bytes(m.data) == b"\x7f")
            assert beat is not None
            with server.lock:
                assert node.count == 20
            assert server.frames_received == 20 and server.running   # the extended frame was ignored
        assert not server.running


def test_node_errors_are_reported_on_stop(channel):
    class Broken(EchoNode):
        def on_frame(self, frame, t):
            raise ZeroDivisionError("boom")

    with open_bus(f"virtual:{channel}") as served, open_bus(f"virtual:{channel}") as client:
        server = NodeServer(Broken(), served).start()
        client.send(can.Message(arbitration_id=0x601, data=b"\x01", is_extended_id=False))
        deadline = time.monotonic() + 2
        while server.error is None and time.monotonic() < deadline:
            time.sleep(0.01)
        with pytest.raises(RuntimeError, match="boom"):
            server.stop()


def test_call_runs_under_the_lock_and_sends_returned_frames(channel):
    node = Booting()
    with open_bus(f"virtual:{channel}") as served, open_bus(f"virtual:{channel}") as client:
        with NodeServer(node, served) as server:
            server.call(node.power_on, server.now_ns())
            assert recv_until(client, lambda m: m.arbitration_id == 0x701) is not None


def test_not_a_node():
    with pytest.raises(TypeError, match="on_frame"):
        NodeServer(object(), None)


def test_open_bus_specs():
    with pytest.raises(ValueError, match="udp_multicast"):
        open_bus("udp_multicast:239.0.0.1")
    with pytest.raises(ValueError, match="channel"):
        open_bus("socketcan")
    with pytest.raises(ValueError):
        open_bus(":x")
    with open_bus("virtual") as bus:
        assert bus.channel_info


@pytest.mark.socketcan
def test_socketcan_vcan0():
    node = EchoNode()
    with open_bus("socketcan:vcan0") as served, open_bus("socketcan:vcan0") as client:
        with NodeServer(node, served):
            client.send(can.Message(arbitration_id=0x601, data=b"\x01\x02", is_extended_id=False))
            reply = recv_until(client, lambda m: m.arbitration_id == 0x581)
            assert reply is not None and bytes(reply.data) == b"\x01\x02"


def test_parse_bus_spec_is_the_rule_open_bus_and_commission_share():
    from linmot_st.bus import parse_bus_spec
    from linmot_st.jobs.commission.runner import check_bus_spec

    assert parse_bus_spec("virtual") == ("virtual", "linmot-st")
    assert parse_bus_spec("Virtual:run1") == ("virtual", "run1")
    assert parse_bus_spec("socketcan:vcan0") == ("socketcan", "vcan0")
    assert parse_bus_spec("pcan:PCAN_USBBUS1") == ("pcan", "PCAN_USBBUS1")
    for bad, message in [("udp_multicast:239.0.0.1", "udp_multicast interface is not supported"),
                         ("socketcan", "needs a channel"), (":x", "expected"),
                         ("nosuch:x", "python-can has no interface 'nosuch'")]:
        with pytest.raises(ValueError, match=message):
            parse_bus_spec(bad)
        with pytest.raises(ValueError, match=message):           # open_bus refuses before opening anything
            open_bus(bad)
        with pytest.raises(ValueError, match=f"--bus '{bad}': "):   # the commission check: same rule
            check_bus_spec(bad)
    check_bus_spec("sim")
