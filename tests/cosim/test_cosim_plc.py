"""CoSim with a real compiled PLC: a tiny ST program that echoes every received frame with Id + 1."""

import os
import time
import uuid

import pytest

from linmot_st.bus import Frame, NodeServer, SimBus, open_bus
from linmot_st.bus.nodes import ScriptedNode
from linmot_st.cosim import CoSim, CoSimError, Mailbox, RealTimeCoSim
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


def test_frame_codec_writes_and_reads_what_the_member_accessors_do(echo_build):
    # the mailbox packs a frame in one struct call where Rx/Tx have T_CanFrame's layout (FrameCodec): the same bytes
    # as the member-by-member accessors (the path of any other mailbox type), both ways, on both backends
    import random

    from linmot_st.plc import Plc
    plc = Plc(echo_build)
    fast = Mailbox(plc, MB)
    plain = Mailbox(plc, MB)
    plain._rx_codec = plain._tx_codec = None
    assert fast._rx_codec is not None and fast._tx_codec is not None
    rng = random.Random(24)
    frames = [Frame(rng.randrange(0x800), rtr=True, rtr_dlc=rng.randrange(9)) if rng.random() < 0.2
              else Frame(rng.randrange(0x800), bytes(rng.randrange(256) for _ in range(rng.randrange(9))))
              for _ in range(40)]
    echoes = [rng.random() < 0.5 for _ in frames]
    rx = plc.var(f"{MB}.Rx")
    before = bytes(rng.randrange(256) for _ in range(rx.nbytes))     # what a previous scan left
    for mailbox in (fast, plain):
        rx.write_bytes(before)
        plc[f"{MB}.RXLOST"] = 0
        assert mailbox.write_rx(frames, echoes) == 8
        written = (rx.read_bytes(), plc[f"{MB}.RXCOUNT"], plc[f"{MB}.RXLOST"])
        if mailbox is fast:
            first = written
    assert written == first and written[1:] == (32, 8)
    tx = plc.var(f"{MB}.Tx")
    for _ in range(5):
        tx.write_bytes(bytes(rng.randrange(256) for _ in range(tx.nbytes)))
        for i in range(1, 33):      # valid identifiers and lengths, the rest of each element left random
            plc[f"{MB}.Tx[{i}].Id"], plc[f"{MB}.Tx[{i}].Dlc"] = rng.randrange(0x800), rng.randrange(9)
        n = rng.randrange(33)
        plc[f"{MB}.TXCOUNT"] = n
        got = fast.take_tx()
        plc[f"{MB}.TXCOUNT"] = n
        assert got == plain.take_tx() and len(got) == n
    plc[f"{MB}.Tx[2].Dlc"] = 9
    for mailbox in (fast, plain):
        plc[f"{MB}.TXCOUNT"] = 3
        with pytest.raises(CoSimError, match=r"Tx\[2\]: Id .* Dlc 9"):
            mailbox.take_tx()
        assert plc[f"{MB}.TXCOUNT"] == 0


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
