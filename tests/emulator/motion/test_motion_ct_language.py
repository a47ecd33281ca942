"""The command-table language on the emulated E1100 ([MC] 4.3.124..127, 166..211, [MC] 6): a program with a
loop, a counter, a branch and waits on a position runs as on a real drive; each wait, IF, variable and modify
command's golden behaviour; every row of the group is accepted (no 0081h); the ST encoder encodes every row as the
catalogue does."""

from __future__ import annotations

import struct

import pytest

from catalogue_programs import encoder_program  # (the encoder program around codec_gen)
from linmot_st.emulator import DriveTimings, E1100Drive, build_entry, load_profile
from linmot_st.emulator.linmot.motion import MotionSettings, ct_language
from linmot_st.emulator.testing import MotionLink
from linmot_st.protocol import commands as C
from linmot_st.protocol import words as W
from linmot_st.protocol.commands import ct_language as CTL
from linmot_st.protocol.upids import P_PREDEF_VMAX, V_ACTUAL_POSITION, V_CT_VAR1, V_CT_VAR2
from stbench import available_backends

MS = 1_000_000
MM = 10_000
END = 0xFFFF

# 0.25 m/s, 5 m/s^2: a trapezoid with 50 ms ramps (6.25 mm each)
VAD = dict(vmax=250_000, acc=500_000, dec=500_000)
PREDEF = {0x14BE: 250_000, 0x14BF: 500_000, 0x14C0: 500_000}


def _link(parameters: dict | None = None, **settings) -> MotionLink:
    # RxPDO3 mapping 2041h = 2: parameter bytes 6..11, so the 12-byte commands (0D4xh..0D7xh) fit
    profile = load_profile().with_defaults({0x1194: 2, 0x2041: 2, **PREDEF, **(parameters or {})})
    link = MotionLink(E1100Drive(1, profile, timings=DriveTimings.fast(), motion=MotionSettings(**settings)))
    link.enable()
    link.home()
    link.advance(MS)
    return link


def load(drive, program: dict[int, tuple]) -> None:
    """Entries into the command table's RAM: entry -> (command ID, fields, link)."""
    for entry, (cid, fields, link) in program.items():
        drive.ct.ram[entry] = build_entry(cid << 4, C.encode(cid, 0, **fields)[2:], link=link)


def run_table(link: MotionLink, entry: int = 1, timeout_ns: int = 5_000_000_000) -> int:
    """200xh from the interface; returns its time. Waits until the sequence ends."""
    t0 = link.t
    link.command(C.START_COMMAND_TABLE, entry=entry)
    assert link.wait(lambda: not link.drive.mc.ct_runner.running, timeout_ns)
    return t0


def times_of(mc, cid: int, since: int = 0) -> list[int]:
    return [t for t, h, _ in mc.executed if h >> 4 == cid and t >= since]


def go_to(link: MotionLink, target: int) -> None:
    link.command(C.PREDEF_VAI_GO_TO_POS, target=target)
    assert link.wait(lambda: link.drive.mc.in_target and not link.drive.mc.motion_active)
    link.advance(100 * MS)               # settled: the axis at rest on the demand


# ---------------------------------------------------------------- a program as a machine builder writes one

PROGRAM = {
    1: (C.SET_CT_VAR1, dict(value=0), 2),                            # the stroke counter
    2: (C.SET_CT_VAR2, dict(value=20 * MM), 3),                      # the first stroke's end
    3: (C.VAI_GO_TO_CT_VAR2, VAD, 4),                                # out to Var 2
    4: (C.WAIT_ACTUAL_POS_GREATER, dict(level=15 * MM), 5),          # on the way out, past 15 mm ...
    5: (C.ADD_CT_VAR2, dict(value=10 * MM), 6),                      # ... the next stroke goes 10 mm further
    6: (C.WAIT_MOTION_FINISHED, {}, 7),
    7: (C.PREDEF_VAI_GO_TO_POS, dict(target=0), 8),                  # back
    8: (C.WAIT_ACTUAL_POS_LESS, dict(level=1 * MM), 9),
    9: (C.ADD_CT_VAR1, dict(value=1), 10),
    10: (C.IF_VAR1_LESS, dict(value=3, if_true=3, if_false=11), END),   # the loop: 3 strokes
    11: (C.WAIT_MOTION_FINISHED, {}, END),
}


