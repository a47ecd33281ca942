"""Independent clients against `linmot-st emulate` on a real Linux SocketCAN stack (vcan0): python canopen's
SDO client and PDO support, and can-utils (cansend, candump, cangen). Run inside a User-Mode Linux guest
where this kernel has no vcan0 (linmot_st_vcan.pytest_plugin); docs/bus.md, "A real SocketCAN stack"."""

from __future__ import annotations

import struct
import subprocess
import threading

import can
import canopen
import pytest

from linmot_st.emulator.cia301.eds import SHIPPED_EDS
from linmot_st_vcan.testing import Candump, EmulatedDrives, can_utility
from shared_vectors import load

pytestmark = pytest.mark.socketcan

# the drive's published words (docs/emulator.md 7): object 2000h + UPID, sub-index 1 = RAM value
STATUS_WORD, STATE_VAR, LOGGED_ERROR, WARN_WORD, CONTROL_WORD = 0x3D51, 0x3B62, 0x3D96, 0x3D8E, 0x3D52


def _pdo_map(pdo_node, cob_id: int, objects: list[int]):
    """A PDO map of 16-bit words built by hand: the E1100 maps its PDOs with LinMot parameters, not CiA 301
    mapping objects, so canopen cannot read the mapping from the drive (docs/emulator.md 9), and the EDS
    gives the variables' SDO type (INTEGER32), not their 16 bits in the PDO."""
    from canopen.objectdictionary import UNSIGNED16, ODVariable
    from canopen.pdo.base import PdoMap, PdoVariable

    pdo = PdoMap(pdo_node, None, None)
    pdo.cob_id, pdo.enabled = cob_id, True
    for index in objects:
        word = ODVariable(pdo_node.node.object_dictionary[index].name, index, 1)
        word.data_type = UNSIGNED16
        var = PdoVariable(word)
        var.pdo_parent, var.offset = pdo, pdo.length
        pdo.map.append(var)
        pdo.length += var.length
    pdo.data = bytearray(pdo.length // 8)
    return pdo


def test_python_canopen_sdo_and_pdo_against_the_emulated_drive(tmp_path):
    with EmulatedDrives([1], tmp_path) as drives:
        net = canopen.Network()
        net.NOTIFIER_CYCLE = 0.05
        net.connect(interface="socketcan", channel="vcan0")
        try:
            node = net.add_node(1, canopen.import_od(str(SHIPPED_EDS), node_id=1))
            node.sdo.RESPONSE_TIMEOUT = 5.0
            # SDO: identity, device name, a ROM write read back, an abort code
            assert node.sdo.upload(0x1018, 1) == struct.pack("<I", 0x156)
            assert node.sdo[0x1008].raw == "1941"
            node.sdo[0x33A2][2].raw = 4321
            assert node.sdo[0x33A2][2].raw == 4321
            with pytest.raises(canopen.SdoAbortedError) as abort:
                node.sdo.upload(0x3001, 1)
            assert abort.value.code == 0x06020000
            # PDO: TxPDO1 sent after each RxPDO1 (transmission type 250), configured in Pre-Operational
            node.sdo.download(0x1800, 2, bytes([250]))
            tpdo = _pdo_map(node.tpdo, 0x181, [STATUS_WORD, STATE_VAR, LOGGED_ERROR, WARN_WORD])
            rpdo = _pdo_map(node.rpdo, 0x201, [CONTROL_WORD])
            received = threading.Event()       # set by canopen's callback: an answer quicker than a wait is not lost
            tpdo.add_callback(lambda pdo: received.set())
            tpdo.subscribe()
            node.nmt.state = "OPERATIONAL"
            for control_word in (0x003E, 0x003F, 0x0006):
                received.clear()
                rpdo[0].raw = control_word
                rpdo.transmit()
                assert received.wait(timeout=5), f"no TxPDO1 after control word {control_word:04X}h"
                words = [tpdo[k].raw for k in range(4)]
                node.nmt.state = "PRE-OPERATIONAL"             # the SDO reads of the same words, undisturbed
                assert node.sdo[CONTROL_WORD][1].raw == control_word
                assert words == [node.sdo[i][1].raw & 0xFFFF for i in (STATUS_WORD, STATE_VAR, LOGGED_ERROR, WARN_WORD)]
                node.nmt.state = "OPERATIONAL"
        finally:
            net.disconnect()
    assert drives.clean_exit() == ""
    assert drives.drive(1).rom(0x13A2) == 4321                 # the write is in the drive process's memory


# the frame examples of LinMot's CANopen manual ([CO1100], spec/linmot-canopen.md 3.1) that a drive as
# `linmot-st emulate` serves it can answer (the error-log example needs a prepared error log: it is replayed
# in-process by test_emulator_vectors.py)
MANUAL_EXAMPLES = [v for v in load("sdo_frames.json")["vectors"]
                   if "[CO1100] example" in v["source"] and v["drive"] == "default"]


@pytest.mark.socketcan(interfaces=("vcan0", "vcan1"))
def test_cansend_frames_of_the_manual_get_the_manuals_answers_on_their_own_bus_only(tmp_path):
    assert len(MANUAL_EXAMPLES) >= 2
    steps = [s for v in MANUAL_EXAMPLES for s in v["steps"]]
    assert all(set(s) <= {"request", "response", "note"} for s in steps)
    cansend = can_utility("cansend")
    # node 1 on each of two buses: frames sent on vcan0 reach only vcan0's drive
    with EmulatedDrives([1], tmp_path / "vcan0") as drives0, \
            EmulatedDrives([1], tmp_path / "vcan1", channel="vcan1") as drives1, \
            Candump(tmp_path / "vcan0.log", "vcan0", filters=("601:7FF", "581:7FF")) as dump0, \
            Candump(tmp_path / "vcan1.log", "vcan1") as dump1, \
            can.Bus(interface="socketcan", channel="vcan0",
                    can_filters=[{"can_id": 0x581, "can_mask": 0x7FF, "extended": False}]) as answers:
        for step in steps:
            request = step["request"].replace(" ", "")
            subprocess.run([cansend, "vcan0", f"601#{request}"], check=True, timeout=30)
            assert answers.recv(timeout=10) is not None, f"no answer to {step['request']}"   # paced by the answer
    expected = [f for s in steps for f in ((0x601, s["request"]), (0x581, s["response"]))]
    recorded = [(m.arbitration_id, bytes(m.data).hex(" ").upper()) for m in dump0.messages()]
    assert recorded == expected                                          # candump's record, not ours
    other_bus = [(m.arbitration_id, bytes(m.data)) for m in dump1.messages()]
    assert other_bus == [], f"vcan1 carried {other_bus[:5]}"
    assert drives0.clean_exit() == "" and drives1.clean_exit() == ""


def test_bad_traffic_from_cangen_crashes_neither_the_drive_nor_the_plc(tmp_path):
    # random identifiers (NMT and SDO ones included), lengths and data, mixed with extended, remote and CAN FD
    # frames, about 1000 a second during a whole commissioning run: the run completes, or fails and says
    # where and why; the drive keeps serving; nothing raises; a PASSED run holds the dataset
    import re

    from linmot_st.emulator.testing import RawSdoClient
    from linmot_st.jobs.commission.runner import RunOptions
    from linmot_st.jobs.commission.testing import EXAMPLE, example
    from linmot_st.jobs.commission.verify import verify
    from linmot_st_vcan.testing import linmot_st

    cangen = can_utility("cangen")
    with EmulatedDrives([1], tmp_path) as drives:
        with Candump(tmp_path / "bus.log") as dump:
            gen = subprocess.Popen([cangen, "vcan0", "-g", "1", "-m", "-I", "r", "-L", "r", "-D", "r", "-i"],
                                   stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
            try:
                res = linmot_st("commission", str(EXAMPLE), "--bus", "socketcan:vcan0", "--no-emulate", "-q")
            finally:
                generating = gen.poll() is None         # it sent throughout the run
                gen.terminate()
                gen_err = gen.communicate(timeout=30)[1].decode(errors="replace")
        with can.Bus(interface="socketcan", channel="vcan0") as bus:
            assert RawSdoClient(bus).exchange("40 00 10 00 00 00 00 00") == bytes.fromhex("43 00 10 00 00 00 00 00")
    assert generating, f"cangen stopped by itself (exit status {gen.returncode}): {gen_err}"
    frames = dump.messages()
    assert sum(m.is_extended_id for m in frames) > 100 and sum(m.is_remote_frame for m in frames) > 100
    assert sum(m.is_fd for m in frames) > 100 and len(frames) > 3000
    assert drives.clean_exit() == ""
    assert "Traceback" not in res.stdout + res.stderr, res.stderr
    if res.returncode == 0:
        assert "result: PASSED" in res.stdout
        assert verify(example(), drives.drives(), RunOptions(bus="socketcan:vcan0", timings="fast")).ok
    else:
        assert res.returncode == 1 and "result: FAILED (commissioning failed on node 1)" in res.stdout, \
            res.stdout + res.stderr
        assert re.search(r"^node 1: Failed in phase .+: ErrorID 16#[0-9A-F]{4} \S", res.stdout, re.M), res.stdout
