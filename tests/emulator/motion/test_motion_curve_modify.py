"""Modify Curve in RAM (050xh..055xh, [MC] 4.3.57..61) on the emulated E1100, and every row of the stream and
curve-modify groups accepted by the drive (no 0081h)."""

from __future__ import annotations

import struct

import pytest

from linmot_st.emulator import DriveTimings, E1100Drive, build_entry, load_profile
from linmot_st.emulator.linmot.curves import Curve
from linmot_st.emulator.testing import MotionLink
from linmot_st.protocol import commands as C
from linmot_st.protocol import words as W

MS = 1_000_000
MM = 10_000

# the rows of this group's modules (protocol/commands/streams.py, curve_modify.py)
ROWS = sorted(cid for cid, c in C.COMMANDS.items()
              if c.kind in (C.Kind.STREAM, C.Kind.STREAM_STOP, C.Kind.CURVE_MODIFY))


def homed_link() -> MotionLink:
    values = {0x1194: 2, 0x146F: 280 * MM, 0x146E: -10 * MM, 0x2041: 2}     # RxPDO3: par bytes 6..11
    link = MotionLink(E1100Drive(1, load_profile().with_defaults(values), timings=DriveTimings.fast()))
    link.enable()
    link.home()
    link.advance(MS)
    link.drive.curves.ram[2] = Curve.build(2, [0, 10 * MM, 20 * MM, 30 * MM], x_length=10_000)   # 100 ms
    return link


def test_the_group_is_complete():
    assert ROWS == [0x030, 0x031, 0x032, 0x033, 0x034, 0x035, 0x03F, 0x050, 0x051, 0x052, 0x054, 0x055, 0x056]
    # what each needs on CANopen: the PVA setpoints and the 64-bit patch fill RxPDO3 up to par byte 11
    assert {cid for cid in ROWS if C.COMMANDS[cid].transport is C.Transport.RXPDO3} == {
        0x031, 0x033, 0x034, 0x035, 0x052, 0x054, 0x055}
    assert C.COMMANDS[0x056].transport is C.Transport.COMMAND_TABLE        # 16 bytes


@pytest.mark.parametrize("cid", ROWS, ids=lambda cid: f"{cid:03X}h")
def test_every_row_is_accepted_by_the_drive(cid):
    link = homed_link()
    mc = link.drive.mc
    fields = {n: 0 for n in C.COMMANDS[cid].field_names}
    if "curve_id" in fields:
        fields["curve_id"] = 2
    if "position" in fields:
        fields["position"] = round(mc.axis.position)
    t0 = link.t
    if C.COMMANDS[cid].transport is C.Transport.COMMAND_TABLE:      # beyond the PDOs: an entry, run by 200xh
        link.drive.ct.ram[9] = build_entry(cid << 4, C.encode(cid, 0, **fields)[2:])
        link.command(C.START_COMMAND_TABLE, entry=9)
        link.advance(MS)
        assert [h >> 4 for t, h, _ in mc.executed if t >= t0] == [C.START_COMMAND_TABLE, cid]
        assert mc.error_code == 0
        return
    link.command(cid, **fields)
    link.advance(MS)
    assert [h >> 4 for t, h, _ in mc.executed if t >= t0] == [cid]
    assert mc.error_code != W.ERR_UNKNOWN_MOTION_CMD
    if C.COMMANDS[cid].kind is not C.Kind.STREAM:       # a stream of one setpoint ends in 0085h later
        assert mc.error_code == 0 and mc.state == W.OPERATION_ENABLED


def test_data_block_patches_change_the_curve_that_runs():
    link = homed_link()
    mc = link.drive.mc
    link.command(C.MODIFY_CURVE_DATA_32, curve_id=2, offset=12, value=40 * MM)      # the 4th setpoint
    link.command(C.MODIFY_CURVE_DATA_64, curve_id=2, offset=4, value=5 * MM, value2=15 * MM)
    link.advance(MS)
    assert mc.curves.ram[2].setpoints == [0, 5 * MM, 15 * MM, 40 * MM]
    link.command(C.TIME_CURVE, curve_id=2)
    link.advance(300 * MS)
    assert mc.error_code == 0 and abs(mc.axis.position - 40 * MM) < 20


def test_a_96_bit_patch_travels_as_a_command_table_entry():
    """056xh has 16 parameter bytes: more than RxPDO2 + RxPDO3 carry, so an entry holds it and 200xh runs it."""
    link = homed_link()
    link.drive.ct.ram[3] = build_entry(C.MODIFY_CURVE_DATA_96 << 4, C.encode(
        C.MODIFY_CURVE_DATA_96, 0, curve_id=2, offset=4, value=1, value2=2, value3=3)[2:])
    link.command(C.START_COMMAND_TABLE, entry=3)
    link.advance(5 * MS)
    assert link.drive.mc.error_code == 0 and link.drive.curves.ram[2].setpoints == [0, 1, 2, 3]


def test_info_block_patches_set_the_x_length_word_by_word():
    """[MC] 4.3.58's example: the low word of the x-length at offset 32, then the high word at 34."""
    link = homed_link()
    curves = link.drive.curves
    x_length = 200_000                              # 2 s in 10 us
    link.command(C.MODIFY_CURVE_INFO_16, curve_id=2, offset=32, value=struct.unpack("<h", struct.pack(
        "<H", x_length & 0xFFFF))[0])
    link.command(C.MODIFY_CURVE_INFO_16, curve_id=2, offset=34, value=x_length >> 16)
    link.advance(MS)
    assert curves.ram[2].x_length == x_length
    link.command(C.MODIFY_CURVE_INFO_32, curve_id=2, offset=32, value=50_000)
    link.advance(MS)
    assert curves.ram[2].x_length == 50_000 and curves.ram[2].setpoint_count == 4


def test_start_address_0fffh_clears_the_curve():
    link = homed_link()
    mc = link.drive.mc
    link.command(C.MODIFY_CURVE_START_ADDRESS, curve_id=2, start_address=0x0FFF)
    link.advance(MS)
    assert 2 not in mc.curves.ram and mc.error_code == 0
    link.command(C.TIME_CURVE, curve_id=2)
    link.advance(MS)
    assert mc.error_code == W.ERR_CURVE_NOT_DEFINED


def test_a_patch_of_a_missing_curve_is_curve_not_defined():
    link = homed_link()
    link.command(C.MODIFY_CURVE_DATA_32, curve_id=7, offset=0, value=1)
    link.advance(MS)
    assert link.drive.mc.error_code == W.ERR_CURVE_NOT_DEFINED


def test_a_patch_beyond_the_block_changes_nothing():
    link = homed_link()
    before = link.drive.curves.ram[2]
    link.command(C.MODIFY_CURVE_DATA_64, curve_id=2, offset=12, value=1, value2=2)     # 16 bytes of data
    link.advance(MS)
    assert link.drive.curves.ram[2] == before and link.drive.mc.error_code == 0
