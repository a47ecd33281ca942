"""The fast idle path of CoSim (idle scans in C, Plc.step_idle) against every scan stepped from Python: the
same frames at the same times on the bus, the same PLC state, the same scan a fault or a watched change
happens in. On both backends (MatIEC where MATIEC_HOME or iec2c is found)."""

from __future__ import annotations

import dataclasses
import os

import pytest

from linmot_st.bus import Frame, SimBus
from linmot_st.bus.nodes import ScriptedNode
from linmot_st.cosim import CoSim, IdlePredicate
from linmot_st.toolchain.testing import BACKEND_PARAMS
from repo_paths import REPO

MB = "CONFIG0.RES0.CAN0"

# Echoes what it receives (Id + 1), sends a heartbeat every Period of its timer while Gate is TRUE (a test
# forces it), counts the scans that saw an empty Rx, and divides by Zero at scan FaultAt.
IDLE_ST = """{#include "st_lib/types/can.st"}
PROGRAM Idler
  VAR_EXTERNAL
    CAN0 : T_CanMailbox;
  END_VAR
  VAR
    Gate : BOOL := TRUE;
    Period : TIME := T#7ms;
    FaultAt : UDINT := 0;
    Zero : UDINT := 0;
    Q : UDINT;
    Scans : UDINT;
    EmptyScans : UDINT;
    Beats : UINT;
    Phase : INT;
    Seen : UDINT;
    Beat : TON;
    i : INT;
  END_VAR
  Scans := Scans + 1;
  IF CAN0.RxCount = 0 THEN
    EmptyScans := EmptyScans + 1;
  END_IF;
  i := 0;
  WHILE i < CAN0.RxCount DO
    i := i + 1;
    IF NOT CAN0.Rx[i].Echo AND CAN0.TxCount < 32 THEN
      Seen := Seen + 1;
      CAN0.TxCount := CAN0.TxCount + 1;
      CAN0.Tx[CAN0.TxCount] := CAN0.Rx[i];
      CAN0.Tx[CAN0.TxCount].Id := CAN0.Rx[i].Id + 1;
    END_IF;
  END_WHILE;
  Beat(IN := Gate AND NOT Beat.Q, PT := Period);
  IF Beat.Q AND CAN0.TxCount < 32 THEN
    Beats := Beats + 1;
    Phase := Phase + 1;
    CAN0.TxCount := CAN0.TxCount + 1;
    CAN0.Tx[CAN0.TxCount].Id := 16#701;
    CAN0.Tx[CAN0.TxCount].Dlc := 2;
    CAN0.Tx[CAN0.TxCount].Rtr := FALSE;
    CAN0.Tx[CAN0.TxCount].Data[0] := UINT_TO_BYTE(Beats);
    CAN0.Tx[CAN0.TxCount].Data[1] := 5;
  END_IF;
  IF Scans = 500 THEN
    Phase := Phase + 100;     (* a change that sends nothing: only a watch sees it *)
  END_IF;
  IF FaultAt > 0 AND Scans = FaultAt THEN
    Q := Scans / Zero;
  END_IF;
END_PROGRAM

CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    VAR_GLOBAL
      CAN0 : T_CanMailbox;
    END_VAR
    TASK Main(INTERVAL := T#1ms, PRIORITY := 0);
    PROGRAM Inst0 WITH Main : Idler;
  END_RESOURCE
END_CONFIGURATION
"""


@pytest.fixture(scope="module", params=BACKEND_PARAMS)
def idle_build(request, tmp_path_factory):
    from linmot_st.toolchain import build
    src = tmp_path_factory.mktemp("idle") / "idle.st"
    src.write_text(IDLE_ST)
    cwd = os.getcwd()
    os.chdir(REPO)                 # include root: the repository (the entry has no st_lib ancestor)
    try:
        return build(str(src), backend=request.param)
    finally:
        os.chdir(cwd)


def _script():
    """Frames from another node at irregular times, some in bursts."""
    times = [300_000, 2_500_000, 2_500_000, 40_100_000, 41_000_000, 333_333_333, 900_000_000]
    return [(t, Frame(0x181 + k, bytes([k, 1, 2]))) for k, t in enumerate(times)]


def _run(build, fast: bool, scans: int = 1200, prepare=None):
    from linmot_st.plc import Plc
    plc = Plc(build)
    bus = SimBus(500_000)
    node = ScriptedNode(_script())
    bus.attach(node, "node")
    sim = CoSim(plc, bus, mailbox=MB, fast_idle=fast)
    if prepare:
        prepare(plc, bus)
    return plc, bus, sim, node


STATE = ("INST0.SCANS", "INST0.EMPTYSCANS", "INST0.BEATS", "INST0.SEEN", "INST0.PHASE", f"{MB}.RXCOUNT")


def _state(plc, sim):
    return [plc[p] for p in STATE] + [plc.time_ns, plc.scan_count, sim.scans, sim.frames_sent,
                                      sim.frames_received]


