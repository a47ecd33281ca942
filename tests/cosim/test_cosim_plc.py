"""CoSim with a real compiled PLC: a tiny ST program that echoes every received frame with Id + 1."""

import os
import time
import uuid

import pytest

from linmot_st.bus import Frame, NodeServer, SimBus, open_bus
from linmot_st.bus.nodes import ScriptedNode
from linmot_st.cosim import CoSim, RealTimeCoSim
from linmot_st_bench.bus import ECHO_ST
from repo_paths import REPO

MB = "CONFIG0.RES0.CAN0"


def _backends():
    from linmot_st import toolchain
    return [pytest.param("builtin", marks=pytest.mark.skipif(not toolchain.builtin_available(),
                                                             reason="builtin ST compiler not importable")),
            pytest.param("matiec", marks=[pytest.mark.matiec, pytest.mark.skipif(
                not toolchain.matiec_available(), reason="MatIEC's iec2c not found")])]


@pytest.fixture(scope="module", params=_backends())
def echo_build(request, tmp_path_factory):
    from linmot_st.toolchain import build
    src = tmp_path_factory.mktemp("echo") / "echo.st"
    src.write_text(ECHO_ST)
    cwd = os.getcwd()
    os.chdir(REPO)                 # include root: the current directory (the entry has no st_lib ancestor)
    try:
        return build(str(src), backend=request.param)
    finally:
        os.chdir(cwd)


def test_echo_program_on_the_simulated_bus(echo_build):
    from linmot_st.plc import Plc
    plc = Plc(echo_build)
    bus = SimBus()
    frames = [Frame(0x181, bytes([1, 2, 3])), Frame(0x281, bytes(range(8))), Frame(0x301, b""),
              Frame(0x701, rtr=True, rtr_dlc=1)]
    node = ScriptedNode([(100_000 + k * 1_000_000, f) for k, f in enumerate(frames)])
    bus.attach(node, "node")
    sim = CoSim(plc, bus, mailbox=MB)
    sim.step(10)
    got = [f for _, f in node.received]
    assert got == [Frame(f.can_id + 1, f.data, f.rtr, f.rtr_dlc) for f in frames]
    # sent at 0.1 ms + k ms, delivered by the scan at (k + 1) ms, echoed at that scan's time
    echoes = [e for e in bus.trace if e.sender == "plc"]
    assert [e.start_ns for e in echoes] == [(k + 1) * 1_000_000 for k in range(4)]
    assert plc["INST0.SEEN"] == 4 and plc[f"{MB}.TXCOUNT"] == 0
    assert sim.frames_received == 4 and sim.frames_sent == 4


def test_rx_overflow_and_tx_lost_with_a_real_plc(echo_build):
    from linmot_st.plc import Plc
    plc = Plc(echo_build)
    bus = SimBus(1_000_000)
    node = ScriptedNode([(0, Frame(0x100 + 2 * k, bytes([k]))) for k in range(40)])
    bus.attach(node, "node")
    sim = CoSim(plc, bus, mailbox=MB)
    bus.run_until(0)
    plc.step(5)                      # the PLC is 5 ms ahead: 40 frames wait for its next scan
    sim.step(3)
    assert plc[f"{MB}.RXLOST"] == 8 and plc["INST0.SEEN"] == 32
    assert len(node.received) == 32


def test_run_until_with_a_real_plc(echo_build):
    from linmot_st.plc import Plc
    plc = Plc(echo_build)
    bus = SimBus()
    bus.attach(ScriptedNode([(5_500_000, Frame(0x123, b"\x01"))]), "node")
    sim = CoSim(plc, bus, mailbox=MB)
    assert sim.run_until(lambda: plc["INST0.SEEN"] == 1, max_scans=100) == 7   # scan at 6 ms sees it


def test_real_time_cosim_with_a_real_plc(echo_build):
    from linmot_st.plc import Plc
    plc = Plc(echo_build)
    channel = f"linmot-st-test-{uuid.uuid4().hex}"
    node = ScriptedNode([(5_000_000 + k * 2_000_000, Frame(0x181, bytes([k]))) for k in range(5)])
    with open_bus(f"virtual:{channel}") as node_bus, open_bus(f"virtual:{channel}") as plc_bus:
        with NodeServer(node, node_bus) as server:
            sim = RealTimeCoSim(plc, plc_bus, mailbox=MB)
            sim.run_until(lambda: plc["INST0.SEEN"] == 5, timeout_s=3.0)
            deadline = time.monotonic() + 1
            while time.monotonic() < deadline:
                with server.lock:
                    if len(node.received) == 5:
                        break
                time.sleep(0.005)
    assert [f for _, f in node.received] == [Frame(0x182, bytes([k])) for k in range(5)]
