"""The drive through its sans-I/O node API in virtual time: boot, NMT, heartbeat, SDO timing, reset and
persistence semantics (ROM vs RAM, flash vs RAM), MC start/stop, set-to-default, PDOs."""

from __future__ import annotations

import struct

import pytest

from linmot_st.bus import Frame
from linmot_st.emulator import (
    OPERATIONAL,
    PRE_OPERATIONAL,
    STOPPED,
    Curve,
    DriveTimings,
    E1100Drive,
    ProtocolOptions,
    build_entry,
    load_profile,
)
from linmot_st.emulator.testing import DirectLink

S, MS, US = 1_000_000_000, 1_000_000, 1_000


def up(index, sub):
    return struct.pack("<BHBI", 0x40, index, sub, 0)


def down(index, sub, value=0):
    return struct.pack("<BHBI", 0x23, index, sub, value & 0xFFFFFFFF)


def value_of(resp: bytes) -> int:
    assert resp[0] == 0x43, resp.hex(" ")
    return struct.unpack_from("<i", resp, 4)[0]


def result_of(resp: bytes) -> int:
    assert resp[0] == 0x60, resp.hex(" ")
    return resp[6]


def abort_of(resp: bytes) -> int:
    assert resp[0] == 0x80, resp.hex(" ")
    return struct.unpack_from("<I", resp, 4)[0]


# ---------------------------------------------------------------------------- boot and NMT
def test_boot_up_message_after_boot_time_and_silence_before():
    d = E1100Drive(5)
    assert d.on_frame(Frame(0x605, up(0x1000, 0)), 0) == [] and d.next_timer_ns() is None   # off
    d.power_on(1000)
    assert d.next_timer_ns() == 1000 + d.timings.boot_ns
    assert d.on_frame(Frame(0x605, up(0x1000, 0)), 2000) == []                               # booting: silent
    out = d.on_timer(d.next_timer_ns())
    assert out == [(1000 + 4 * S, Frame(0x705, b"\x00"))]
    assert d.nmt_state == PRE_OPERATIONAL


def test_sdo_turnaround_is_configurable_and_fits_a_1ms_scan():
    for turnaround in (150 * US, 400 * US):
        d = E1100Drive(1, timings=DriveTimings(sdo_turnaround_ns=turnaround))
        link = DirectLink(d)
        t0 = link.t
        [(ready, frame)] = d.on_frame(Frame(0x601, up(0x1018, 1)), t0)
        assert ready == t0 + turnaround and frame.can_id == 0x581
    assert DriveTimings().sdo_turnaround_ns < 300 * US


def test_nmt_states_and_sdo_availability():
    link = DirectLink(E1100Drive(1))
    d = link.node
    link.nmt(0x01)
    assert d.nmt_state == OPERATIONAL
    assert link.sdo(up(0x1000, 0)) is not None
    link.nmt(0x02)
    assert d.nmt_state == STOPPED
    assert link.sdo(up(0x1000, 0), timeout_ns=10 * MS) is None         # CiA 301: no SDO in Stopped
    link.nmt(0x80)
    assert d.nmt_state == PRE_OPERATIONAL and link.sdo(up(0x1000, 0)) is not None
    link.nmt(0x01, node_id=2)                                           # another node: ignored
    assert d.nmt_state == PRE_OPERATIONAL
    link.nmt(0x01, node_id=0)                                           # all nodes
    assert d.nmt_state == OPERATIONAL


def test_heartbeat_producer():
    link = DirectLink(E1100Drive(1))
    assert link.advance(3 * S) == []                                   # 1017h = 0: no heartbeat
    assert link.sdo(struct.pack("<BHBHH", 0x2B, 0x1017, 0, 100, 0))[0] == 0x60
    t0 = link.t - link.node.timings.sdo_turnaround_ns                 # the write takes effect when received
    beats = link.advance(350 * MS)
    assert [f for _, f in beats] == [Frame(0x701, b"\x7f")] * 3
    assert [t - t0 for t, _ in beats] == [100 * MS, 200 * MS, 300 * MS]
    link.nmt(0x01)
    assert Frame(0x701, b"\x05") in [f for _, f in link.advance(150 * MS)]
    link.nmt(0x02)
    assert Frame(0x701, b"\x04") in [f for _, f in link.advance(150 * MS)]