def test_a_program_with_a_loop_a_counter_a_branch_and_position_waits():
    link = _link()
    d, mc = link.drive, link.drive.mc
    load(d, PROGRAM)
    t0 = run_table(link)
    assert mc.state == W.OPERATION_ENABLED and mc.error_code == 0
    assert mc.ct_runner.executed == [1, 2] + [3, 4, 5, 6, 7, 8, 9, 10] * 3 + [11]
    # the variables, as a PLC reads them: UPIDs 1E72h / 1E73h by SDO (2000h + UPID, sub 1)
    assert link.sdo(bytes([0x40, 0x72, 0x3E, 1, 0, 0, 0, 0]))[4:] == struct.pack("<i", 3)
    assert link.sdo(bytes([0x40, 0x73, 0x3E, 1, 0, 0, 0, 0]))[4:] == struct.pack("<i", 50 * MM)
    assert mc.variable(V_CT_VAR1) == 3 and mc.variable(V_CT_VAR2) == 50 * MM

    samples = mc.trajectory.between(t0)
    # three strokes out, to 20, 30 and 40 mm, each back to 0
    peaks, out = [], False
    for s in samples:
        if s.demand_velocity > 0:
            out = True
        elif out and s.demand_velocity == 0 and s.demand > 0:
            peaks.append(s.demand)
            out = False
    assert peaks == [20 * MM, 30 * MM, 40 * MM]
    assert mc.dem_p == 0 and not mc.motion_active
    # each Add To Var 2 ran in the MC cycle the actual position first passed 15 mm
    adds = times_of(mc, C.ADD_CT_VAR2, t0)
    waits = times_of(mc, C.WAIT_ACTUAL_POS_GREATER, t0)
    assert len(adds) == len(waits) == 3
    for t_wait, t_add in zip(waits, adds):
        first = next(s.t_ns for s in samples if s.t_ns > t_wait and s.t_ns % MS == 0 and s.actual > 15 * MM)
        assert t_add == first
    # the first stroke: 20 mm at 0.25 m/s, 5 m/s^2 = 80 ms + 50 ms; it starts in the 200xh's cycle + 2 entries
    start = times_of(mc, C.VAI_GO_TO_CT_VAR2, t0)[0]
    assert start - t0 == 2 * MS
    end = next(s.t_ns for s in samples if s.t_ns > start and s.demand == 20 * MM)
    assert abs((end - start) - 130 * MS) <= MS


def test_the_program_runs_the_same_without_the_fast_path():
    """Quiet cycles are off while a sequence runs; before and after it the fast path gives the same trajectory."""
    runs = []
    for quiet in (True, False):
        link = _link(quiet_cycles=quiet)
        load(link.drive, PROGRAM)
        t0 = run_table(link)
        link.advance(300 * MS)
        runs.append([(s.t_ns - t0, s.demand, s.actual, s.status_word) for s in link.drive.mc.trajectory.between(t0)
                     if s.t_ns % MS == 0])
    assert runs[0] == runs[1]


def test_a_command_from_the_interface_ends_the_sequence():
    """INFERRED (docs/emulator.md 13.6): the interface's command replaces the sequence, as it replaces a motion."""
    link = _link()
    mc = link.drive.mc
    load(link.drive, {1: (C.WAIT_TIME, dict(time=10_000), 2), 2: (C.SET_CT_VAR1, dict(value=7), END)})
    link.command(C.START_COMMAND_TABLE, entry=1)
    link.advance(10 * MS)
    assert mc.ct_runner.running and mc.motion_active
    link.command(C.PREDEF_VAI_GO_TO_POS, target=10 * MM)
    assert not mc.ct_runner.running
    link.advance(2 * 1000 * MS)
    assert mc.ct_runner.variables[1] == 0 and mc.dem_p == 10 * MM


