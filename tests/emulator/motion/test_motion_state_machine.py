"""The main state machine of the emulated E1100 (seed 004 chapter 3, spec/linmot-motion.md section 1), transition
by transition, driven by RxPDO1 frames; every step checks TxPDO1 byte for byte.

The expected words are built here from the seed's bit tables (status word 3.23, state var 3.8, warn word 3.24),
not taken from the emulator.
"""

from __future__ import annotations

import struct

import pytest

from linmot_st.emulator import DriveTimings, E1100Drive, load_profile
from linmot_st.emulator.testing import MotionLink

MS = 1_000_000

# status word bits (seed 004 3.23)
OP_ENABLED, SWITCH_ON, ENABLE_OP, ERROR, VOLTAGE, QUICK_STOP_N, LOCKED, WARNING = 1, 2, 4, 8, 0x10, 0x20, 0x40, 0x80
SPECIAL, IN_TARGET, HOMED, FATAL, MOTION = 0x200, 0x400, 0x800, 0x1000, 0x2000
NOT_HOMED = 0x0080                       # warn word bit 7

# control words
OFF, READY, ON, OPERATE = 0x0000, 0x003E, 0x003F, 0x003F


def drive(defaults: dict | None = None):
    values = {0x1194: 2}
    values.update(defaults or {})
    return E1100Drive(1, load_profile().with_defaults(values), timings=DriveTimings.fast())


def tx1(link) -> bytes:
    return link.pdos(1)[-1][1]


def words(sw: int, sv: int, err: int = 0, warn: int = NOT_HOMED) -> bytes:
    return struct.pack("<HHHH", sw, sv, err, warn)


def cw_bits(cw: int) -> int:
    """The status bits that mirror the control word (1, 2, 4, 5 from bits 0, 3, 1, 2)."""
    return ((SWITCH_ON if cw & 1 else 0) | (ENABLE_OP if cw & 8 else 0) | (VOLTAGE if cw & 2 else 0)
            | (QUICK_STOP_N if cw & 4 else 0))


@pytest.fixture
def link():
    return MotionLink(drive())


def step(link, cw: int, dt_ns: int = MS) -> bytes:
    link.cw(cw)
    link.advance(dt_ns)
    return tx1(link)


def test_power_on_is_switch_on_disabled(link):
    # MC started with control word 0: state 0 is left at once (bit 0 is 0), state 1 with no bits
    assert tx1(link) == words(WARNING, 0x0100)


def test_1_to_2_needs_bits_1_2_and_bit_0_low(link):
    assert step(link, 0x0007) == words(cw_bits(0x0007) | WARNING, 0x0100)    # x111: stays in 1
    assert step(link, 0x0006) == words(cw_bits(0x0006) | WARNING, 0x0200)    # x110: 2
    assert step(link, 0x0004) == words(cw_bits(0x0004) | WARNING, 0x0100)    # bit 1 low: back to 1
    assert step(link, 0x0006) == words(cw_bits(0x0006) | WARNING, 0x0200)
    assert step(link, 0x0002) == words(cw_bits(0x0002) | WARNING, 0x0100)    # bit 2 low: back to 1


def test_2_to_5_hw_tests_then_6_then_8():
    d = E1100Drive(1, load_profile().with_defaults({0x1194: 2}))       # the default 300 ms HW test
    link = MotionLink(d)
    step(link, 0x0006)
    t0 = link.t
    assert step(link, 0x0007, 200_000) == words(cw_bits(0x0007) | WARNING, 0x0500)
    link.wait(lambda: d.mc.state == 6, 1000 * MS, step_ns=100_000)
    assert 299.9 <= (link.t - t0) / MS <= 300.2                        # seed 004 3.6: about 300 ms
    link.advance(MS)
    assert tx1(link) == words(cw_bits(0x0007) | WARNING, 0x0600)
    # 6 -> 8 with bit 3; at rest and not homed: operation enabled, in target, count 0
    assert step(link, 0x003F) == words(OP_ENABLED | cw_bits(0x003F) | WARNING | IN_TARGET, 0x0840)


def test_hw_tests_left_with_bit_0_or_power_bits(link):
    step(link, 0x0006)
    assert step(link, 0x0007, 200_000)[2:4] == b"\x00\x05"
    assert step(link, 0x0006)[2:4] == b"\x00\x02"                     # bit 0 low in HW tests: 2
    step(link, 0x0007, 200_000)
    assert step(link, 0x0005)[2:4] == b"\x00\x01"                     # bit 1 low: 1