def test_heartbeat_from_interface_parameters_at_boot():
    profile = load_profile().with_defaults({0x2020: 1, 0x2021: 250})
    link = DirectLink(E1100Drive(1, profile))
    assert link.sdo(up(0x1017, 0))[4:6] == struct.pack("<H", 250)
    assert [t - link.received[0][0] for t, f in link.advance(600 * MS) if f.data == b"\x7f"] == [250 * MS, 500 * MS]


def test_reset_communication_keeps_ram_and_resets_comm_objects():
    link = DirectLink(E1100Drive(1))
    d = link.node
    link.sdo(down(0x33A2, 1, 55))                                          # RAM of a live parameter
    link.sdo(struct.pack("<BHBHH", 0x2B, 0x1017, 0, 100, 0))
    link.nmt(0x82)
    boot = link.wait_for(lambda f: f.can_id == 0x701 and f.data == b"\x00", 50 * MS)
    assert boot is not None and d.nmt_state == PRE_OPERATIONAL
    assert d.ram(0x13A2) == 55                                             # the drive did not restart
    assert d.comm.value(0x1017) == 0                                       # communication objects reset


def test_reset_node_reloads_ram_from_rom_and_stores_from_flash():
    d = E1100Drive(1)
    d.curves.flash[7] = Curve.build(7, [0, 100, 200])
    d.ct.flash[3] = build_entry(0x0101, name="three")
    link = DirectLink(d)
    assert link.sdo(down(0x33A2, 1, 55))[0] == 0x60                        # RAM only
    assert link.sdo(down(0x33A2, 2, 66))[0] == 0x60                        # ROM only
    link.sdo(down(0x2000, 0x41))                                           # delete all curves (RAM)
    link.sdo(down(0x2000, 0x81))                                           # delete all CT entries (RAM)
    assert d.curves.ram == {} and d.ct.ram == {}
    link.nmt(0x81)
    assert link.wait_for(lambda f: f.can_id == 0x701, 5 * S) == Frame(0x701, b"\x00")
    assert (d.ram(0x13A2), d.rom(0x13A2)) == (66, 66)
    assert set(d.curves.ram) == {7} and set(d.ct.ram) == {3}


def test_software_reset_answers_first_then_reboots():
    link = DirectLink(E1100Drive(1))
    d = link.node
    link.sdo(down(0x3194, 2, 2))                                           # Motor Type ROM (non-live)
    t0 = link.t
    assert link.sdo(down(0x2000, 0x0B)) == bytes.fromhex("60 00 20 0B 00 00 00 00")
    assert link.t - t0 == d.timings.sdo_turnaround_ns
    assert link.sdo(up(0x1000, 0), timeout_ns=100 * MS) is None            # rebooting: silent
    boot = link.wait_for(lambda f: f.can_id == 0x701, 5 * S)
    assert boot.data == b"\x00" and d.ram(0x3194 - 0x2000) == 2
    assert d.mc.state_var >> 8 == 1                                        # motor defined: no setup error now


def test_power_cycle_keeps_rom_flash_and_error_log():
    d = E1100Drive(1)
    link = DirectLink(d)
    link.sdo(down(0x33A2, 2, 66))
    assert len(d.errlog.entries) == 1                                      # 64h at boot: no motor defined
    link = DirectLink(d, t_ns=link.t + S)                                  # power on again
    assert d.rom(0x13A2) == 66 == d.ram(0x13A2)
    assert [e.code for e in d.errlog.entries] == [0x64, 0x64] and d.errlog.occurred == 2


# ---------------------------------------------------------------------------- system services, timing
@pytest.mark.parametrize("sub, layer, seconds", [(0x07, 1, 0.5), (0x08, 2, 2.0), (0x09, 3, 0.5), (0x0A, 4, 0.5)])
def test_set_default_takes_its_time_and_blocks_the_sdo_server(sub, layer, seconds):
    link = DirectLink(E1100Drive(1))
    d = link.node
    upid = {1: 0x0420, 2: 0x13A2, 3: 0x2011, 4: 0x3000}[layer]
    link.sdo(down(0x2000 + upid, 2, 1 if layer != 3 else 4))
    t0 = link.t
    link.send(Frame(0x601, down(0x2000, sub)))
    link.advance(10 * MS)
    assert d.sdo_busy
    link.send(Frame(0x601, up(0x1000, 0)))                                 # dropped while busy
    answer = link.wait_for(lambda f: f.can_id == 0x581, 5 * S)
    assert answer.data[:4] == bytes([0x60, 0x00, 0x20, sub])
    assert link.t - t0 == int(seconds * S) + d.timings.sdo_turnaround_ns
    assert [f for _, f in link.received if f.can_id == 0x581][-1] == answer  # nothing else answered
    assert d.rom(upid) == d.params[upid].default