def test_idle_scans_put_the_same_frames_on_the_bus(idle_build):
    out = {}
    for fast in (False, True):
        plc, bus, sim, node = _run(idle_build, fast)
        sim.step(700)
        plc.force("INST0.GATE", False)         # a forced input holds through scans run in C
        sim.step(300)
        plc.unforce("INST0.GATE")
        sim.step(1)
        plc["INST0.PERIOD"] = 50_000_000       # a setting written between calls, as a test does
        sim.step(1000)
        out[fast] = (list(bus.trace), node.received, _state(plc, sim), sim.idle_scans)
    slow, fast = out[False], out[True]
    assert slow[0] == fast[0] and slow[1] == fast[1] and slow[2] == fast[2]
    assert slow[3] == 0 and fast[3] > 1500          # most scans were idle and ran in C
    assert len(fast[0]) > 50                         # heartbeats, echoes and the node's frames


def test_a_fault_in_an_idle_scan_stops_at_the_same_scan(idle_build):
    from linmot_st.plc import PlcFault
    got = {}
    for fast in (False, True):
        plc, bus, sim, _ = _run(idle_build, fast, prepare=lambda p, b: p.__setitem__("INST0.FAULTAT", 777))
        with pytest.raises(PlcFault) as exc:
            sim.step(2000)
        got[fast] = (exc.value.kind, exc.value.scan, plc.scan_count, plc.time_ns, list(bus.trace))
    assert got[False] == got[True] and got[True][1] == 777


class PhaseWatch(IdlePredicate):
    """Records the scan and PLC time at which Inst0.Phase changes; true once it passed 100."""

    def __init__(self, plc):
        self.phase = plc.var("INST0.PHASE")
        super().__init__(plc, [self.phase])
        self.last, self.changes = self.phase.value, []

    def __call__(self):
        run = self.begin_call()
        if run and self.phase.value != self.last:
            self.last = self.phase.value
            self.changes.append((run - 1, self.plc.time_ns - self.plc.tick_ns, self.last))
        self.end_call()
        return self.last > 100


def test_a_watched_change_ends_the_idle_run_at_its_scan(idle_build):
    got = {}
    for fast in (False, True):
        plc, bus, sim, _ = _run(idle_build, fast)
        watch = PhaseWatch(plc)
        n = sim.run_until(watch, max_scans=5000)
        got[fast] = (n, watch.changes, watch.scans, list(bus.trace), sim.idle_scans)
    assert got[False][:4] == got[True][:4]
    assert got[True][1][-1][2] > 100 and got[True][4] > 300


def test_without_a_watch_the_predicate_sees_every_scan(idle_build):
    from linmot_st.plc import Plc
    plc = Plc(idle_build)
    sim = CoSim(plc, SimBus(500_000), mailbox=MB)
    calls = []
    sim.run_until(lambda: calls.append(plc.scan_count) or len(calls) > 40, max_scans=100)
    assert calls == list(range(41)) and sim.idle_scans > 30    # mostly idle, yet one C call per scan


def test_the_motion_job_is_the_same_with_idle_scans_in_c(idle_build):
    """The demo's scenario (commissioning with the drives' real timings: boot, flash save, reset; then the
    motion steps): the whole bus trace, every phase and every step identical."""
    from linmot_st.jobs.commission.runner import RunOptions
    from linmot_st.jobs.commission.testing import project_build
    from linmot_st.jobs.motion.budget import job_budget
    from linmot_st.jobs.motion.job import job_drives, motion_phase, run
    from linmot_st.jobs.motion.plan import plan as make_plan
    from linmot_st.pvl import load_pvl

    backend = idle_build.backend
    pvl = load_pvl(REPO / "examples" / "two_axes.pvl")
    steps = make_plan(pvl, 50.0)
    inhibit = job_budget(2, 500_000)[1].interval_100us          # TxPDO2's inhibit time as the job plans it
    out = {}
    for fast in (False, True):
        idle = []

        def after(plc, sim, drives, _motion=motion_phase(steps, 60.0, None, inhibit)):
            idle.append(sim.idle_scans)
            return _motion(plc, sim, drives)

        opts = RunOptions(axes=2, timings="real", fast_idle=fast)
        res = run(pvl, opts, project_build(backend), after=after, drive_factory=job_drives(steps, opts))
        assert res.after is not None and res.after.finished
        out[fast] = (res, idle[0])
    (slow, _), (fast, idle) = out[False], out[True]
    assert slow.trace == fast.trace
    assert [[dataclasses.astuple(p) for p in a.phases] for a in slow.axes] == \
        [[dataclasses.astuple(p) for p in a.phases] for a in fast.axes]
    assert [[dataclasses.astuple(s) for s in a.steps] for a in slow.after.axes] == \
        [[dataclasses.astuple(s) for s in a.steps] for a in fast.after.axes]
    assert (slow.scans, slow.after.scans, slow.after.t1_ns) == (fast.scans, fast.after.scans, fast.after.t1_ns)
    assert idle > 0.6 * fast.scans       # the boot, flash and reset waits ran in C


