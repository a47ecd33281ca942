"""The drive-model seam (emulator/models.py, emulator/linmot/model.py): a second drive model made of data (a
parameter profile written here), a service table (the E1100's less one service) and a quirk (its boot time),
built through the one factory and run on the simulated bus and on python-can's virtual bus."""

from __future__ import annotations

import json
import struct

import pytest

from linmot_st.bus import Frame, SimBus
from linmot_st.cli import main
from linmot_st.emulator import DriveTimings
from linmot_st.emulator.linmot.model import E1100, BootTime, DriveModel
from linmot_st.emulator.linmot.profile import DEFAULT_PROFILE
from linmot_st.emulator.models import MODELS, make_drive, model_named
from linmot_st.emulator.testing import ServedDrive

MS = 1_000_000
NODE = 3
BOOT_NS = 7 * MS                   # the quirk: E1100 timings say 4 s (real) and 20 ms (fast)
OFFSET_UPID = 0x3ABC               # a parameter only this model's data has: SINT32, default -1234
READ_OFFSET = bytes.fromhex("40 BC 5A 01 00 00 00 00")         # 2000h + 3ABCh, sub 01h: RAM value
RESET_DRIVE = bytes.fromhex("23 00 20 0B 00 00 00 00")         # sub 0Bh: not offered by this model
ABORT_NO_SUBINDEX = 0x06090011

PARAMETERS = """upid,kind,type,live,access,default,min,max,stringlets,name
1194,par,ENUM_DIR16,0,rw,1,0,0x7FFF,,Motor Type
2020,par,BOOL,0,rw,1,,,,Produce Heartbeat
2021,par,UINT16,0,rw,250,1,65535,,Producer Time
3ABC,par,SINT32,1,rw,-1234,-5000,5000,,Test\\Offset
"""


@pytest.fixture
def model(tmp_path) -> DriveModel:
    """The test model T1: its identity and firmware layers as the E1100's, four parameters of its own
    (heartbeat on at 250 ms from the data), no error texts, no "Reset drive" service, a 7 ms boot."""
    spec = json.loads(DEFAULT_PROFILE.read_text())
    spec.update(description="test drive model T1", parameter_file="t1_parameters.csv")
    del spec["error_text_file"]
    (tmp_path / "t1.json").write_text(json.dumps(spec))
    (tmp_path / "t1_parameters.csv").write_text(PARAMETERS)
    return DriveModel("T1", tmp_path / "t1.json", E1100.without_services(0x0B), (BootTime(BOOT_NS),))


def _abort_code(answer: bytes) -> int:
    assert answer[0] == 0x80, answer.hex(" ")
    return struct.unpack_from("<I", answer, 4)[0]


def test_the_second_model_on_the_simulated_bus(model):
    bus = SimBus(500_000)
    drive = make_drive(model, NODE, timings=DriveTimings())
    bus.attach(drive, "t1")
    plc = bus.endpoint("plc")
    drive.power_on(0)
    bus.run_until(BOOT_NS + MS)
    boot = [(t, f) for t, f in plc.receive() if f.can_id == 0x700 + NODE]
    assert len(boot) == 1 and boot[0][1].data == b"\x00"
    assert BOOT_NS < boot[0][0] < BOOT_NS + MS          # the quirk's boot time (frame end: + its bit time)

    plc.send(Frame(0x600 + NODE, READ_OFFSET), bus.now)
    plc.send(Frame(0x600 + NODE, RESET_DRIVE), bus.now + MS)
    bus.run_until(bus.now + 300 * MS)
    got = plc.receive()
    answers = [f.data for _, f in got if f.can_id == 0x580 + NODE]
    assert struct.unpack_from("<i", answers[0], 4)[0] == -1234          # from the model's data
    assert _abort_code(answers[1]) == ABORT_NO_SUBINDEX                 # a service the model does not have
    assert drive.booted                                                  # ... so the drive did not reset
    beats = [t for t, f in got if f.can_id == 0x700 + NODE and f.data == b"\x7f"]
    assert beats and beats[0] - boot[0][0] == pytest.approx(250 * MS, abs=MS)   # heartbeat from its data


def test_the_e1100_differs_where_the_model_does():
    drive = make_drive("E1100", NODE, timings=DriveTimings())
    assert drive.timings.boot_ns == 4_000_000_000 and OFFSET_UPID not in drive.params
    assert 0x0B in drive.mfr.services


def test_the_second_model_on_python_cans_virtual_bus(model):
    drive = make_drive(model, NODE, timings=DriveTimings.fast())
    assert drive.timings.boot_ns == BOOT_NS                 # the quirk wins over the timings given
    with ServedDrive(drive) as served:                      # waits for the boot-up message
        client = served.client
        answer = client.exchange(READ_OFFSET)
        assert answer is not None and struct.unpack_from("<i", answer, 4)[0] == -1234
        assert _abort_code(client.exchange(RESET_DRIVE)) == ABORT_NO_SUBINDEX


def test_a_model_in_the_table_is_built_by_name(model, monkeypatch):
    monkeypatch.setitem(MODELS, model.name, model)
    assert model_named("t1") is model
    assert make_drive("T1", NODE).model is model
    with pytest.raises(ValueError, match=r"no drive model 'B9' \(known: B1100, E1100, T1\)"):
        make_drive("B9", NODE)


def test_emulate_refuses_an_unknown_model(capsys):
    assert main(["emulate", "--interface", "virtual", "--channel", "x", "--drive", "B9"]) == 2
    assert "--drive B9: no drive model 'B9' (known: B1100, E1100)" in capsys.readouterr().err


def test_a_quirk_changes_each_drive_of_its_model_only():
    from linmot_st.emulator.linmot.model import FifoTransmit

    fifo = DriveModel("FIFO", E1100.profile, E1100.services, (FifoTransmit(),))
    bus = SimBus(500_000)
    bus.attach(make_drive(fifo, 1), "fifo")
    bus.attach(make_drive("E1100", 2), "e1100")
    assert [bus._part(n).by_priority for n in ("fifo", "e1100")] == [False, True]
