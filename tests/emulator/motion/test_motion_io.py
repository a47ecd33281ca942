"""The drive's I/O (emulator/linmot/io.py) and the commands that use it (issue 20 sections 2 and 4): triggered
moves that start within one MC cycle after the trigger edge and not before, re-arming until 008xh, the trigger
modes' inhibit and delay times ([MC] 7.2.2), the captured position (X4.5, 1E62h, 0D0xh), the analog target
(X4.4, 019xh), the outputs with a mask (003xh/004xh), the limit switches ([MC] 7.2.3), a command-table wait for
a trigger edge (213xh), and the record of the I/O beside the trajectory.

Golden figures come from the manual's rules (edge + delay, one MC cycle of 1 ms), not from the emulator.
"""

from __future__ import annotations

import pytest

from linmot_st.emulator import DriveTimings, E1100Drive, build_entry, load_profile
from linmot_st.emulator.testing import MotionLink
from linmot_st.protocol import commands as C
from linmot_st.protocol import words as W
from linmot_st.protocol.upids import V_CAPTURED_POSITION

MS = 1_000_000
MM = 10_000
CYCLE = MS                        # the default MC cycle

# predefined VAI: 0.5 m/s, 5 m/s^2 (14BEh..14C0h)
PREDEF = {0x14BE: 500_000, 0x14BF: 500_000, 0x14C0: 500_000}


def homed_link(**defaults) -> MotionLink:
    values = {0x1194: 2, 0x170C: 1, 0x146F: 280 * MM, 0x146E: -10 * MM, **PREDEF}
    values.update({int(k[1:], 16) if isinstance(k, str) else k: v for k, v in defaults.items()})
    d = E1100Drive(1, load_profile().with_defaults(values), timings=DriveTimings.fast())
    link = MotionLink(d)
    link.enable()
    link.home()
    link.advance(5 * MS)
    return link


def first_motion(link, t0: int) -> int | None:
    """The time of the first sample after t0 with Motion Active (the cycle in which a motion starts: its demand
    leaves the start position from the next cycle on)."""
    for s in link.drive.mc.trajectory.between(t0):
        if s.status_word & W.SW_MOTION_ACTIVE:
            return s.t_ns
    return None


def test_triggered_move_starts_within_one_cycle_after_the_edge_and_not_before():
    link = homed_link()
    mc, io = link.drive.mc, link.drive.io
    t0 = link.t
    link.command(0x02A, target=50 * MM)           # Predef VAI Go To Pos On Rising Trigger Event
    link.advance(20 * MS)
    assert mc.status_word & W.SW_EVENT_HANDLER and mc.state_var & W.SV_EVENT_HANDLER
    assert first_motion(link, t0) is None and not mc.motion_active          # armed: nothing moves yet
    edge = link.t + 3 * MS + 300_000                                        # between two MC cycles
    io.set_input("X4.6", 1, edge)
    link.advance(400 * MS)
    start = first_motion(link, t0)
    assert start is not None and edge < start <= edge + CYCLE
    assert abs(mc.axis.position - 50 * MM) < 10 and mc.in_target
    assert mc.status_word & W.SW_EVENT_HANDLER                              # still armed ([MC] 4.3.6)


