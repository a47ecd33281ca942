"""The E1100's PDOs on the emulated drive (spec/linmot-canopen.md 4, spec/linmot-motion.md 4): transmission
types 254 (inhibit time, event timer), 1..240 (SYNC), 250 (poll/response), RxPDOs evaluated on SYNC, the header /
slave header rule, the mapping parameters (RxPDO1 with a command, RxPDO3 lengths and Direct Par, TxPDO by UPID),
bad mappings, and PDOs only in Operational."""

from __future__ import annotations

import struct

import pytest

from linmot_st.bus.frame import Frame
from linmot_st.emulator import DriveTimings, E1100Drive, load_profile
from linmot_st.emulator.testing import MotionLink
from linmot_st.protocol import commands as C

MS = 1_000_000
MM = 10_000


def drive(defaults: dict | None = None) -> E1100Drive:
    values = {0x1194: 2, 0x146F: 280 * MM, 0x146E: -10 * MM}
    values.update(defaults or {})
    return E1100Drive(1, load_profile().with_defaults(values), timings=DriveTimings.fast())


def sdo_write(link, index: int, sub: int, value: int, size: int) -> bytes:
    cs = {1: 0x2F, 2: 0x2B, 4: 0x23}[size]
    return link.sdo(struct.pack("<BHB", cs, index, sub) + value.to_bytes(size, "little").ljust(4, b"\0"))


def preop_link(defaults: dict | None = None) -> MotionLink:
    return MotionLink(drive(defaults), operational=False)


def homed(link: MotionLink) -> MotionLink:
    link.nmt(0x01)
    link.advance(MS)
    link.enable()
    link.home()
    link.advance(MS)
    return link


def test_pdos_flow_only_in_operational():
    link = preop_link()
    link.cw(0x003E)
    link.advance(10 * MS)
    assert link.pdos(1) == [] and link.drive.mc.state == 1            # RxPDO1 not evaluated in Pre-Operational
    link.nmt(0x01)
    link.advance(MS)
    assert len(link.pdos(1)) == 1 and len(link.pdos(2)) == 1           # each event PDO once on entering
    link.cw(0x003E)
    link.advance(MS)
    assert link.drive.mc.state == 2
    link.nmt(0x02)                                                     # Stopped
    t = link.t
    link.cw(0x003F)
    link.advance(50 * MS)
    assert link.pdos(1, t) == [] and link.drive.mc.state == 2


def test_inhibit_time_spaces_event_pdos():
    link = preop_link()
    assert sdo_write(link, 0x1801, 3, 50, 2)[0] == 0x60                # TxPDO2 inhibit 5 ms (100 us units)
    homed(link)
    t0 = link.t
    link.command(C.VAI16_GO_TO_POS, target=500, vmax=1000, acc=100, dec=100)
    link.advance(300 * MS)
    times = [t for t, _ in link.pdos(2, t0)]
    gaps = [b - a for a, b in zip(times, times[1:])]
    assert len(times) > 20 and min(gaps) >= 5 * MS
    # the last one carries the final content: a change inside the inhibit time is sent when it ends
    assert struct.unpack("<HhhH", link.pdos(2)[-1][1])[1] == 500


def test_event_timer_sends_without_change():
    link = preop_link()
    sdo_write(link, 0x1800, 5, 20, 2)                                  # TxPDO1 every 20 ms at least
    link.nmt(0x01)
    link.advance(MS)
    t0 = link.t
    link.advance(200 * MS)
    times = [t for t, _ in link.pdos(1, t0)]
    assert len(times) == 10 and {b - a for a, b in zip(times, times[1:])} == {20 * MS}


def test_sync_transmission_and_rxpdos_evaluated_on_sync():
    link = preop_link()
    sdo_write(link, 0x1800, 2, 1, 1)                                   # TxPDO1 on every SYNC
    sdo_write(link, 0x1801, 2, 2, 1)                                   # TxPDO2 on every 2nd SYNC
    link.nmt(0x01)
    link.advance(MS)
    assert link.pdos(1) == []                                          # synchronous: nothing before a SYNC
    link.cw(0x003E)
    link.advance(5 * MS)
    assert link.drive.mc.state == 1                                    # the control word waits for the SYNC
    for _ in range(4):
        link.send(Frame(0x080, b""))
        link.advance(MS)
    assert link.drive.mc.state == 2
    assert len(link.pdos(1)) == 4 and len(link.pdos(2)) == 2
    assert struct.unpack("<HHHH", link.pdos(1)[0][1])[1] == 0x0200     # sampled after the RxPDO was applied


