"""Quiet cycles (plain motion run in a tight loop, and ahead of the bus where no event-driven TxPDO needs every
cycle) change nothing: the same frames at the same times, and the same trajectory, as every MC cycle run one by
one through the generic path (MotionSettings(quiet_cycles=False))."""

from __future__ import annotations

import struct

import pytest

from linmot_st.bus import Frame, SimBus
from linmot_st.bus.nodes import ScriptedNode
from linmot_st.emulator import DriveTimings, E1100Drive, build_entry, load_profile
from linmot_st.emulator.linmot.motion import MotionSettings
from linmot_st.protocol import commands as C

MS = 1_000_000
MM = 10_000


def _cmd(cid: int, count: int, **fields) -> list[Frame]:
    raw = C.encode(cid, count, **fields).ljust(10, b"\0")
    return [Frame(0x301, raw[:8]), Frame(0x401, raw[:2] + raw[8:10])]


def _script(sync: bool, inhibit_100us: int = 0) -> list[tuple[int, Frame]]:
    cw = lambda w: Frame(0x201, struct.pack("<H", w))                               # noqa: E731
    sdo_read = lambda upid: Frame(0x601, struct.pack("<BHB4x", 0x40, 0x2000 + upid, 1))   # noqa: E731
    s: list[tuple[int, Frame]] = []
    if sync:
        s.append((50 * MS, Frame(0x601, struct.pack("<BHBBxxx", 0x2F, 0x1801, 2, 1))))   # TxPDO2 on SYNC
    if inhibit_100us:                                                                   # TxPDO2's inhibit time
        s.append((50 * MS, Frame(0x601, struct.pack("<BHBHxx", 0x2B, 0x1801, 3, inhibit_100us))))
    s += [(60 * MS, Frame(0x000, b"\x01\x01")), (61 * MS, cw(0x003E)), (70 * MS, cw(0x003F)),
          (120 * MS, cw(0x083F)), (150 * MS, cw(0x003F))]
    t = 200 * MS
    s += [(t, f) for f in _cmd(C.VAI16_GO_TO_POS, 1, target=800, vmax=1000, acc=100, dec=50)]
    s += [(t + 37 * MS + 300_000, sdo_read(0x1B8D)), (t + 90 * MS, sdo_read(0x1BAF))]
    s += [(t + 120 * MS, f) for f in _cmd(C.VAI16_GO_TO_POS, 2, target=100, vmax=700, acc=80, dec=80)]  # re-target
    s += [(t + 700 * MS, cw(0x002F)), (t + 760 * MS, cw(0x003F))]                     # abort and back
    s += [(t + 800 * MS, f) for f in _cmd(C.VAI16_GO_TO_POS, 3, target=1200, vmax=1500, acc=200, dec=200)]
    s += [(t + 850 * MS, cw(0x001F)), (t + 900 * MS, cw(0x003F))]                     # freeze and resume
    s += [(t + 1500 * MS, f) for f in _cmd(C.VAI_STOP, 4, dec=100000)]
    s += [(t + 1600 * MS, f) for f in _cmd(C.VAI16_GO_TO_POS, 5, target=2900, vmax=1000, acc=100, dec=100)]
    if sync:
        s += [(k * 4 * MS, Frame(0x080, b"")) for k in range(15, 900)]
    return sorted(s, key=lambda x: x[0])


def _special_script(sync: bool, inhibit_100us: int = 0) -> list[tuple[int, Frame]]:
    """The special states by control word: homing by a negative search onto the mechanical stop (its phase 2 back
    to the initial position), jog plus and minus, go to initial position, clearance check (left in its phase 2),
    go to position, a jog left while it runs."""
    cw = lambda w: Frame(0x201, struct.pack("<H", w))                               # noqa: E731
    s = [(f_t, f) for f_t, f in _script(sync, inhibit_100us) if f_t <= 70 * MS and f.can_id != 0x080]
    t = 100 * MS
    for bit, ms in ((0x0800, 900), (0, 50), (0x0100, 400), (0, 50), (0x0200, 300), (0, 50), (0x2000, 600), (0, 50),
                    (0x1000, 900), (0, 50), (0x0040, 700), (0, 50), (0x0100, 100), (0, 100)):
        s.append((t, cw(0x003F | bit)))
        t += ms * MS
    if sync:
        s += [(k * 4 * MS, Frame(0x080, b"")) for k in range(15, 1300)]
    return sorted(s, key=lambda x: x[0])


