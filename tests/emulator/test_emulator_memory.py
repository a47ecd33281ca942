"""The drive's memory as JSON (emulator/linmot/memory.py, `linmot-st emulate --dump-memory`), and the receive filters
a served drive gives its bus (`E1100Drive.rx_filter`, NodeServer)."""

from __future__ import annotations

import json
import time
import uuid

import can
import pytest

from linmot_st.bus import Frame, NodeServer, open_bus
from linmot_st.cli import main
from linmot_st.emulator import OPERATIONAL, DriveTimings, E1100Drive
from linmot_st.emulator.linmot.memory import FORMAT, dump, load, read, write
from linmot_st.emulator.testing import DirectLink
from linmot_st.jobs.commission.testing import commission
from linmot_st.jobs.commission.verify import drive_state


def test_a_commissioned_drive_survives_the_round_trip_through_json(tmp_path):
    run = commission(reset=True)                 # the example's parameters, curves and entries, in flash
    drive = run.result.drives[1]
    write(drive, tmp_path / "drive1.json")
    memory = read(tmp_path / "drive1.json")
    assert memory["format"] == FORMAT and memory["node_id"] == 1 and memory["curves"]["flash"]
    fresh = E1100Drive(1)
    assert drive_state(fresh) != drive_state(drive)
    load(fresh, memory)
    assert drive_state(fresh) == drive_state(drive)
    memory.pop("nmt_state")                       # recorded, not memory: a loaded drive stays where it is
    assert {k: v for k, v in dump(fresh).items() if k != "nmt_state"} == memory


def test_load_refuses_what_is_not_a_dump_of_this_profile():
    memory = dump(E1100Drive(1))
    with pytest.raises(ValueError, match="not a drive memory dump"):
        load(E1100Drive(1), {**memory, "format": "something else"})
    with pytest.raises(ValueError, match="UPID 0001h"):
        load(E1100Drive(1), {**memory, "params": {"0001": [0, 0]}})


def test_emulate_writes_the_dump_when_it_stops(tmp_path, capsys):
    path = tmp_path / "drive5.json"
    rc = main(["emulate", "--interface", "virtual", "--channel", f"mem-{uuid.uuid4().hex[:8]}", "--node-id", "5",
               "--fast", "--duration", "0.1", "--dump-memory", str(path)])
    assert rc == 0, capsys.readouterr().err
    memory = json.loads(path.read_text())
    assert memory["node_id"] == 5 and memory["nmt_state"] == "PRE-OPERATIONAL"
    load(E1100Drive(5), memory)


def test_emulate_refuses_a_dump_path_it_cannot_write_before_serving(tmp_path, capsys):
    rc = main(["emulate", "--interface", "virtual", "--channel", "x", "--dump-memory", str(tmp_path / "no" / "x.json")])
    out, err = capsys.readouterr()
    assert rc == 2 and err.startswith("linmot-st emulate: error: --dump-memory ") and "does not exist" in err and out == ""


def _state(drive) -> tuple:
    return (drive.nmt_state, drive.mc.control_word, drive.mc.state, json.dumps(dump(drive), sort_keys=True))


def test_the_drive_reacts_to_no_frame_outside_its_rx_filter():
    # the filters a served drive gives its bus must never hide a frame it would act on: every standard
    # identifier, in Operational, with data that would mean something (NMT start, an SDO read, a control word)
    link = DirectLink(E1100Drive(1, timings=DriveTimings.fast()))
    link.send(Frame(0x000, bytes([0x01, 0x01])))
    link.advance(10_000_000)
    drive = link.node
    assert drive.nmt_state == OPERATIONAL
    ids = set(drive.rx_filter)
    assert ids == {0x000, 0x080, 0x201, 0x301, 0x401, 0x601}
    before = _state(drive)
    for can_id in range(0x800):
        if can_id in ids:
            continue
        for data in (bytes([0x81, 0x01]), bytes([0x40, 0x00, 0x10, 0x00, 0, 0, 0, 0]), bytes([0x3F, 0x00])):
            assert drive.on_frame(Frame(can_id, data), link.t) == [], hex(can_id)
    assert _state(drive) == before


def test_rx_filter_follows_the_rxpdo_cob_ids():
    link = DirectLink(E1100Drive(1, timings=DriveTimings.fast()))
    assert link.sdo("23 00 14 01 A1 02 00 00") == bytes.fromhex("60 00 14 01 00 00 00 00")    # RxPDO1 on 2A1h
    assert link.sdo("23 01 14 01 01 03 00 80") == bytes.fromhex("60 01 14 01 00 00 00 00")    # RxPDO2 invalid
    assert set(link.node.rx_filter) == {0x000, 0x601}          # Pre-Operational: NMT and its SDO requests
    link.send(Frame(0x000, bytes([0x01, 0x01])))
    link.advance(1_000_000)
    assert set(link.node.rx_filter) == {0x000, 0x080, 0x2A1, 0x401, 0x601}


def test_node_server_gives_the_bus_the_nodes_rx_filter():
    channel = f"filters-{uuid.uuid4().hex[:8]}"
    drive = E1100Drive(1, timings=DriveTimings.fast())
    with open_bus(f"virtual:{channel}") as served, open_bus(f"virtual:{channel}") as client:
        with NodeServer(drive, served, on_start=drive.power_on) as server:
            for can_id in (0x123, 0x602, 0x581, 0x701, 0x601):
                client.send(can.Message(arbitration_id=can_id, data=bytes([0x40, 0, 0x10, 0, 0, 0, 0, 0]),
                                        is_extended_id=False))
            deadline = time.monotonic() + 5
            while server.frames_received < 1 and time.monotonic() < deadline:
                time.sleep(0.01)
            time.sleep(0.1)
            assert server.frames_received == 1          # only 601h passed the filters
