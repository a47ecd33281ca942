"""The bus node protocol (bus/node.py): one check for both transports, one filter concept (`rx_filter`)."""

from __future__ import annotations

import time
import uuid

import can
import pytest

from linmot_st.bus import Frame, NodeServer, SimBus, open_bus
from linmot_st.bus.node import check_node


class _NoTimer:
    def on_frame(self, frame, t_ns):
        return ()

    def on_timer(self, t_ns):
        return ()


class _Listener:
    """Counts the frames it gets; `rx_filter` as given (None: every frame)."""

    def __init__(self, rx_filter):
        self.rx_filter = rx_filter
        self.got: list[int] = []

    def on_frame(self, frame, t_ns):
        self.got.append(frame.can_id)
        return ()

    def on_timer(self, t_ns):
        return ()

    def next_timer_ns(self):
        return None


def test_both_transports_refuse_a_node_without_next_timer_ns_with_the_same_message():
    with pytest.raises(TypeError, match=r"_NoTimer is not a bus node: it has no next_timer_ns\(\) method") as sim:
        SimBus().attach(_NoTimer())
    with pytest.raises(TypeError) as served:
        NodeServer(_NoTimer(), bus=None)
    assert str(sim.value) == str(served.value)
    check_node(_Listener(None))                      # a complete node passes


@pytest.mark.parametrize("rx_filter, expected", [(frozenset({0x123}), [0x123]), (None, [0x123, 0x456])])
def test_one_rx_filter_on_the_simulated_and_on_a_python_can_bus(rx_filter, expected):
    bus = SimBus()
    node = _Listener(rx_filter)
    bus.attach(node, "n")
    plc = bus.endpoint()
    for cid in (0x123, 0x456):
        plc.send(Frame(cid, b"\x01"), 0)
    bus.run_until(10_000_000)
    assert node.got == expected

    channel = f"node-{uuid.uuid4().hex[:8]}"
    node = _Listener(rx_filter)
    with open_bus(f"virtual:{channel}") as served, open_bus(f"virtual:{channel}") as client:
        with NodeServer(node, served) as server:
            time.sleep(0.05)                         # the server has given the bus the node's filter
            for cid in (0x123, 0x456):
                client.send(can.Message(arbitration_id=cid, data=b"\x01", is_extended_id=False))
            deadline = time.monotonic() + 5
            while server.frames_received < len(expected) and time.monotonic() < deadline:
                time.sleep(0.01)
            time.sleep(0.1)
            with server.lock:
                assert node.got == expected