# homing mode 3 (mechanical stop, negative search), jog increment 20 mm, the special states' positions
SPECIAL_PROFILE = {0x1500: 3, 0x14B1: 20 * MM, 0x1502: 50 * MM, 0x1510: 30 * MM, 0x1520: 10 * MM, 0x1521: 40 * MM}

# a command-table program in flash: moves with the waits the quiet cycles check in their loop (motion finished,
# time, in target) and one they leave to the generic cycle (actual position), looped twice with a counter
END = 0xFFFF
TABLE = {
    1: (C.PREDEF_VAI_GO_TO_POS, dict(target=20 * MM), 2),
    2: (C.WAIT_MOTION_FINISHED, {}, 3),
    3: (C.WAIT_TIME, dict(time=500), 4),                                # 50 ms
    4: (C.PREDEF_VAI_GO_TO_POS, dict(target=5 * MM), 5),
    5: (C.WAIT_IN_TARGET_POSITION, {}, 6),
    6: (C.PREDEF_VAI_GO_TO_POS, dict(target=30 * MM), 7),
    7: (C.WAIT_ACTUAL_POS_GREATER, dict(level=25 * MM), 8),
    8: (C.ADD_CT_VAR1, dict(value=1), 9),
    9: (C.WAIT_MOTION_FINISHED, {}, 10),
    10: (C.IF_VAR1_LESS, dict(value=2, if_true=1, if_false=END), END),
}
TABLE_PROFILE = {0x14BE: 250_000, 0x14BF: 500_000, 0x14C0: 500_000}     # predefined vmax, acc, dec


def _table_script(sync: bool, inhibit_100us: int = 0) -> list[tuple[int, Frame]]:
    """Home (at the actual position), then start the command table's entry 1 (200xh)."""
    s = [(f_t, f) for f_t, f in _script(sync, inhibit_100us) if f_t <= 150 * MS and f.can_id != 0x080]
    s += [(200 * MS, f) for f in _cmd(C.START_COMMAND_TABLE, 1, entry=1)]
    if sync:
        s += [(k * 4 * MS, Frame(0x080, b"")) for k in range(15, 1000)]
    return sorted(s, key=lambda x: x[0])


SCENARIOS = {"moves": (_script, {}), "special": (_special_script, SPECIAL_PROFILE),
             "table": (_table_script, TABLE_PROFILE)}


def _run(quiet: bool, sync: bool, hold_ns: int, inhibit_100us: int = 0, scenario: str = "moves"):
    script, parameters = SCENARIOS[scenario]
    profile = load_profile().with_defaults({0x1194: 2, 0x146F: 250 * MM, 0x146E: -10 * MM, **parameters})
    drive = E1100Drive(1, profile, timings=DriveTimings.fast(),
                       motion=MotionSettings(quiet_cycles=quiet, in_target_hold_ns=hold_ns))
    for entry, (cid, fields, link) in (TABLE if scenario == "table" else {}).items():
        drive.ct.flash[entry] = build_entry(cid << 4, C.encode(cid, 0, **fields)[2:], link=link)
    generic = []                               # the cycles that ran through the generic path
    original = drive.mc._cycle

    def counted(t: int) -> None:
        generic.append(t)
        original(t)
    drive.mc._cycle = counted
    wakes = []                                 # the bus's timer calls of the drive
    on_timer = drive.on_timer

    def woken(t: int) -> list:
        wakes.append(t)
        return on_timer(t)
    drive.on_timer = woken
    bus = SimBus(1_000_000)
    bus.attach(drive, "drive")
    bus.attach(ScriptedNode(script(sync, inhibit_100us)), "master")
    drive.power_on(0)
    for k in range(1, 60 if scenario == "special" else 40):   # observed now and then, as a test would (no
        bus.run_until(k * 100 * MS)                         # effect on either)
    trace = [(e.start_ns, e.frame.can_id, bytes(e.frame.data)) for e in bus.trace]
    drive.generic_cycles, drive.wakes = len(generic), len(wakes)
    return trace, list(drive.mc.trajectory.samples), drive


@pytest.mark.parametrize("sync, hold_ns", [(False, 0), (True, 0), (True, 5 * MS)])
def test_quiet_cycles_give_the_same_frames_and_trajectory(sync, hold_ns):
    ref_trace, ref_samples, ref = _run(False, sync, hold_ns)
    trace, samples, drive = _run(True, sync, hold_ns)
    assert drive.mc.error_code == 0x0008                                   # the last move runs into the limit
    assert len(trace) == len(ref_trace) and trace == ref_trace
    assert len(samples) == len(ref_samples) and samples == ref_samples
    assert drive.errlog.entries == ref.errlog.entries