def test_mc_stop_start_and_flash_save_policy():
    link = DirectLink(E1100Drive(1))
    d = link.node
    assert result_of(link.sdo(down(0x2000, 0x40))) == 0xD7                  # MC runs
    t0 = link.t
    assert result_of(link.sdo(down(0x2000, 0x35), timeout_ns=S)) == 0
    assert link.t - t0 == d.timings.mc_stop_ns + d.timings.sdo_turnaround_ns and d.mc_phase == "stopped"
    assert result_of(link.sdo(down(0x2000, 0x40))) == 0
    assert d.flash_busy()
    t0 = link.t
    start = link.sdo(down(0x2000, 0x36))
    assert abort_of(start) == 0x08000022                                   # no MC start while flash is written
    while value_of(link.sdo(up(0x2000, 0x42))) == 4:
        link.advance(10 * MS)
    assert 300 * MS <= link.t - t0 <= 400 * MS
    t0 = link.t
    assert result_of(link.sdo(down(0x2000, 0x36), timeout_ns=5 * S)) == 0
    assert link.t - t0 == d.timings.mc_start_ns + d.timings.sdo_turnaround_ns and d.mc_phase == "running"


def test_state_refusal_can_be_an_abort():
    link = DirectLink(E1100Drive(1, protocol=ProtocolOptions(save_refusal="abort")))
    assert abort_of(link.sdo(down(0x2000, 0x40))) == 0x08000022
    assert abort_of(link.sdo(down(0x2000, 0x80))) == 0x08000022


def test_mc_start_copies_rom_to_ram_of_mc_layer_only():
    link = DirectLink(E1100Drive(1))
    d = link.node
    link.sdo(down(0x33A2, 2, 66))                                          # MC layer, ROM only
    link.sdo(down(0x2430, 2, 1))                                           # OS layer 0430h, ROM only
    link.sdo(down(0x2000, 0x35), timeout_ns=S)
    link.sdo(down(0x2000, 0x36), timeout_ns=5 * S)
    assert d.ram(0x13A2) == 66 and d.ram(0x0430) == 0


def test_flash_save_duration_grows_with_the_data():
    durations = []
    for n in (0, 20):
        d = E1100Drive(1)
        for k in range(1, n + 1):
            d.curves.flash[k] = Curve.build(k, list(range(200)))           # 870 bytes each
        link = DirectLink(d)
        link.sdo(down(0x2000, 0x35), timeout_ns=S)
        link.sdo(down(0x2000, 0x40))
        t0 = link.t
        while value_of(link.sdo(up(0x2000, 0x42))) == 4:
            link.advance(MS)
        durations.append(link.t - t0)
    assert durations[0] < 320 * MS < 600 * MS < durations[1]


# ---------------------------------------------------------------------------- persistence of curves and CT
def _download_curve(link, curve: Curve, two_byte: bool = False):
    idx = 0x2000 + curve.curve_id
    codes = [result_of(link.sdo(struct.pack("<BHBHH", 0x23, idx, 0x50, len(curve.info), len(curve.data))))]
    info = curve.info + b"\0\0"
    if two_byte:
        codes += [result_of(link.sdo(struct.pack("<BHBH", 0x23, idx, 0x51, 0) + curve.info[k:k + 2]))
                  for k in range(0, 70, 2)]
        codes += [result_of(link.sdo(struct.pack("<BHBH", 0x23, idx, 0x52, 0) + curve.data[k:k + 2]))
                  for k in range(0, len(curve.data), 2)]
    else:
        codes += [result_of(link.sdo(struct.pack("<BHB", 0x23, idx, 0x54) + info[k:k + 4])) for k in range(0, 72, 4)]
        codes += [result_of(link.sdo(struct.pack("<BHB", 0x23, idx, 0x53) + curve.data[k:k + 4]))
                  for k in range(0, len(curve.data), 4)]
    return codes