def enabled(defaults: dict | None = None) -> MotionLink:
    link = MotionLink(drive(defaults))
    link.enable()
    link.advance(MS)
    return link


def test_8_back_to_6_when_enable_operation_drops():
    link = enabled()
    assert step(link, 0x0037) == words(cw_bits(0x0037) | WARNING, 0x0600)
    assert step(link, 0x003F)[2:4] == b"\x40\x08"


@pytest.mark.parametrize("cw, state", [(0x003E, 2), (0x003D, 1), (0x003B, 1)])
def test_off1_off2_off3_from_8(cw, state):
    link = enabled()
    assert step(link, cw) == words(cw_bits(cw) | WARNING, state << 8)
    assert link.drive.mc.controlled is False                          # the power stage is off


def test_state_0_anti_restart_after_an_error_acknowledge():
    link = enabled()
    link.command(0x0FF)                                               # unknown motion command: error 0081h
    link.advance(MS)
    assert tx1(link) == words(ERROR | cw_bits(0x003F) | WARNING, 0x0481, 0x0081)
    assert step(link, 0x003F) == words(ERROR | cw_bits(0x003F) | WARNING, 0x0481, 0x0081)    # no edge: stays
    # rising bit 7 with bit 0 still set: state 0 (switch on locked) until bit 0 is released
    assert step(link, 0x00BF) == words(cw_bits(0x00BF) | LOCKED | WARNING, 0x0000)
    assert step(link, 0x003F) == words(cw_bits(0x003F) | LOCKED | WARNING, 0x0000)
    assert step(link, 0x003E) == words(cw_bits(0x003E) | WARNING, 0x0200)   # 0 -> 1 -> 2 at once


def test_fatal_error_cannot_be_acknowledged():
    link = enabled()
    link.drive.inject_error(0x000D, link.t)                           # X1 Pwr Over Current ([MC] 10: fatal)
    link.advance(MS)
    assert tx1(link) == words(ERROR | FATAL | cw_bits(0x003F) | WARNING, 0x040D, 0x000D)
    step(link, 0x00BF)
    assert tx1(link)[2:4] == b"\x0D\x04"                              # still error 4
    assert link.drive.errlog.entries[-1].code == 0x000D


def test_setup_error_without_motor_stays():
    link = MotionLink(E1100Drive(1, timings=DriveTimings.fast()))    # factory default: Motor Type 0
    assert tx1(link) == words(ERROR | FATAL, 0x0364, 0x0064, 0)
    for cw in (0x003E, 0x003F, 0x00BF):
        assert step(link, cw)[2:4] == b"\x64\x03"


def test_homing_9_sub_state_0f_then_back_to_8():
    link = enabled()
    assert step(link, 0x083F) == words(OP_ENABLED | cw_bits(0x083F) | HOMED | IN_TARGET, 0x090F, 0, 0)  # mode 0
    assert step(link, 0x003F) == words(OP_ENABLED | cw_bits(0x003F) | HOMED | IN_TARGET, 0x08C0, 0, 0)


def test_homing_on_the_mechanical_stop_runs_search_and_initial_position():
    link = enabled({0x1500: 3})                                     # mech stop negative search
    d = link.drive
    link.cw(0x083F)
    link.advance(5 * MS)
    sw, sv, _, warn = struct.unpack("<HHHH", tx1(link))
    assert sv == 0x0901 and sw & SPECIAL and sw & MOTION and warn == NOT_HOMED     # searching
    assert link.wait(lambda: d.mc.state_var == 0x090F, 5_000 * MS)
    assert d.mc.homed and abs(d.mc.axis.position - 100_000) <= 1000   # at the initial position 1502h (10 mm)
    # the stop is the home position 13C7h = 0: the slider's own frame says where the stop is
    assert d.mc.axis.physical - d.mc.axis.position == pytest.approx(d.motion.stop_negative_pu - 0, abs=1)
    step(link, 0x003F)
    assert d.mc.state == 8 and d.mc.homed


def test_homing_aborted_when_bit_11_drops_early():
    link = enabled({0x1500: 3})
    link.cw(0x083F)
    link.advance(20 * MS)
    sw, sv, _, _ = struct.unpack("<HHHH", step(link, 0x003F))
    assert sv >> 8 == 8 and not sw & HOMED
    assert not link.drive.mc.homed


