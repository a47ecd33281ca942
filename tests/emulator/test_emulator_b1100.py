"""The emulated B1100 (emulator/linmot/b1100.py, docs/emulator.md 14): its object dictionary, the
select-then-access parameter protocol of [CO1100] p.23 and p.31-33, strings at UPID + 0, the refusals of what
it lacks, boot and the 6085h flag, and the E1100 motion model running on its UPIDs."""

from __future__ import annotations

import struct

import pytest

from linmot_st.emulator import DriveTimings
from linmot_st.emulator.cia301.eds import generate_eds
from linmot_st.emulator.linmot.b1100 import B1100Drive, B1100Settings
from linmot_st.emulator.models import MODELS, make_drive
from linmot_st.emulator.testing import DirectLink

NODE = 63
ABORT_NO_OBJECT, ABORT_NO_SUBINDEX, ABORT_WRITE_ONLY = 0x06020000, 0x06090011, 0x06010001
ABORT_READ_ONLY, ABORT_UNSUPPORTED = 0x06010002, 0x06010000


def select(upid: int) -> str:
    return f"23 00 20 C0 {upid & 0xFF:02X} {upid >> 8:02X} 00 00"


def abort_code(answer: bytes) -> int | None:
    return int.from_bytes(answer[4:8], "little") if answer[0] == 0x80 else None


@pytest.fixture
def link():
    return DirectLink(make_drive("b1100", NODE, timings=DriveTimings.fast()))


def test_the_factory_builds_a_b1100_with_its_data():
    d = make_drive("B1100", NODE)
    assert isinstance(d, B1100Drive) and MODELS["B1100"].default_node_id == 63
    assert d.profile.definitions.series == "B1100"
    assert 0xE9E7 in d.params and 0xF4D9 in d.params and 0x7078 in d.params


def test_the_manual_example_read_of_e9e7h(link):
    """[CO1100] p.31: select E9E7h (answer 60 00 20 C0 00..), read RAM (43 .. FFFFFEDCh for -292)."""
    assert link.sdo(select(0xE9E7)) == bytes.fromhex("60 00 20 C0 00 00 00 00")
    answer = link.sdo("40 00 20 01 00 00 00 00")
    assert answer[:4] == bytes.fromhex("43 00 20 01")
    assert struct.unpack("<i", answer[4:8])[0] == 0      # no current while the axis is off


def test_ram_and_rom_through_the_selection_and_a_reset(link):
    d = link.node
    assert link.sdo(select(0xE19C))[0] == 0x60                       # Max Current
    assert link.sdo("23 00 20 01 B8 0B 00 00")[0] == 0x60             # RAM 3000
    assert d.ram(0xE19C) == 3000 and d.rom(0xE19C) != 3000
    assert link.sdo("23 00 20 02 D0 07 00 00")[0] == 0x60             # ROM 2000, same selection
    assert d.rom(0xE19C) == 2000
    assert link.sdo("40 00 20 02 00 00 00 00")[4:8] == (2000).to_bytes(4, "little")
    assert link.sdo("23 00 20 0B 00 00 00 00")[0] == 0x60             # reset: answered at once, then boot
    assert link.wait_for(lambda f: f.can_id == 0x700 + NODE, 10**9) is not None
    assert d.ram(0xE19C) == 2000                                      # RAM from ROM at boot
    # the selection is a RAM variable: 0000h after the reset, which is no parameter
    assert abort_code(link.sdo("40 00 20 01 00 00 00 00")) == ABORT_NO_OBJECT


def test_unknown_upid_refused_at_the_access_or_the_select():
    link = DirectLink(make_drive("B1100", NODE, timings=DriveTimings.fast()))
    assert link.sdo(select(0x1234))[0] == 0x60                        # a plain store
    assert abort_code(link.sdo("40 00 20 01 00 00 00 00")) == ABORT_NO_OBJECT
    strict = DirectLink(B1100Drive(NODE, timings=DriveTimings.fast(), b1100=B1100Settings(select_check="select")))
    assert abort_code(strict.sdo(select(0x1234))) == ABORT_NO_OBJECT