def test_with_the_setting_off_the_sequence_goes_on_beside_the_interfaces_command():
    link = _link(interface_command_ends_sequence=False)
    mc = link.drive.mc
    load(link.drive, {1: (C.WAIT_TIME, dict(time=1000), 2), 2: (C.SET_CT_VAR1, dict(value=7), END)})
    link.command(C.START_COMMAND_TABLE, entry=1)
    link.advance(10 * MS)
    link.command(C.PREDEF_VAI_GO_TO_POS, target=10 * MM)
    assert mc.ct_runner.running
    link.advance(2 * 1000 * MS)
    assert mc.ct_runner.variables[1] == 7 and mc.dem_p == 10 * MM and not mc.ct_runner.running


# ---------------------------------------------------------------- the waits, one by one

_SAMPLE_SIGNAL = {   # the signal of each wait on a trajectory sample (velocities: pu/s -> 1E-6 m/s)
    0x220: lambda s: s.demand, 0x222: lambda s: s.actual,
    0x224: lambda s: s.demand - s.actual, 0x226: lambda s: abs(s.demand - s.actual),
    0x228: lambda s: s.demand_velocity / 10, 0x22A: lambda s: s.actual_velocity / 10,
}


def _sample_holds(cid: int, level: int):
    """The wait's condition on a trajectory sample (the values the MC had in that cycle): even IDs 'greater'."""
    signal = _SAMPLE_SIGNAL[cid & ~1]
    return (lambda s: signal(s) > level) if cid & 1 == 0 else (lambda s: signal(s) < level)


# (wait, level, outward): outward moves 0 -> 50 mm, else 50 -> 0 mm
LEVEL_WAITS = [
    (CTL.WAIT_DEMAND_POS_GREATER, 30 * MM, True), (CTL.WAIT_DEMAND_POS_LESS, 20 * MM, False),
    (CTL.WAIT_ACTUAL_POS_GREATER, 30 * MM, True), (CTL.WAIT_ACTUAL_POS_LESS, 20 * MM, False),
    (CTL.WAIT_DIFF_POS_GREATER, 100, True), (CTL.WAIT_DIFF_POS_LESS, -100, False),
    (CTL.WAIT_DIFF_POS_UNSIGNED_GREATER, 100, False), (CTL.WAIT_DIFF_POS_UNSIGNED_LESS, 5, True),
    (CTL.WAIT_DEMAND_VEL_GREATER, 200_000, True), (CTL.WAIT_DEMAND_VEL_LESS, -200_000, False),
    (CTL.WAIT_ACTUAL_VEL_GREATER, 200_000, True), (CTL.WAIT_ACTUAL_VEL_LESS, -200_000, False),
]


@pytest.mark.parametrize("cid,level,outward", LEVEL_WAITS, ids=[f"{c:03X}h" for c, _, _ in LEVEL_WAITS])
def test_a_level_wait_holds_the_sequence_until_the_first_cycle_its_condition_holds(cid, level, outward):
    link = _link()
    mc = link.drive.mc
    if not outward:
        go_to(link, 50 * MM)
    load(link.drive, {1: (C.VAI_GO_TO_POS, dict(target=50 * MM if outward else 0, **VAD), 2),
                      2: (cid, dict(level=level), 3),
                      3: (C.SET_CT_VAR1, dict(value=1), END)})
    t0 = run_table(link)
    (t_wait,), (t_marker,) = times_of(mc, cid, t0), times_of(mc, C.SET_CT_VAR1, t0)
    holds = _sample_holds(cid, level)
    cycles = [s for s in mc.trajectory.between(t_wait + 1) if s.t_ns % MS == 0]
    first = next(s for s in cycles if holds(s))
    assert t_marker == first.t_ns
    assert t_marker > t_wait and mc.ct_runner.variables[1] == 1
    if cid not in (CTL.WAIT_DIFF_POS_UNSIGNED_LESS,):      # the others hold only once the motion is under way
        assert not holds(cycles[0]) or cycles[0].t_ns == t_marker
        assert t_marker - t_wait >= MS