def test_an_edge_on_a_cycle_boundary_is_seen_one_cycle_later_at_most():
    link = homed_link()
    mc = link.drive.mc
    link.command(0x02A, target=20 * MM)
    link.advance(10 * MS)
    edge = (link.t // CYCLE + 5) * CYCLE
    t0 = link.t
    link.drive.io.set_input("X4.6", 1, edge)
    link.advance(200 * MS)
    start = first_motion(link, t0)
    assert edge < start <= edge + CYCLE
    assert mc.events.fired == [start]


def test_rearmed_on_every_edge_until_008h_clears_it():
    link = homed_link()
    mc, io = link.drive.mc, link.drive.io
    p0 = mc.axis.position
    link.command(0x02B, target=10 * MM)              # Predef VAI Increment Target Pos On Rising Trigger Event
    link.advance(5 * MS)
    io.pulse_train("X4.6", link.t + 10 * MS, 200 * MS, 20 * MS, 3)
    link.advance(700 * MS)
    assert len(mc.events.fired) == 3
    assert abs(mc.axis.position - (p0 + 30 * MM)) < 10                      # three increments of 10 mm
    link.command(C.CLEAR_EVENT_EVALUATION)
    link.advance(5 * MS)
    assert not mc.status_word & W.SW_EVENT_HANDLER
    io.pulse_train("X4.6", link.t + 10 * MS, 50 * MS, 10 * MS, 2)
    link.advance(200 * MS)
    assert len(mc.events.fired) == 3 and abs(mc.axis.position - (p0 + 30 * MM)) < 10


def test_falling_edge_variant_ignores_the_rising_edge():
    link = homed_link()
    mc, io = link.drive.mc, link.drive.io
    p0 = mc.axis.position
    link.command(0x09C, target=30, vmax=500, acc=500, dec=500)   # VAI 16 Bit Go To Pos On Falling Trigger Event
    link.advance(5 * MS)
    rise, fall = link.t + 10 * MS, link.t + 60 * MS
    io.set_input("X4.6", 1, rise)
    io.set_input("X4.6", 0, fall)
    t0 = link.t
    link.advance(300 * MS)
    assert fall < first_motion(link, t0) <= fall + CYCLE
    assert abs(mc.axis.position - 30 * 1000) < 10 and p0 != mc.axis.position   # 16-bit scale 1000 pu


def test_clear_event_evaluation_before_the_edge_moves_nothing():
    link = homed_link()
    mc = link.drive.mc
    t0 = link.t
    link.command(0x02A, target=50 * MM)
    link.advance(5 * MS)
    link.command(C.CLEAR_EVENT_EVALUATION)
    link.advance(5 * MS)
    assert not mc.status_word & W.SW_EVENT_HANDLER
    link.drive.io.set_input("X4.6", 1, link.t + MS)
    link.advance(100 * MS)
    assert first_motion(link, t0) is None and mc.events.fired == []


def test_trigger_mode_none_ignores_the_input():
    link = homed_link(**{"x170C": 0})
    link.command(0x02A, target=50 * MM)
    t0 = link.t
    link.drive.io.set_input("X4.6", 1, link.t + 5 * MS)
    link.advance(100 * MS)
    assert link.drive.io.input("X4.6") == 1 and first_motion(link, t0) is None


def test_delayed_mode_moves_the_edge_by_the_delay_time():
    # mode 3 (delayed): rise delay 170Fh = 150 x 100 us = 15 ms (the unit is INFERRED, IoSettings)
    link = homed_link(**{"x170C": 3, "x170F": 150})
    mc = link.drive.mc
    link.command(0x02A, target=40 * MM)
    link.advance(5 * MS)
    edge = link.t + 2 * MS + 500_000
    t0 = link.t
    link.drive.io.set_input("X4.6", 1, edge)
    link.advance(300 * MS)
    start = first_motion(link, t0)
    assert edge + 15 * MS < start <= edge + 15 * MS + CYCLE
    assert link.drive.mc.trajectory.io_at("trigger", edge + 15 * MS - 1) in (None, 0)
    assert mc.trajectory.io_at("trigger", edge + 15 * MS) == 1


def test_inhibited_mode_debounces_a_bouncing_contact():
    # mode 2: after a rising edge further edges are ignored for 170Dh = 50 x 100 us = 5 ms, after a falling one
    # for 170Eh = 5 ms
    link = homed_link(**{"x170C": 2, "x170D": 50, "x170E": 50})
    mc, io = link.drive.mc, link.drive.io
    p0 = mc.axis.position
    link.command(0x02B, target=5 * MM)
    link.advance(5 * MS)
    t = link.t + 10 * MS
    # a contact bouncing for 3 ms: rise, fall, rise, fall, rise every 0.7 ms; then a clean release and press
    io.play("X4.6", [(t, 1), (t + 700_000, 0), (t + 1_400_000, 1), (t + 2_100_000, 0), (t + 2_800_000, 1),
                     (t + 100 * MS, 0), (t + 200 * MS, 1)])
    link.advance(400 * MS)
    assert len(mc.events.fired) == 2                                       # one per press, not per bounce
    assert abs(mc.axis.position - (p0 + 10 * MM)) < 10
    rises = [c.t_ns for c in mc.trajectory.io if c.name == "trigger" and c.value == 1]
    assert rises == [t, t + 200 * MS]


def test_inhibited_mode_takes_the_level_when_the_inhibit_time_ends():
    link = homed_link(**{"x170C": 2, "x170D": 50, "x170E": 50})
    io = link.drive.io
    link.command(0x02C, target=30 * MM)               # Predef VAI Go To Pos On Falling Trigger Event
    link.advance(5 * MS)
    t = link.t + 10 * MS
    io.play("X4.6", [(t, 1), (t + 1 * MS, 0)])        # released inside the rise inhibit time
    t0 = link.t
    link.advance(200 * MS)
    # the debounced signal falls when the 5 ms end (INFERRED: the level then is taken)
    assert t + 5 * MS < first_motion(link, t0) <= t + 5 * MS + CYCLE


def test_captured_position_and_vai_increment_captured_pos():
    link = homed_link()
    d = link.drive
    mc, io = d.mc, d.io
    link.command(C.PREDEF_VAI_GO_TO_POS, target=100 * MM)
    link.advance(50 * MS)                              # moving
    t_cap = link.t + 3 * MS
    io.set_input("X4.5", 1, t_cap)
    link.advance(10 * MS)
    sample = mc.trajectory.at(t_cap)
    assert io.captured_position == pytest.approx(sample.actual, abs=1)
    assert mc.variable(V_CAPTURED_POSITION) == io.captured_position
    captured = io.captured_position
    link.advance(500 * MS)                             # at 100 mm
    # 0D0xh carries 16 parameter bytes: a command-table entry started by 200xh (Transport.COMMAND_TABLE)
    assert C.COMMANDS[C.VAI_INCREMENT_CAPTURED_POS].transport is C.Transport.COMMAND_TABLE
    d.ct.ram[1] = build_entry(C.VAI_INCREMENT_CAPTURED_POS << 4,
                              C.encode(C.VAI_INCREMENT_CAPTURED_POS, 0, target=-5 * MM, vmax=500_000, acc=500_000,
                                       dec=500_000)[2:])
    link.command(C.START_COMMAND_TABLE, entry=1)
    link.advance(500 * MS)
    assert mc.error_code == 0 and abs(mc.axis.position - (captured - 5 * MM)) < 10


def test_vai_go_to_analog_pos_follows_the_analog_input():
    # INVENTED scaling 14DCh/14DDh: 0 V -> 0 mm, 10 V -> 200 mm
    link = homed_link(**{"x14DC": 0, "x14DD": 200 * MM})
    d = link.drive
    ramp = link.t
    d.io.analog_ramp(ramp, ramp + 100 * MS, 0.0, 5.0, steps=50)           # a ramp to 5 V over 100 ms
    link.advance(150 * MS)
    assert d.io.analog() == 5.0 and d.mc.trajectory.io_at("X4.4", ramp + 50 * MS) == pytest.approx(2.5)
    d.ct.ram[2] = build_entry(C.VAI_GO_TO_ANALOG_POS << 4,
                              C.encode(C.VAI_GO_TO_ANALOG_POS, 0, vmax=500_000, acc=500_000, dec=500_000)[2:])
    link.command(C.START_COMMAND_TABLE, entry=2)
    link.advance(600 * MS)
    assert d.mc.error_code == 0 and abs(d.mc.axis.position - 100 * MM) < 10       # 5 V of 10 V: 100 mm


def test_outputs_with_mask():
    link = homed_link()
    io = link.drive.io
    link.command(C.WRITE_X4_OUTPUTS, mask=0b0000_0101, value=0b1111_1111)      # X4.3 and X4.5 on
    link.advance(2 * MS)
    assert io.outputs("X4") == 0b101 and io.output("X4.3") == 1 and io.output("X4.4") == 0
    link.command(C.WRITE_X4_OUTPUTS, mask=0b0000_0011, value=0b0000_0010)      # X4.3 off, X4.4 on, X4.5 kept
    link.command(C.WRITE_X6_OUTPUTS, mask=0x8001, value=0xFFFF)
    link.advance(2 * MS)
    assert io.outputs("X4") == 0b110 and io.output("X4.5") == 1
    assert io.outputs("X6") == 0x8001 and io.output("X6.15") == 1 and io.output("X6.1") == 0
    assert link.drive.mc.state == W.OPERATION_ENABLED                        # accepted, no 0081h
    names = [(c.name, c.value) for c in link.drive.mc.trajectory.io]
    assert names[:2] == [("X4.3", 1), ("X4.5", 1)] and ("X4.3", 0) in names


@pytest.mark.parametrize("mode, state", [(1, W.ERROR), (2, W.ERROR_QUICK_STOP)])
def test_limit_switch_raises_its_error_with_the_configured_behaviour(mode, state):
    link = homed_link(**{"x121B": mode})
    mc = link.drive.mc
    link.command(C.PREDEF_VAI_GO_TO_POS, target=200 * MM)
    link.advance(60 * MS)
    t = link.t + MS
    link.drive.io.set_input("X4.9", 1, t)                                      # Limit OUT reached
    link.drive.observe(t)
    link.run_until(t)
    assert mc.state == state and mc.error_code == 0x0088 and not mc.homed
    if mode == 2:                                                              # quick stop, then error
        link.advance(500 * MS)
        assert mc.state == W.ERROR and abs(mc.axis.velocity) < 1


def test_limit_switch_without_error_behaviour_does_nothing():
    link = homed_link()                                                        # 121Bh = 0
    link.drive.io.set_input("X4.8", 1, link.t + MS)
    link.advance(10 * MS)
    assert link.drive.mc.state == W.OPERATION_ENABLED and link.drive.mc.homed


def test_command_table_waits_for_the_rising_trigger():
    link = homed_link()
    d = link.drive
    p0 = d.mc.axis.position
    d.ct.ram[1] = build_entry(C.WAIT_RISING_TRIGGER << 4, b"", link=2)
    d.ct.ram[2] = build_entry(C.PREDEF_VAI_INCREMENT_DEM_POS << 4,
                              C.encode(C.PREDEF_VAI_INCREMENT_DEM_POS, 0, target=10 * MM)[2:], link=0xFFFF)
    link.command(C.START_COMMAND_TABLE, entry=1)
    link.advance(50 * MS)
    assert d.mc.ct_runner.running and d.mc.axis.position == p0
    edge = link.t + 7 * MS + 100_000
    t0 = link.t
    d.io.set_input("X4.6", 1, edge)
    link.advance(300 * MS)
    # Motion Active is on while the table runs (INFERRED); the demand leaves p0 one cycle after the entry ran
    moved = next(s.t_ns for s in d.mc.trajectory.between(t0) if abs(s.demand - p0) > 0.01)
    assert edge + CYCLE < moved <= edge + 2 * CYCLE
    assert abs(d.mc.axis.position - (p0 + 10 * MM)) < 10


def test_start_command_table_on_rising_trigger():
    link = homed_link()
    d = link.drive
    p0 = d.mc.axis.position
    d.ct.ram[5] = build_entry(C.PREDEF_VAI_INCREMENT_DEM_POS << 4,
                              C.encode(C.PREDEF_VAI_INCREMENT_DEM_POS, 0, target=5 * MM)[2:])
    link.command(C.START_COMMAND_TABLE_ON_RISE, entry=5)
    link.advance(5 * MS)
    d.io.pulse_train("X4.6", link.t + 5 * MS, 150 * MS, 10 * MS, 2)
    link.advance(400 * MS)
    assert abs(d.mc.axis.position - (p0 + 10 * MM)) < 10 and len(d.mc.events.fired) == 2


def test_inputs_are_readable_and_recorded():
    link = homed_link()
    io = link.drive.io
    io.set_input("X4.7", 1, link.t + MS)
    io.set_analog(2.5, link.t + 2 * MS)
    link.advance(5 * MS)
    assert io.input("X4.7") == 1 and io.analog() == 2.5
    io.set_input("X6.2", 1)
    link.advance(MS)
    assert io.input_word("X6") == 0b100 and io.input_word() == 1 << 4 and io.outputs("X6") == 0
    assert link.drive.mc.variable(0x1DA0) == 1 << 4 and link.drive.mc.variable(0x1DA3) == 2500
    with pytest.raises(ValueError):
        io.set_input("X4.6", 1, link.t - MS)                   # the past cannot change
    with pytest.raises(KeyError):
        io.set_input("X9.1", 1)


# ---------------------------------------------------------------- every row of this part of issue 20 is accepted
from linmot_st.protocol.commands.triggered import TRIGGERED  # noqa: E402

ROWS = sorted(set(TRIGGERED) | {C.WRITE_X4_OUTPUTS, C.WRITE_X6_OUTPUTS, C.CLEAR_EVENT_EVALUATION,
                                C.VAI_GO_TO_ANALOG_POS, C.VAI_INCREMENT_CAPTURED_POS, C.VAI_START_TRIG_RISE_CONFIG,
                                C.VAI_START_TRIG_FALL_CONFIG, C.WAIT_RISING_TRIGGER, C.WAIT_FALLING_TRIGGER})
SMALL = {"target": 10, "vmax": 100, "acc": 100, "dec": 100, "curve_id": 1, "offset": 0, "curve_time": 100_000,
         "amplitude": 1000, "entry": 1, "mask": 1, "value": 1}


@pytest.mark.parametrize("cid", ROWS, ids=lambda c: f"{c:03X}h")
def test_every_row_is_accepted(cid):
    """Sent as the catalogue's transport says: RxPDO2 + RxPDO3 (2041h = 2: parameter bytes 6..11) up to 12
    bytes, a command-table entry started by 200xh beyond; the drive runs it without 0081h or any other error."""
    row = C.COMMANDS[cid]
    link = homed_link(**{"x2041": 2})
    d = link.drive
    d.ct.ram[1] = build_entry(C.NOP << 4, b"")
    fields = {n: SMALL[n] for n in row.field_names}
    if row.transport is C.Transport.COMMAND_TABLE:
        d.ct.ram[9] = build_entry(cid << 4, C.encode(cid, 0, **fields)[2:])
        link.command(C.START_COMMAND_TABLE, entry=9)
    else:
        link.command(cid, **fields)
    link.advance(20 * MS)
    assert d.mc.error_code == 0 and d.mc.state == W.OPERATION_ENABLED, f"{d.mc.error_code:04X}h"
    assert d.mc.state_var & 0x0F == link.count                               # the count is echoed: executed
    assert [h >> 4 for _, h, _ in d.mc.executed][-1] == cid
    assert bool(d.mc.status_word & W.SW_EVENT_HANDLER) == (cid in TRIGGERED)


# ---------------------------------------------------------------- the fast path and the inputs
def _bus_run(quiet: bool):
    """On a SimBus with SYNC every 4 ms (TxPDO2 on SYNC: quiet cycles are computed ahead of the bus), a
    re-armed increment on the trigger while a pulse train plays; one pulse arrives during a motion."""
    import struct

    from linmot_st.bus import Frame, SimBus
    from linmot_st.bus.nodes import ScriptedNode
    from linmot_st.emulator.linmot.motion import MotionSettings

    def cmd(cid, count, **fields):
        raw = C.encode(cid, count, **fields).ljust(10, b"\0")
        return [Frame(0x301, raw[:8]), Frame(0x401, raw[:2] + raw[8:10])]

    cw = lambda w: Frame(0x201, struct.pack("<H", w))                               # noqa: E731
    s = [(50 * MS, Frame(0x601, struct.pack("<BHBBxxx", 0x2F, 0x1801, 2, 1))),
         (60 * MS, Frame(0x000, b"\x01\x01")), (61 * MS, cw(0x003E)), (70 * MS, cw(0x003F)),
         (120 * MS, cw(0x083F)), (150 * MS, cw(0x003F))]
    s += [(200 * MS, f) for f in cmd(0x02B, 1, target=10 * MM)]
    s += [(k * 4 * MS, Frame(0x080, b"")) for k in range(15, 400)]
    profile = load_profile().with_defaults({0x1194: 2, 0x170C: 4, 0x170D: 20, 0x170F: 35, **PREDEF})
    drive = E1100Drive(1, profile, timings=DriveTimings.fast(), motion=MotionSettings(quiet_cycles=quiet))
    bus = SimBus(1_000_000)
    bus.attach(drive, "drive")
    bus.attach(ScriptedNode(sorted(s, key=lambda x: x[0])), "master")
    drive.power_on(0)
    drive.io.pulse_train("X4.6", 250 * MS + 123_456, 90 * MS, 30 * MS, 6)
    drive.io.play("X4.6", [(900 * MS, 1), (900 * MS + 500_000, 0), (901 * MS, 1), (950 * MS, 0)])   # bounces
    for k in range(1, 17):
        bus.run_until(k * 100 * MS)
    trace = [(e.start_ns, e.frame.can_id, bytes(e.frame.data)) for e in bus.trace]
    return trace, list(drive.mc.trajectory.samples), drive


def test_triggered_moves_are_the_same_with_quiet_cycles():
    ref_trace, ref_samples, ref = _bus_run(False)
    trace, samples, drive = _bus_run(True)
    assert len(ref.mc.events.fired) == 7 and drive.mc.events.fired == ref.mc.events.fired
    assert drive.mc.error_code == 0 and abs(drive.mc.axis.position - 70 * MM) < 10    # seven 10 mm steps
    assert trace == ref_trace and samples == ref_samples
    assert drive.mc.trajectory.io == ref.mc.trajectory.io
    # each run starts in the first MC cycle after its (inhibited, then 3.5 ms delayed) edge
    edges = [c.t_ns for c in drive.mc.trajectory.io if c.name == "trigger" and c.value == 1]
    assert len(edges) == 7 and all(e < f <= e + CYCLE for e, f in zip(edges, drive.mc.events.fired))


def test_x43_as_brake_output_follows_operation_enabled():
    """[MC] 7.2.1.1: with brake mode 1717h the brake is released (X4.3 = 24 V) while Operation Enabled is set;
    003xh does not drive it then."""
    link = homed_link(**{"x1717": 1})
    io = link.drive.io
    assert io.output("X4.3") == 1
    link.command(C.WRITE_X4_OUTPUTS, mask=0b11, value=0b10)
    link.advance(2 * MS)
    assert io.output("X4.3") == 1 and io.output("X4.4") == 1
    link.cw(0x0037)                                              # enable operation off: state 6
    link.advance(5 * MS)
    assert link.drive.mc.state == W.READY_TO_OPERATE and io.output("X4.3") == 0 and io.outputs("X4") == 0b10


def test_vai_go_to_analog_pos_can_follow_the_input():
    """MotionSettings(analog_target_follows=True): the target follows X4.4 until another motion replaces it."""
    from linmot_st.emulator.linmot.motion import MotionSettings

    values = {0x1194: 2, 0x146F: 280 * MM, 0x146E: -10 * MM, 0x14DC: 0, 0x14DD: 200 * MM, **PREDEF}
    d = E1100Drive(1, load_profile().with_defaults(values), timings=DriveTimings.fast(),
                   motion=MotionSettings(analog_target_follows=True))
    link = MotionLink(d)
    link.enable()
    link.home()
    d.io.set_analog(1.0, link.t)
    d.ct.ram[2] = build_entry(C.VAI_GO_TO_ANALOG_POS << 4,
                              C.encode(C.VAI_GO_TO_ANALOG_POS, 0, vmax=500_000, acc=500_000, dec=500_000)[2:])
    link.command(C.START_COMMAND_TABLE, entry=2)
    link.advance(300 * MS)
    assert abs(d.mc.axis.position - 20 * MM) < 10                            # 1 V: 20 mm
    d.io.analog_ramp(link.t, link.t + 200 * MS, 1.0, 4.0, steps=20)
    link.advance(600 * MS)
    assert abs(d.mc.axis.position - 80 * MM) < 10                            # followed to 4 V: 80 mm
    link.command(C.PREDEF_VAI_GO_TO_POS, target=10 * MM)                      # another motion ends following
    d.io.set_analog(9.0, link.t + 10 * MS)
    link.advance(600 * MS)
    assert abs(d.mc.axis.position - 10 * MM) < 10 and d.mc.events.follow is None


def test_the_st_encoder_encodes_every_row_as_the_catalogue(tmp_path):
    """F_LmMotionEncode (st_lib/motion/codec_gen.st, generated from the catalogue) against the Python codec for
    every row of this part, with values at the ends of each field's type."""

    from catalogue_programs import encoder_program
    from linmot_st import toolchain
    from linmot_st.plc import Plc
    from stbench import available_backends

    backends = available_backends()
    if not backends:
        pytest.skip("no ST backend")
    plc = Plc(toolchain.build(str(encoder_program(tmp_path)), backend=backends[0], root=tmp_path))
    extremes = {"INT": (-32768, 32767), "UINT": (65535, 1), "DINT": (-2_000_000_000, 2_000_000_000),
                "UDINT": (2_147_483_647, 7)}          # the encoder takes DINT inputs
    for k, cid in enumerate(ROWS):
        row = C.COMMANDS[cid]
        for which in (0, 1):
            fields = {f.name: extremes[f.type][which] for f in row.fields}
            expected = C.encode(cid, k % 16, **fields)
            plc["ENC.CID"], plc["ENC.COUNT"] = cid, k % 16
            for name, value in zip("ABCD", list(fields.values()) + [0] * 4):
                plc[f"ENC.{name}"] = value
            plc.step(1)
            assert plc["ENC.NBYTES"] == len(expected) - 2, f"{cid:03X}h"
            assert bytes(plc["ENC.IMG"])[:len(expected)] == expected, f"{cid:03X}h"