def homed(defaults: dict | None = None) -> MotionLink:
    link = enabled(defaults)
    link.home()
    link.advance(MS)
    return link


def test_aborting_12_and_back():
    link = homed()
    link.command(0x090, target=500, vmax=1000, acc=100, dec=100)
    link.advance(50 * MS)
    assert step(link, 0x002F)[2:4] == b"\x00\x0C"                     # /Abort = 0: 12, quick stop
    d = link.drive
    assert link.wait(lambda: not d.mc.motion_active, 500 * MS)
    stopped_at = d.mc.dem_p
    assert 0 < stopped_at < 500_000
    assert step(link, 0x003F)[2:4][1] == 8                            # bit 4 back: 8, rests in position
    link.advance(100 * MS)
    assert d.mc.dem_p == stopped_at


def test_freezing_13_resumes_a_vai_motion():
    link = homed()
    d = link.drive
    link.command(0x090, target=500, vmax=1000, acc=100, dec=100)
    link.advance(40 * MS)
    assert step(link, 0x001F)[2:4] == b"\x00\x0D"                     # /Freeze = 0: 13
    assert link.wait(lambda: not d.mc.motion_active, 500 * MS)
    assert d.mc.dem_p < 500_000
    link.cw(0x003F)                                                   # rising /Freeze: the motion is finished
    assert link.wait(lambda: d.mc.in_target, 1000 * MS)
    assert d.mc.state == 8 and d.mc.dem_p == 500_000


def test_special_states_go_to_position_clearance_initial_jog():
    link = homed({0x1510: 200_000, 0x1520: 50_000, 0x1521: 150_000, 0x1502: 120_000, 0x14B1: 30_000})
    d = link.drive
    for cw, state, end in ((0x007F, 15, 200_000), (0x103F, 10, 150_000), (0x203F, 11, 120_000),
                           (0x013F, 16, 150_000), (0x023F, 17, 120_000)):
        link.cw(cw)
        link.advance(MS)
        assert tx1(link)[3] == state and d.mc.status_word & SPECIAL
        assert link.wait(lambda: d.mc.state_var == state << 8 | 0x0F, 5_000 * MS), state
        assert d.mc.dem_p == pytest.approx(end)
        assert not d.mc.status_word & SPECIAL
        step(link, 0x003F)
        assert d.mc.state == 8


def test_special_mode_and_phase_search_are_refused():
    for cw in (0x043F, 0x803F):
        link = enabled()
        sw, sv, err, _ = struct.unpack("<HHHH", step(link, cw))
        assert sv == 0x0486 and err == 0x0086 and sw & ERROR


def test_motion_command_in_state_6_is_an_error():
    link = MotionLink(drive())
    step(link, 0x0006)
    step(link, 0x0007, 50 * MS)                                      # HW tests done: 6
    assert link.drive.mc.state == 6
    link.command(0x090, target=100, vmax=100, acc=100, dec=100)
    link.advance(MS)
    assert tx1(link)[2:6] == b"\x86\x04\x86\x00"


def test_error_during_motion_quick_stop_14_then_4():
    link = homed()
    d = link.drive
    link.command(0x090, target=1000, vmax=1000, acc=100, dec=100)
    link.advance(60 * MS)
    d.mc.block(True, link.t)                                          # an obstacle: the lag grows
    assert link.wait(lambda: d.mc.state == 14, 500 * MS)
    assert d.mc.error_code == 0x000B and d.mc.status_word & ERROR
    assert link.wait(lambda: d.mc.state == 4, 2000 * MS)
    link.advance(MS)
    assert tx1(link)[2:6] == b"\x0B\x04\x0B\x00" and not d.mc.controlled


def test_state_var_in_8_carries_count_and_motion_bits():
    link = homed()
    d = link.drive
    link.command(0x090, target=300, vmax=1000, acc=100, dec=100)
    link.advance(2 * MS)
    sv = struct.unpack("<H", tx1(link)[2:4])[0]
    assert sv == 0x0800 | 0x80 | 0x20 | link.count                   # homed, motion active, count echo
    link.wait(lambda: d.mc.in_target, 1000 * MS)
    link.advance(MS)
    assert struct.unpack("<H", tx1(link)[2:4])[0] == 0x0800 | 0x80 | 0x40 | link.count