@pytest.mark.parametrize("cid,level", [(CTL.WAIT_CURRENT_GREATER, 100), (CTL.WAIT_CURRENT_LESS, -100)])
def test_a_current_wait_holds_until_the_demand_current_passes_its_level(cid, level):
    """Demand current 1B93h = 0.5 kg x 5 m/s^2 / 10 N/A = 250 mA while accelerating, -250 mA while braking."""
    link = _link()
    mc = link.drive.mc
    seen = []
    load(link.drive, {1: (C.VAI_GO_TO_POS, dict(target=50 * MM, **VAD), 2), 2: (cid, dict(level=level), 3),
                      3: (C.SET_CT_VAR1, dict(value=1), END)})
    link.command(C.START_COMMAND_TABLE, entry=1)
    t0 = link.t - 1
    while mc.ct_runner.running:
        seen.append((link.t, mc.variable(0x1B93)))
        link.advance(MS)
    seen.append((link.t, mc.variable(0x1B93)))
    (t_marker,) = times_of(mc, C.SET_CT_VAR1, t0)
    before = [i for t, i in seen if t < t_marker - MS]
    passed = (lambda i: i > level) if cid == CTL.WAIT_CURRENT_GREATER else (lambda i: i < level)
    assert not any(passed(i) for i in before)
    assert any(passed(i) for t, i in seen if t_marker - MS <= t <= t_marker + MS)
    # greater: in the acceleration ramp (the first 50 ms); less: in the braking ramp (the last 50 ms)
    elapsed = t_marker - t0
    assert (0 < elapsed <= 50 * MS) if cid == CTL.WAIT_CURRENT_GREATER else (200 * MS <= elapsed <= 250 * MS)


def test_waits_from_the_interface_do_nothing():
    link = _link()
    mc = link.drive.mc
    for cid in (CTL.WAIT_DEMAND_POS_GREATER, CTL.WAIT_CURRENT_LESS):
        link.command(cid, level=1)
        link.advance(5 * MS)
        assert not mc.ct_runner.running and mc.state == W.OPERATION_ENABLED and not mc.motion_active


# ---------------------------------------------------------------- the IFs

def _ifs():
    """(IF, fields that make it true, fields that make it false) with the axis at rest at 50 mm, Var 1 = 5,
    Var 2 = -5, homed (status bit 11), no warning."""
    def v(value):
        return dict(value=value)
    cases = [
        (CTL.IF_VAR1_LESS, v(6), v(5)), (CTL.IF_VAR1_GREATER, v(4), v(5)),
        (CTL.IF_VAR2_LESS, v(-4), v(-5)), (CTL.IF_VAR2_GREATER, v(-6), v(-5)),
        (CTL.IF_DEMAND_POS_LESS, v(50 * MM + 1), v(50 * MM)), (CTL.IF_DEMAND_POS_GREATER, v(50 * MM - 1), v(50 * MM)),
        (CTL.IF_ACTUAL_POS_LESS, v(51 * MM), v(49 * MM)), (CTL.IF_ACTUAL_POS_GREATER, v(49 * MM), v(51 * MM)),
        (CTL.IF_DIFF_POS_LESS, v(10), v(-10)), (CTL.IF_DIFF_POS_GREATER, v(-10), v(10)),
        (CTL.IF_CURRENT_LESS, v(1), v(0)), (CTL.IF_CURRENT_GREATER, v(-1), v(0)),
        (CTL.IF_MASKED_STATUS_WORD, dict(mask=W.SW_HOMED, value=W.SW_HOMED), dict(mask=W.SW_HOMED, value=0)),
        (CTL.IF_MASKED_WARN_WORD, dict(mask=0x00FF, value=0), dict(mask=0x00FF, value=0x0080)),
    ]
    return cases


@pytest.mark.parametrize("cid,true_fields,false_fields", _ifs(), ids=[f"{c[0]:03X}h" for c in _ifs()])
def test_an_if_continues_at_its_true_or_false_entry(cid, true_fields, false_fields):
    link = _link()
    mc = link.drive.mc
    go_to(link, 50 * MM)
    for fields, expected in ((true_fields, [1, 2]), (false_fields, [1, 3])):
        link.command(C.SET_CT_VAR1, value=5)
        link.command(C.SET_CT_VAR2, value=-5)
        # the IF's own link (4) is not followed: it continues at one of its two entries
        load(link.drive, {1: (cid, dict(fields, if_true=2, if_false=3), 4),
                          2: (C.SET_CT_VAR1, dict(value=100), END),
                          3: (C.SET_CT_VAR1, dict(value=200), END),
                          4: (C.SET_CT_VAR1, dict(value=300), END)})
        run_table(link)
        assert mc.ct_runner.executed == expected, (hex(cid), fields)
        assert mc.ct_runner.variables[1] == (100 if expected[1] == 2 else 200)
        assert mc.error_code == 0