class _AlwaysChangesNodes:
    """A sampler's `changes_nodes` that says True whatever the sampler sets: the bus reads every timer each scan."""

    def __get__(self, obj, owner=None):
        return True

    def __set__(self, obj, value):
        pass


def test_samplers_that_change_no_node_spare_the_timer_reads_and_nothing_else(idle_build, monkeypatch):
    """The samplers declare changes_nodes False (the motion sampler except when it moves a drive's input or
    conveyor), so the bus does not ask every drive for its next timer before each scan. The demo's scenario on 4
    axes (TxPDO2 with the budget's inhibit time): the same trace, phases, steps and trajectories as with every
    timer read before every scan."""
    from linmot_st.jobs.commission.runner import RunOptions, Sampler
    from linmot_st.jobs.commission.testing import project_build
    from linmot_st.jobs.motion.budget import job_budget, job_inputs
    from linmot_st.jobs.motion.job import MotionSampler, job_drives, motion_phase, run
    from linmot_st.jobs.motion.plan import plan as make_plan
    from linmot_st.pvl import load_pvl

    pvl = load_pvl(REPO / "examples" / "two_axes.pvl")
    steps = make_plan(pvl, 50.0)
    inhibit = job_budget(4, 500_000)[1].interval_100us
    assert inhibit > 0
    out = []
    for forced in (False, True):
        if forced:
            monkeypatch.setattr(Sampler, "changes_nodes", _AlwaysChangesNodes())
            monkeypatch.setattr(MotionSampler, "changes_nodes", _AlwaysChangesNodes(), raising=False)
        opts = RunOptions(axes=4, timings="fast")
        res = run(pvl, opts, project_build(idle_build.backend), after=motion_phase(steps, 60.0, None, inhibit,
                                                                           budget_in=job_inputs(4, 500_000)),
                  drive_factory=job_drives(steps, opts))
        assert res.after is not None and res.after.finished
        out.append(res)
    spared, every = out
    assert spared.trace == every.trace and len(spared.trace) > 5000
    assert [[dataclasses.astuple(p) for p in a.phases] for a in spared.axes] == \
        [[dataclasses.astuple(p) for p in a.phases] for a in every.axes]
    assert [[dataclasses.astuple(s) for s in a.steps] for a in spared.after.axes] == \
        [[dataclasses.astuple(s) for s in a.steps] for a in every.after.axes]
    for n, drive in spared.drives.items():
        assert drive.mc.trajectory.samples == every.drives[n].mc.trajectory.samples


class _Alarm:
    """A bus node set from outside: it sends one frame when its alarm (set by the test) goes off."""

    def __init__(self) -> None:
        self.at: int | None = None

    def on_frame(self, frame: Frame, t_ns: int) -> list:
        return []

    def on_timer(self, t_ns: int) -> list:
        self.at = None
        return [(t_ns, Frame(0x555, b"\x01"))]

    def next_timer_ns(self) -> int | None:
        return self.at


class _SetsAlarm(IdlePredicate):
    """At its first call from scan 20 on it sets the alarm 3 ms ahead (a change to a node from outside), declaring
    it or not."""

    def __init__(self, plc, alarm: _Alarm, declares: bool) -> None:
        super().__init__(plc, [plc.var("INST0.SCANS")])      # called after every scan, also with idle scans in C
        self.alarm, self.declares, self.set_for = alarm, declares, None

    def __call__(self) -> bool:
        scan = self.begin_call()
        self.changes_nodes = False
        if scan >= 20 and self.set_for is None:
            self.alarm.at = self.set_for = self.plc.time_ns + 3_000_000
            self.changes_nodes = self.declares
        self.end_call()
        return self.set_for is not None and self.plc.time_ns > self.set_for + 5_000_000


@pytest.mark.parametrize("fast", [False, True])
def test_a_predicate_that_changes_a_node_says_so_and_the_bus_sees_it(idle_build, fast):
    """changes_nodes True after the call that changed a node: the bus reads the timers again, the node's frame goes
    at its time. Not declared, the bus keeps the timer it read last until the node's next event (a frame it
    receives; here none): the frame never goes (the contract: say so, or it is seen late or never)."""
    from linmot_st.plc import Plc
    sent = {}
    for declares in (True, False):
        plc = Plc(idle_build)
        plc["INST0.GATE"] = False           # no heartbeat: nothing else on the bus makes it read the timer
        bus = SimBus(500_000)
        alarm = _Alarm()
        bus.attach(alarm, "alarm")
        sim = CoSim(plc, bus, mailbox=MB, fast_idle=fast)
        predicate = _SetsAlarm(plc, alarm, declares)
        sim.run_until(predicate, max_scans=1000)
        sent[declares] = (predicate.set_for, [e.start_ns for e in bus.trace if e.frame.can_id == 0x555])
    due, frames = sent[True]
    assert frames == [due]
    assert sent[False][1] == []