def test_strings_start_at_the_upid_itself(link):
    d = link.node
    link.sdo(select(0x7078))                                          # User Comment: stringlet 1 = 7078h
    assert link.sdo("23 00 20 02 59 20 41 78")[0] == 0x60
    link.sdo(select(0x7079))
    assert link.sdo("23 00 20 02 69 73 00 00")[0] == 0x60
    assert d.string(0x7078).startswith("Y Axis")


def test_what_the_b1100_lacks_is_refused_as_a_missing_object(link):
    for request, code in [
        ("40 00 20 03 00 00 00 00", ABORT_NO_SUBINDEX),               # min value: no limits stored
        ("23 00 20 07 00 00 00 00", ABORT_NO_SUBINDEX),               # set OS ROM to default
        ("23 00 20 20 00 00 00 00", ABORT_NO_SUBINDEX),               # UPID list
        ("23 00 20 35 00 00 00 00", ABORT_NO_SUBINDEX),               # MC stop
        ("23 00 20 40 00 00 00 00", ABORT_NO_SUBINDEX),               # flash save
        ("23 01 20 50 00 00 00 00", ABORT_NO_OBJECT),                 # add curve 1 (2001h: no object)
        ("23 01 20 83 00 00 00 00", ABORT_NO_OBJECT),                 # CT entry 1
        ("40 E7 29 01 00 00 00 00", ABORT_NO_OBJECT),                 # 2000h + UPID: not on the B1100
        ("40 00 20 C0 00 00 00 00", ABORT_WRITE_ONLY),                # the selection is write-only
    ]:
        assert abort_code(link.sdo(request)) == code, request
    assert link.sdo("40 00 20 00 00 00 00 00")[4] == 0xC0             # highest sub-index


def test_variables_and_tree_rows_are_read_only(link):
    link.sdo(select(0x6061))                                          # status word
    assert abort_code(link.sdo("23 00 20 01 00 00 00 00")) == ABORT_READ_ONLY
    assert abort_code(link.sdo("40 00 20 02 00 00 00 00")) == ABORT_UNSUPPORTED    # no ROM
    link.sdo(select(0x2CA1))                                          # OS tree ID (seed 000 Table 4)
    assert link.sdo("40 00 20 01 00 00 00 00")[4:6] == (257).to_bytes(2, "little")
    assert abort_code(link.sdo("23 00 20 02 01 00 00 00")) == ABORT_READ_ONLY


def test_identity_1018h_has_the_vendor_only_and_the_eds_lists_2000h_alone(link):
    assert link.sdo("40 18 10 00 00 00 00 00")[4] == 1
    assert link.sdo("40 18 10 01 00 00 00 00")[4:8] == (0x156).to_bytes(4, "little")
    assert abort_code(link.sdo("40 18 10 02 00 00 00 00")) == ABORT_NO_SUBINDEX
    eds = generate_eds(link.node)
    assert "[2000sub0]" in eds and "[2000subC0]" in eds and "[2001]" not in eds and "[2000sub3]" not in eds


def test_the_default_flag_restores_the_installation_values_at_boot(link):
    d = link.node
    link.sdo(select(0xE19C))
    link.sdo("23 00 20 02 D0 07 00 00")
    link.sdo(select(0x6085))
    link.sdo("23 00 20 02 01 00 00 00")
    link.sdo("23 00 20 0B 00 00 00 00")
    assert link.wait_for(lambda f: f.can_id == 0x700 + NODE, 10**9) is not None
    assert d.rom(0xE19C) == d.params[0xE19C].default and d.rom(0x6085) == 0


def test_the_e1100_motion_model_runs_on_the_b1100_upids(link):
    """The MC reads the B1100's Motor Type (D194h, counterpart 1194h): 0 boots into the setup error; the status
    word read over 6061h is the MC's."""
    d = link.node
    assert d.mc.params[0x1194] is d.params[0xD194]
    link.sdo(select(0x6061))
    sw = int.from_bytes(link.sdo("40 00 20 01 00 00 00 00")[4:8], "little")
    assert sw == d.mc.words[0]