IO_IFS = [   # (IF, fields true, fields false) with 2.5 V on X4.4, X4.7 high, X6.1 set by 004xh
    (CTL.IF_ANALOG_X4_4_LESS, dict(value=2501), dict(value=2500)),
    (CTL.IF_MASKED_X4_INPUTS, dict(mask=0x0011, value=0x0010), dict(mask=0x0010, value=0)),   # bit 4 = X4.7
    (CTL.IF_MASKED_X6_INPUTS, dict(mask=0x0003, value=0x0002), dict(mask=0x0002, value=0)),
]


@pytest.mark.parametrize("cid,true_fields,false_fields", IO_IFS, ids=[f"{c[0]:03X}h" for c in IO_IFS])
def test_an_io_if_reads_the_drives_inputs(cid, true_fields, false_fields):
    link = _link()
    d, mc = link.drive, link.drive.mc
    d.io.set_analog(2.5)
    d.io.set_input("X4.7", 1)
    d.io.write_outputs("X6", 0x0002, 0x0002, link.t)
    link.advance(MS)
    for fields, expected in ((true_fields, [1, 2]), (false_fields, [1, 3])):
        load(d, {1: (cid, dict(fields, if_true=2, if_false=3), END),
                 2: (C.NOP, {}, END), 3: (C.NOP, {}, END)})
        run_table(link)
        assert mc.ct_runner.executed == expected, (hex(cid), fields)


def test_an_if_from_the_interface_starts_the_table_at_the_entry_it_selects():
    """INFERRED (docs/emulator.md 13.6)."""
    link = _link()
    mc = link.drive.mc
    load(link.drive, {2: (C.SET_CT_VAR2, dict(value=22), END), 3: (C.SET_CT_VAR2, dict(value=33), END)})
    link.command(C.SET_CT_VAR1, value=1)
    link.command(CTL.IF_VAR1_GREATER, value=0, if_true=2, if_false=3)
    link.advance(5 * MS)
    assert mc.ct_runner.executed == [2] and mc.ct_runner.variables[2] == 22
    link.command(CTL.IF_VAR1_GREATER, value=1, if_true=2, if_false=3)
    link.advance(5 * MS)
    assert mc.ct_runner.executed == [3] and mc.ct_runner.variables[2] == 33


def test_an_if_jumping_to_a_missing_entry_raises_008ah():
    link = _link()
    mc = link.drive.mc
    load(link.drive, {1: (CTL.IF_VAR1_LESS, dict(value=1, if_true=9, if_false=2), END)})
    run_table(link)
    assert mc.state == W.ERROR and mc.error_code == W.ERR_CMD_TAB_ENTRY_NOT_DEFINED


# ---------------------------------------------------------------- the variables

def test_set_add_and_wrap():
    link = _link()
    r = link.drive.mc.ct_runner
    link.command(C.SET_CT_VAR1, value=-7)
    link.command(C.ADD_CT_VAR1, value=10)
    link.command(C.SET_CT_VAR2, value=2**31 - 1)
    link.command(C.ADD_CT_VAR2, value=1)            # SInt32: wraps (INFERRED)
    link.advance(MS)
    assert r.variables == {1: 3, 2: -2**31}
    assert link.drive.params.read(V_CT_VAR2, "ram") == 0x80000000