def test_rxpdos_on_sync_by_parameter_with_asynchronous_txpdos():
    link = MotionLink(drive({0x2042: 1}))
    link.cw(0x003E)
    link.advance(5 * MS)
    assert link.drive.mc.state == 1
    link.send(Frame(0x080, b""))
    link.advance(MS)
    assert link.drive.mc.state == 2


def test_type_250_answers_each_rxpdo():
    link = preop_link()
    sdo_write(link, 0x1800, 2, 250, 1)
    link.nmt(0x01)
    link.advance(MS)
    t0 = link.t
    for _ in range(3):
        link.cw(0x003E)
        link.advance(MS)
    assert len(link.pdos(1, t0)) == 3                                  # one answer per RxPDO1, changed or not


def test_command_needs_both_headers_with_the_new_count():
    link = homed(preop_link())
    d = link.drive
    raw = C.encode(C.VAI16_GO_TO_POS, 5, target=300, vmax=1000, acc=100, dec=100)
    link.send(Frame(0x301, raw[:8]))
    link.send(Frame(0x401, bytes([0x04, 0x09]) + raw[8:10]))          # slave header with the old count
    link.advance(50 * MS)
    assert not d.mc.motion_active and d.mc.last_count != 5
    link.send(Frame(0x401, bytes([0xF5, 0xFF]) + raw[8:10]))          # only the low 4 bits count
    link.advance(MS)
    assert d.mc.motion_active and d.mc.last_count == 5
    # a repeated frame with the same count does nothing
    assert link.wait(lambda: d.mc.in_target, 2000 * MS)
    link.send(Frame(0x301, raw[:8]))
    link.send(Frame(0x401, raw[:2] + raw[8:10]))
    link.advance(5 * MS)
    assert not d.mc.motion_active


def test_header_alone_triggers_with_rxpdo3_off():
    link = preop_link()
    sdo_write(link, 0x1402, 1, 0x80000401, 4)                         # RxPDO3 not valid
    homed(link)
    link.send(Frame(0x301, C.encode(C.TIME_CURVE, 1, curve_id=9).ljust(8, b"\0")))
    link.advance(MS)
    assert link.drive.mc.error_code == 0x0062                          # executed (and refused: no curve 9)


def test_rxpdo1_with_control_word_and_command():
    link = homed(preop_link({0x2040: 1}))
    d = link.drive
    link.send(Frame(0x402, b""))                                       # (another node: ignored)
    # control word + header + par bytes 0..3: a 020xh predef VAI go to 25 mm in one frame, with RxPDO3's
    # slave header following
    raw = C.encode(C.PREDEF_VAI_GO_TO_POS, 3, target=25 * MM)
    link.send(Frame(0x201, struct.pack("<H", 0x003F) + raw))
    link.send(Frame(0x401, raw[:2] + b"\0\0"))
    assert link.wait(lambda: d.mc.in_target and d.mc.dem_p == 25 * MM, 3000 * MS)
    # the same frame again (the control word repeated each cycle): the count did not change, nothing starts
    link.rx1_command = raw
    link.cw(0x003F)
    link.advance(20 * MS)
    assert not d.mc.motion_active and d.mc.last_count == 3
    # RxPDO1 is 8 bytes in this mapping: a 2-byte control word is not processed
    link.send(Frame(0x201, struct.pack("<H", 0x003E)))
    link.advance(MS)
    assert d.mc.state == 8


@pytest.mark.parametrize("mode, length", [(0, 4), (1, 6), (2, 8)])
def test_rxpdo3_lengths(mode, length):
    link = homed(preop_link({0x2041: mode, 0x2050: 0x13A2}))
    d = link.drive
    raw = C.encode(C.WRITE_LIVE_PARAMETER, 2, upid=0x13A2, value=0x00012345).ljust(14, b"\0")
    link.send(Frame(0x301, raw[:8]))
    link.send(Frame(0x401, raw[:2] + raw[8:8 + length - 2]))
    link.advance(MS)
    assert d.mc.last_count == 2
    # value bytes 2..3 travel in par bytes 6..7: every mapping carries them
    assert d.params[0x13A2].ram == 0x2345
    # a frame shorter than the mapping is not processed
    raw = C.encode(C.WRITE_LIVE_PARAMETER, 3, upid=0x13A2, value=7)
    link.send(Frame(0x301, raw[:8]))
    link.send(Frame(0x401, raw[:2] + raw[8:8 + length - 3]))
    link.advance(MS)
    assert d.mc.last_count == 2 and d.params[0x13A2].ram == 0x2345