@pytest.mark.parametrize("header", [0x0400, 0x0900, 0x2000])     # time curve, VAI 16 bit, command table
def test_commands_whose_catalogue_row_lacks_the_b1100_answer_0081h(header):
    from linmot_st.protocol.commands import B1100, COMMANDS
    assert B1100 not in COMMANDS[header >> 4].drives
    for model, refused in (("B1100", True), ("E1100", False)):
        link = DirectLink(make_drive(model, NODE, timings=DriveTimings.fast()))
        link.run_until(link.t + 100_000_000)            # the MC runs (boot + HW tests)
        mc = link.node.mc
        mc.execute(header, bytes(16), link.t)
        assert (mc.error_code == 0x0081) is refused, model


def test_the_b1100_motor_type_decides_the_setup_error_and_its_commands_run():
    """D194h (Motor Type, counterpart 1194h): 0 boots the MC into the setup error 0064h as the E1100's; with a
    motor the MC is ready and a command of both drives runs."""
    drive = make_drive("B1100", NODE, timings=DriveTimings.fast())
    link = DirectLink(drive)
    link.run_until(link.t + 100_000_000)
    assert drive.mc.error_code == 0x0064
    drive = make_drive("B1100", NODE, timings=DriveTimings.fast())
    drive.params[0xD194].rom = 2
    link = DirectLink(drive)
    link.run_until(link.t + 100_000_000)
    mc = drive.mc
    mc.execute(0x0000, bytes(16), link.t)                 # No Operation: both drives
    assert mc.error_code == 0


def test_a_mixed_bus_on_the_simulated_bus_and_on_python_cans_virtual_bus():
    """An E1100 (node 1) and a B1100 (node 63) on one bus answer each in its own protocol."""
    from linmot_st.bus import SimBus
    from linmot_st.emulator.testing import ServedDrive

    bus = SimBus(500_000)
    e1100, b1100 = (make_drive(m, n, timings=DriveTimings.fast()) for m, n in (("E1100", 1), ("B1100", NODE)))
    for name, d in (("e", e1100), ("b", b1100)):
        bus.attach(d, name)
        d.power_on(0)
    bus.run_until(100_000_000)
    assert e1100.booted and b1100.booted
    assert {e.frame.can_id for e in bus.trace if e.frame.data == b"\x00"} >= {0x701, 0x700 + NODE}  # boot-ups

    import uuid
    channel = f"linmot-st-mixed-{uuid.uuid4().hex[:8]}"
    with ServedDrive(make_drive("E1100", 1, timings=DriveTimings.fast()), channel=channel) as e, \
            ServedDrive(make_drive("B1100", NODE, timings=DriveTimings.fast()), channel=channel) as b:
        assert e.client.exchange("40 A0 31 02 00 00 00 00")[0] == 0x43            # E1100: 2000h + 11A0h
        assert b.client.exchange(select(0xE19C)) == bytes.fromhex("60 00 20 C0 00 00 00 00")
        answer = b.client.exchange("40 00 20 02 00 00 00 00")
        assert answer[0] == 0x43 and int.from_bytes(answer[4:8], "little") == b.drive.rom(0xE19C)
        assert abort_code(b.client.exchange("40 A0 31 02 00 00 00 00")) == ABORT_NO_OBJECT   # not on the B1100


def _operation_enabled(model: str):
    drive = make_drive(model, NODE, timings=DriveTimings.fast())
    drive.params[0xD194 if model == "B1100" else 0x1194].rom = 2        # a motor: no setup error
    link = DirectLink(drive)
    link.run_until(link.t + 100_000_000)
    for cw in (0x003E, 0x003F):
        drive.mc.set_control_word(cw, link.t)
        link.run_until(link.t + 50_000_000)
    assert drive.mc.state == 8, drive.mc.state
    return drive, link


def test_special_mode_state_20_on_control_word_bit_10_only_on_the_b1100():
    drive, link = _operation_enabled("B1100")
    drive.mc.set_control_word(0x043F, link.t)
    link.run_until(link.t + 5_000_000)
    assert drive.mc.state == 20 and not drive.mc.controlled               # current 0: no analog input
    drive.mc.set_control_word(0x003F, link.t)
    link.run_until(link.t + 5_000_000)
    assert drive.mc.state == 8 and drive.mc.controlled
    e1100, elink = _operation_enabled("E1100")
    e1100.mc.set_control_word(0x043F, elink.t)
    elink.run_until(elink.t + 5_000_000)
    assert e1100.mc.state != 20 and e1100.mc.error_code != 0               # refused on the E1100