def test_variables_to_and_from_upid_ram_values():
    link = _link()
    d, mc = link.drive, link.drive.mc
    go_to(link, 12 * MM)
    link.command(C.UPID_TO_CT_VAR1, upid=V_ACTUAL_POSITION)       # a variable: its value now
    link.command(C.UPID_TO_CT_VAR2, upid=P_PREDEF_VMAX)           # a parameter: its RAM value
    link.advance(MS)
    assert abs(mc.ct_runner.variables[1] - 12 * MM) <= 5 and mc.ct_runner.variables[2] == PREDEF[P_PREDEF_VMAX]
    link.command(C.SET_CT_VAR1, value=123_456)
    link.command(C.CT_VAR1_TO_UPID, upid=P_PREDEF_VMAX)           # live, writable, in range: taken
    link.command(C.SET_CT_VAR2, value=-1)
    link.command(C.CT_VAR2_TO_UPID, upid=0x14BF)                  # -1 outside 0..1E8: ignored (as 002xh)
    link.command(C.CT_VAR2_TO_UPID, upid=V_CT_VAR1)               # a variable: ignored
    link.command(C.UPID_TO_CT_VAR2, upid=0x7777)                  # no such UPID: Var 2 unchanged
    link.advance(MS)
    assert d.params[P_PREDEF_VMAX].ram == 123_456 and d.params[0x14BF].ram == PREDEF[0x14BF]
    assert mc.ct_runner.variables == {1: 123_456, 2: -1}
    assert mc.state == W.OPERATION_ENABLED


def test_the_variables_travel_in_a_txpdo_mapped_by_upid():
    """TxPDO3 by UPID (203Bh/203Ch, docs/emulator.md 13.5) carries Var 1 and Var 2 as it carries any variable."""
    link = _link({0x203B: V_CT_VAR1, 0x203C: V_CT_VAR2})
    link.command(C.SET_CT_VAR1, value=-5)
    link.command(C.SET_CT_VAR2, value=70_000)
    link.advance(5 * MS)
    assert struct.unpack("<ii", link.pdos(3)[-1][1]) == (-5, 70_000)


def test_an_mc_start_clears_the_variables():
    link = _link()
    link.command(C.SET_CT_VAR1, value=9)
    link.advance(MS)
    mc = link.drive.mc
    assert mc.ct_runner.variables[1] == 9
    mc.stop(link.t)
    mc.start(link.t, True)
    assert mc.ct_runner.variables == {1: 0, 2: 0}


@pytest.mark.parametrize("cid", [C.VAI_GO_TO_CT_VAR1, C.VAI_GO_TO_CT_VAR2,
                                 C.VAI_GO_TO_CT_VAR1_FROM_ACT, C.VAI_GO_TO_CT_VAR2_FROM_ACT])
def test_vai_to_a_variables_position(cid):
    link = _link()
    mc = link.drive.mc
    var = 1 if cid in (C.VAI_GO_TO_CT_VAR1, C.VAI_GO_TO_CT_VAR1_FROM_ACT) else 2
    link.command(C.SET_CT_VAR1 if var == 1 else C.SET_CT_VAR2, value=30 * MM)
    link.command(C.SET_CT_VAR2 if var == 1 else C.SET_CT_VAR1, value=-30 * MM)     # the other: not used
    link.advance(MS)
    mc.push(2 * MM, link.t)              # a disturbance: the slider 2 mm ahead of the demand (0)
    t0 = link.t
    link.command(cid, **VAD)
    link.advance(5 * MS)
    first = next(s for s in mc.trajectory.between(t0) if s.demand_velocity > 0)
    from_actual = cid in (C.VAI_GO_TO_CT_VAR1_FROM_ACT, C.VAI_GO_TO_CT_VAR2_FROM_ACT)
    assert (first.demand > 1.9 * MM) == from_actual      # from the actual position, or on from the demand
    assert link.wait(lambda: not mc.motion_active and mc.in_target)
    assert mc.dem_p == 30 * MM and mc.error_code == 0


# ---------------------------------------------------------------- modify an entry in RAM