def test_rxpdo3_as_direct_parameters():
    link = homed(preop_link({0x2041: 3, 0x2050: 0x13A2, 0x2051: 0x13A3}))
    link.send(Frame(0x401, struct.pack("<HH", 21, 4)))
    link.advance(MS)
    assert link.drive.params[0x13A2].ram == 21 and link.drive.params[0x13A3].ram == 4


def test_txpdo3_by_upid_carries_the_32_bit_position():
    link = homed(preop_link({0x203B: 0x1B8D, 0x203C: 0x1BAF}))       # actual position, actual velocity
    d = link.drive
    link.command(C.VAI16_GO_TO_POS, target=1500, vmax=1000, acc=100, dec=100)
    link.advance(100 * MS)
    t, data = link.pdos(3)[-1]
    pos, vel = struct.unpack("<ii", data)
    sample = d.mc.trajectory.at(t - d.timings.pdo_latency_ns)         # the cycle the PDO was built in
    assert pos == round(sample.actual) and vel == round(sample.actual_velocity / 10) and 0 < vel <= 1_000_000
    link.wait(lambda: d.mc.in_target, 3000 * MS)
    link.advance(50 * MS)
    assert struct.unpack("<ii", link.pdos(3)[-1][1])[0] == pytest.approx(150 * MM, abs=200)


def test_txpdo1_by_upid():
    link = homed(preop_link({0x2030: 1, 0x2031: 0x1D51, 0x2032: 0x1B62, 0x2033: 0x1B8D}))
    sw, sv, pos = struct.unpack("<HHi", link.pdos(1)[-1][1])
    assert sv == 0x08C0 and sw == link.drive.mc.status_word and pos == 0


@pytest.mark.parametrize("upids, code", [((0x1B8D, 0x1B8D, 0x1B8D), 0xD3), ((0x7777,), 0xD9), ((0x03E8,), 0xD9)])
def test_bad_txpdo3_mapping_is_an_interface_error(upids, code):
    values = {0x203B + k: u for k, u in enumerate(upids)}
    link = MotionLink(drive(values))
    assert link.drive.mc.error_code == code and link.drive.mc.state == 4
    assert link.drive.errlog.entries[-1].code == code and link.pdos(3) == []


def test_mapping_is_read_when_entering_operational():
    """Interface parameters are not live: written to ROM, they take effect after the reset, then at NMT Start."""
    link = MotionLink(drive(), operational=False)
    assert link.sdo(struct.pack("<BHBI", 0x23, 0x2000 + 0x203B, 2, 0x1B8D))[0] == 0x60   # ROM
    link.nmt(0x01)
    link.advance(MS)
    assert link.pdos(3) == []
    link.nmt(0x81)                                                     # reset node: RAM = ROM
    assert link.wait(lambda: link.drive.booted, 10_000 * MS)
    link.nmt(0x01)
    link.advance(MS)
    assert len(link.pdos(3)) == 1



@pytest.mark.parametrize("position, demand, acceleration, scale, expected", [
    (1234.5, -987.5, 0.0, 1000, (1, 0, -1)),                    # in range: the common case
    (50_000_000.0, -50_000_000.0, 0.0, 1000, (32767, 0, -32768)),   # both positions saturate
    (10.0, 20.0, 1e12, 1000, (0, 32767, 0)),                     # the demand current saturates
    (-40_000.0, 40_000.0, -1e12, 0, (-32768, -32768, 32767)),    # scale 0 counts as 1
])
def test_txpdo2_default_content_is_the_mc_variables(position, demand, acceleration, scale, expected):
    """TxPDO2's packer (on every SYNC, its own arithmetic for speed) gives what variable() gives, saturated
    alike: motion command status, actual position 16 bit, demand current, demand position 16 bit."""
    d = drive()
    mc = d.mc
    mc.running = mc.controlled = True
    mc.last_header = 0x0123
    mc.axis.physical, mc.axis.offset, mc.axis.acceleration = position - 3.0, 3.0, acceleration
    mc.dem_p = demand
    d.params[0x14C8].ram = scale
    words = struct.unpack("<Hhhh", mc.txpdo2_payload())
    assert words == (0x0123, *expected)
    assert words[1:] == (mc.variable(0x1B95), mc.variable(0x1B93), mc.variable(0x1B94))