def _upload_curve(link, cid: int) -> Curve | None:
    resp = link.sdo(up(0x2000 + cid, 0x60))
    rc, info_size, data_size = struct.unpack_from("<BBH", resp, 4)
    if rc:
        return None
    info = b"".join(link.sdo(up(0x2000 + cid, 0x61))[4:] for _ in range(-(-info_size // 4)))[:info_size]
    data = b"".join(link.sdo(up(0x2000 + cid, 0x62))[4:] for _ in range(data_size // 4))
    return Curve(cid, info, data)


@pytest.mark.parametrize("two_byte", [False, True])
def test_curve_round_trip_and_persistence(two_byte):
    curve = Curve.build(42, [k * k - 500 for k in range(100)], name="Parabola", x_length=50_000)
    link = DirectLink(E1100Drive(1))
    d = link.node
    codes = _download_curve(link, curve, two_byte)
    assert codes[0] == 0 and codes[-1] == 0 and set(codes[1:-1]) <= {0, 4}
    assert codes.count(0) == 3                                             # add, info finished, data finished
    assert d.curves.ram[42] == curve and d.curves.flash == {}
    assert _upload_curve(link, 42) == curve
    assert curve.setpoints[:3] == [-500, -499, -496] and d.curves.ram[42].name == "Parabola"
    link.nmt(0x81)                                                         # not saved: lost at reset
    link.wait_for(lambda f: f.can_id == 0x701, 5 * S)
    assert d.curves.ram == {} and _upload_curve(link, 42) is None
    _download_curve(link, curve, two_byte)
    link.sdo(down(0x2000, 0x35), timeout_ns=S)
    assert result_of(link.sdo(down(0x2000, 0x40))) == 0
    link.advance(S)
    assert d.curves.flash[42] == curve
    link.nmt(0x81)
    link.wait_for(lambda f: f.can_id == 0x701, 5 * S)
    assert _upload_curve(link, 42) == curve                               # saved: back after the reset


def test_incomplete_curve_is_not_present_and_not_saved():
    link = DirectLink(E1100Drive(1))
    d = link.node
    link.sdo(struct.pack("<BHBHH", 0x23, 0x2009, 0x50, 70, 16))
    assert d.curves.in_progress() == [9] and link.sdo(up(0x2009, 0x60))[4] == 0xD4
    link.sdo(down(0x2000, 0x35), timeout_ns=S)
    link.sdo(down(0x2000, 0x40))
    link.advance(S)
    assert d.curves.flash == {}


def test_curve_memory_limit():
    link = DirectLink(E1100Drive(1, curve_capacity_bytes=1000))
    assert result_of(link.sdo(struct.pack("<BHBHH", 0x23, 0x2001, 0x50, 70, 900))) == 0
    assert result_of(link.sdo(struct.pack("<BHBHH", 0x23, 0x2002, 0x50, 70, 40))) == 0xD1


def test_command_table_write_save_reset_read():
    entry = build_entry(0x0101, struct.pack("<iIII", 500000, 1000000, 1000000, 1000000), name="GoTo50mm")
    link = DirectLink(E1100Drive(1))
    d = link.node
    assert result_of(link.sdo(struct.pack("<BHBHH", 0x23, 0x2000 + 200, 0x83, 64, 0))) == 0
    codes = [result_of(link.sdo(struct.pack("<BHBH", 0x23, 0x2000 + 200, 0x84, 0) + entry[k:k + 2]))
             for k in range(0, 64, 2)]
    assert codes == [4] * 31 + [0]
    assert d.ct.ram[200] == entry
    assert link.sdo(up(0x2000, 0x8D))[4:] == struct.pack("<I", 0xFFFFFEFF)   # 192..223: bit 8 = entry 200
    link.nmt(0x81)
    link.wait_for(lambda f: f.can_id == 0x701, 5 * S)
    assert d.ct.ram == {}                                                  # not saved: lost
    d.ct.ram[200] = entry
    link.sdo(down(0x2000, 0x35), timeout_ns=S)
    assert result_of(link.sdo(down(0x2000, 0x80))) == 0
    assert value_of(link.sdo(up(0x2000, 0x80))) == 4
    link.advance(S)
    assert value_of(link.sdo(up(0x2000, 0x80))) == 0 and d.ct.flash == {200: entry}
    link.sdo(down(0x2000, 0x0B))
    link.wait_for(lambda f: f.can_id == 0x701, 5 * S)
    assert link.sdo(up(0x2000 + 200, 0x85))[4:] == bytes([0, 0, 64, 0])
    data = b"".join(link.sdo(up(0x2000 + 200, 0x86))[6:8] for _ in range(32))
    assert data == entry


# ---------------------------------------------------------------------------- PVL example, tree mismatch
def test_seeds_pvl_example_is_writable():
    rows = {0x03E9: 0x6F43794D, 0x03EA: 0x6F72746E, 0x03EB: 0x72656C6C, 0x03F3: 0x78412058,
            0x03F4: 0x4C207369, 0x03F5: 0x00746665, 0x1194: 0x00000002}
    rows.update({u: 0 for u in (0x03EC, 0x03ED, 0x03EE, 0x03EF, 0x03F0, 0x03F6, 0x03F7, 0x03F8, 0x03F9, 0x03FA)})
    link = DirectLink(E1100Drive(1))
    d = link.node
    for upid, value in rows.items():
        assert link.sdo(down(0x2000 + upid, 2, value)) == struct.pack("<BHBI", 0x60, 0x2000 + upid, 2, 0)
    assert d.string(0x03E8) == "MyController" and d.string(0x03F2) == "X Axis Left"
    assert d.rom(0x1194) == 2


def test_drive_with_a_mismatching_tree():
    d = E1100Drive(1, load_profile().with_tree(2, tree_id=4613, main_version=4, sub_version=2))
    link = DirectLink(d)
    assert [value_of(link.sdo(up(0x2000 + u, 1))) for u in (0x0561, 0x055A, 0x055B)] == [4613, 4, 2]


# ---------------------------------------------------------------------------- MC state machine and PDOs
def test_control_word_drives_the_state_machine_and_txpdo1():
    d = E1100Drive(1, load_profile().with_defaults({0x1194: 2}))
    link = DirectLink(d)
    link.nmt(0x01)
    first = [f for _, f in link.advance(MS) if f.can_id == 0x181]
    sw, sv, err, warn = struct.unpack("<HHHH", first[0].data)
    assert sv >> 8 == 1 and warn == 0x0080 and sw & 0x0040 == 0               # switch on disabled
    link.send(Frame(0x201, struct.pack("<H", 0x0006)))
    link.send(Frame(0x201, struct.pack("<H", 0x003F)), dt_ns=MS)
    link.advance(500 * MS)
    states = [struct.unpack("<HHHH", f.data)[1] >> 8 for _, f in link.received if f.can_id == 0x181]
    # switch on disabled, ready to switch on, HW tests (300 ms), then ready to operate and at once (bit 3 set)
    # operation enabled: TxPDO1 is sent on change, the intermediate state 6 does not outlive the step
    assert states == [1, 2, 5, 8]
    sw = struct.unpack("<H", [f for _, f in link.received if f.can_id == 0x181][-1].data[:2])[0]
    assert sw & 0x0001 and sw & 0x0002 and sw & 0x0004
    assert value_of(link.sdo(up(0x3D51, 1))) == sw                         # status word variable 1D51h
    assert value_of(link.sdo(up(0x3B62, 1))) == 0x0840                     # state var: operation enabled, at
    #                                                                        rest: in target position (bit 6)


def test_setup_error_without_motor_and_error_register():
    link = DirectLink(E1100Drive(1))
    d = link.node
    assert d.mc.state_var == 0x0364 and d.mc.status_word & 0x0008
    assert link.sdo(up(0x1001, 0))[4] == 1
    link.nmt(0x01)
    [tx] = [f for _, f in link.advance(MS) if f.can_id == 0x181]
    assert struct.unpack("<HHHH", tx.data)[1:3] == (0x0364, 0x64)


def test_sync_driven_txpdo():
    link = DirectLink(E1100Drive(1))
    link.sdo(struct.pack("<BHBB3x", 0x2F, 0x1801, 2, 2))                    # TxPDO2 every 2nd SYNC
    link.nmt(0x01)
    link.advance(MS)
    n = len([1 for _, f in link.received if f.can_id == 0x281])
    for _ in range(4):
        link.send(Frame(0x080, b""), dt_ns=MS)
    link.advance(MS)
    assert len([1 for _, f in link.received if f.can_id == 0x281]) - n == 2