def test_modify_an_entrys_target_and_link_in_ram():
    link = _link()
    d, mc = link.drive, link.drive.mc
    load(d, {1: (C.PREDEF_VAI_GO_TO_POS, dict(target=10 * MM), END), 2: (C.SET_CT_VAR1, dict(value=5), END)})
    link.command(CTL.MODIFY_CT_32BIT, entry=1, offset=6, value=35 * MM)    # the first parameter: the target
    link.command(CTL.MODIFY_CT_16BIT, entry=1, offset=2, value=2)          # the link: on to entry 2
    link.advance(MS)
    assert struct.unpack_from("<HHHi", d.ct.ram[1], 0) == (0xA701, 2, C.PREDEF_VAI_GO_TO_POS << 4, 35 * MM)
    link.command(CTL.MODIFY_CT_16BIT, entry=1, offset=63, value=1)         # past the 64 bytes: ignored
    link.advance(MS)
    assert len(d.ct.ram[1]) == 64
    run_table(link)
    assert mc.ct_runner.executed == [1, 2] and mc.ct_runner.variables[1] == 5
    assert link.wait(lambda: not mc.motion_active)
    assert mc.dem_p == 35 * MM
    assert d.ct.flash.get(1) is None                                       # RAM only
    link.command(CTL.MODIFY_CT_16BIT, entry=9, offset=6, value=0)          # no entry 9
    link.advance(MS)
    assert mc.state == W.ERROR and mc.error_code == W.ERR_CMD_TAB_ENTRY_NOT_DEFINED


# ---------------------------------------------------------------- every row is accepted

GROUP = sorted(cid for cid, c in C.COMMANDS.items() if c.source and c.kind in (
    C.Kind.CT_MODIFY, C.Kind.CT_VARIABLE, C.Kind.CT_IF, C.Kind.VAI_CT_VAR) or cid in ct_language.WAITS)


def _fields(cid: int) -> dict:
    values = {"entry": 1, "offset": 6, "if_true": 1, "if_false": 1, "upid": V_ACTUAL_POSITION, "mask": 0,
              "vmax": 100_000, "acc": 100_000, "dec": 100_000, "time": 10}
    return {n: values.get(n, 0) for n in C.COMMANDS[cid].field_names}


@pytest.mark.parametrize("as_entry", [False, True], ids=["interface", "table"])
def test_every_row_of_the_group_is_accepted(as_entry):
    assert len(GROUP) >= 45
    for cid in GROUP:
        link = _link()
        mc = link.drive.mc
        load(link.drive, {1: (C.NOP, {}, END)})
        if as_entry or C.COMMANDS[cid].kind is C.Kind.WAIT:
            load(link.drive, {2: (cid, _fields(cid), END)})
            link.command(C.START_COMMAND_TABLE, entry=2)
        else:
            link.command(cid, **_fields(cid))
        link.advance(5 * MS)
        assert cid in [h >> 4 for _, h, _ in mc.executed], f"{cid:03X}h not run"
        assert mc.state == W.OPERATION_ENABLED and mc.error_code == 0, f"{cid:03X}h: {mc.error_code:04X}h"


# ---------------------------------------------------------------- the ST encoder

def _example(cid: int) -> dict:
    """Field values that fill every byte: negative where signed, the top of the range where unsigned."""
    signed = {"INT": -12345, "DINT": -123456789, "UINT": 0xFEDC, "UDINT": 0xFEDCBA98}
    return {f.name: signed[f.type] - i for i, f in enumerate(C.COMMANDS[cid].fields)}


@pytest.mark.parametrize("backend", available_backends() or ["none"])
def test_the_st_encoder_encodes_every_row_of_the_group_as_the_catalogue(tmp_path, backend):
    if backend == "none":
        pytest.skip("no ST backend")
    from linmot_st import toolchain
    from linmot_st.plc import Plc

    plc = Plc(toolchain.build(str(encoder_program(tmp_path)), backend=backend, root=tmp_path))
    for count, cid in enumerate(GROUP):
        fields = _example(cid)
        expected = C.encode(cid, count & 0xF, **fields)
        plc["ENC.CID"], plc["ENC.COUNT"] = cid, count & 0xF
        for name, value in zip("ABCD", list(fields.values()) + [0] * 4):
            plc[f"ENC.{name}"] = value - (1 << 32) if value >= 1 << 31 else value    # A..D are DINT
        plc.step(1)
        assert plc["ENC.NBYTES"] == len(expected) - 2, hex(cid)
        assert bytes(plc["ENC.IMG"])[:len(expected)] == expected, hex(cid)