def test_quiet_cycles_are_used():
    """The speed-up is real: most cycles of the run are quiet (the rest: where an output word changes)."""
    _, samples, ref = _run(False, True, 0)
    _, _, drive = _run(True, True, 0)
    assert ref.generic_cycles > 900                                        # every cycle, one by one
    assert drive.generic_cycles < ref.generic_cycles / 10


@pytest.mark.parametrize("inhibit_100us, wakes_share", [(35, 0.7), (100, 0.35)])
def test_quiet_cycles_ahead_while_the_event_pdo_waits_for_its_inhibit_time(inhibit_100us, wakes_share):
    """TxPDO2 event-driven with an inhibit time (the bus budget's): while it waits for the inhibit time to end, the
    quiet cycles up to then are computed ahead (a change in them sends nothing; at the end it goes with the content
    of that time). The same frames and trajectory as every cycle run one by one, and far fewer wakes."""
    ref_trace, ref_samples, ref = _run(False, False, 0, inhibit_100us)
    trace, samples, drive = _run(True, False, 0, inhibit_100us)
    assert len(trace) == len(ref_trace) and trace == ref_trace
    assert len(samples) == len(ref_samples) and samples == ref_samples
    assert drive.errlog.entries == ref.errlog.entries
    assert sum(e[1] == 0x281 for e in trace) > 50                          # TxPDO2 ran, spaced by the inhibit
    # about two wakes per inhibit time while moving (its end, the next cycle) instead of one per 1 ms cycle
    _, _, every_cycle = _run(True, False, 0)                                # no inhibit: a wake every cycle
    assert drive.wakes < wakes_share * every_cycle.wakes, (drive.wakes, every_cycle.wakes)


@pytest.mark.parametrize("sync, inhibit_100us", [(False, 0), (True, 0), (False, 35)])
def test_special_states_quiet_cycles_give_the_same_frames_and_trajectory(sync, inhibit_100us):
    """The special states' cycles are quiet while their plan runs (the homing search while the following error
    stays below the stop error): the same frames and trajectory as every cycle one by one, through the homing
    search onto the stop, both jogs, go to initial position, both phases of the clearance check, go to position."""
    ref_trace, ref_samples, ref = _run(False, sync, 0, inhibit_100us, "special")
    trace, samples, drive = _run(True, sync, 0, inhibit_100us, "special")
    assert len(trace) == len(ref_trace) and trace == ref_trace
    assert len(samples) == len(ref_samples) and samples == ref_samples
    assert drive.errlog.entries == ref.errlog.entries == [] and drive.mc.homed
    seen = {(s.state_var >> 8, s.state_var & 0xFF) for s in samples}
    assert {(9, 1), (9, 2), (9, 15), (16, 1), (16, 15), (17, 1), (17, 15), (11, 15), (10, 1), (10, 2), (15, 1),
            (15, 15)} <= seen                                          # every phase ran
    assert ref.generic_cycles > 2500 and drive.generic_cycles < ref.generic_cycles / 50


@pytest.mark.parametrize("sync, inhibit_100us", [(False, 0), (True, 0), (False, 35)])
def test_command_table_waits_quiet_cycles_give_the_same_frames_and_trajectory(sync, inhibit_100us):
    """A command-table sequence in a wait that reads nothing a quiet cycle changes (motion finished, time, in
    target) runs quiet cycles until the wait holds; a wait on the actual position runs every cycle generically.
    The same frames, trajectory and executed entries as every cycle one by one."""
    ref_trace, ref_samples, ref = _run(False, sync, 0, inhibit_100us, "table")
    trace, samples, drive = _run(True, sync, 0, inhibit_100us, "table")
    assert len(trace) == len(ref_trace) and trace == ref_trace
    assert len(samples) == len(ref_samples) and samples == ref_samples
    assert drive.mc.executed == ref.mc.executed and drive.errlog.entries == ref.errlog.entries == []
    assert drive.mc.ct_runner.executed == list(range(1, 11)) * 2 and drive.mc.ct_runner.variables[1] == 2
    assert not drive.mc.ct_runner.running and abs(drive.mc.axis.position - 30 * MM) < 1
    waits = [t for t, h, _ in drive.mc.executed if h >> 4 == C.WAIT_ACTUAL_POS_GREATER]
    assert len(waits) == 2                                             # the loop ran twice
    # the rest are generic: the position waits, and the waits after a plan's end (the time wait at rest)
    assert ref.generic_cycles > 800 and drive.generic_cycles < ref.generic_cycles / 2
