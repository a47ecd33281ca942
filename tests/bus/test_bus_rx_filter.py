"""Nodes' acceptance filters on the simulated bus (`rx_filter`, SimBus(rx_filters=...)) and one transmit
buffer per CAN-ID for a node with several buffers (`tx_by_priority`): what they change and what they must
not (docs/bus.md, "Receive filters" and "Transmit queues")."""

from __future__ import annotations

import pytest

from linmot_st.bus import Frame, SimBus
from linmot_st.bus.nodes import ScriptedNode
from repo_paths import REPO


class Recorder(ScriptedNode):
    """Records the frames it is offered; `rx_filter` as given (None: every frame); a filtered one widens its
    filter to 0x300 when it gets 0x100."""

    def __init__(self, script=(), rx_filter=None):
        super().__init__(list(script))
        self.rx_filter = rx_filter
        self.seen: list[int] = []

    def on_frame(self, frame, t_ns):
        self.seen.append(frame.can_id)
        if frame.can_id == 0x100 and self.rx_filter is not None:     # "listen to 0x300 from now on"
            self.rx_filter = frozenset({0x100, 0x300})
        return super().on_frame(frame, t_ns)


def test_a_node_is_offered_only_what_its_filter_accepts_and_the_filter_is_read_again_after_each_frame():
    bus = SimBus()
    node = Recorder(rx_filter=frozenset({0x100}))
    plain = Recorder()                                   # no filter: every frame
    bus.attach(node, "node")
    bus.attach(plain, "plain")
    plc = bus.endpoint("plc")
    for k, cid in enumerate((0x300, 0x200, 0x100, 0x300, 0x200)):
        plc.send(Frame(cid, bytes([k])), k * 1_000_000)
    bus.run_until(10_000_000)
    assert node.seen == [0x100, 0x300]                   # the first 0x300 came before the filter took it
    assert plain.seen == [0x300, 0x200, 0x100, 0x300, 0x200]
    assert [e.frame.can_id for e in bus.trace] == [0x300, 0x200, 0x100, 0x300, 0x200]   # the bus is the bus


def test_a_filter_changed_in_place_is_read_at_each_frame():
    # the bus keeps the receivers of each CAN-ID while every filter is a frozenset; a set the node changes in place
    # (the same object) is looked at anew for every frame
    class InPlace(Recorder):
        def on_frame(self, frame, t_ns):
            self.seen.append(frame.can_id)
            if frame.can_id == 0x100:
                self.rx_filter.add(0x300)
            return []

    bus = SimBus()
    node = InPlace(rx_filter={0x100})
    fixed = Recorder(rx_filter=frozenset({0x300}))
    bus.attach(node, "node")
    bus.attach(fixed, "fixed")
    plc = bus.endpoint("plc")
    for k, cid in enumerate((0x300, 0x100, 0x300, 0x200, 0x300)):
        plc.send(Frame(cid, bytes([k])), k * 1_000_000)
    bus.run_until(10_000_000)
    assert node.seen == [0x100, 0x300, 0x300]
    assert fixed.seen == [0x300, 0x300, 0x300]


def test_the_bus_can_offer_every_frame_to_every_node():
    bus = SimBus(rx_filters=False)
    node = Recorder(rx_filter=frozenset({0x100}))
    bus.attach(node, "node")
    plc = bus.endpoint("plc")
    plc.send(Frame(0x200, b"\x01"), 0)
    bus.run_until(1_000_000)
    assert node.seen == [0x200]


def test_one_transmit_buffer_per_can_id_keeps_the_newest_data_of_an_unsent_frame():
    """While another node holds the bus, a node with several transmit buffers queues a second frame of the same
    CAN-ID: it takes the first one's place (the first one's data is lost, counted); a node with one FIFO sends
    both. A frame not ready yet never replaces anything."""
    def run(by_priority: bool):
        bus = SimBus()
        busy = ScriptedNode([(0, Frame(0x080, bytes(8)))])          # 8 bytes: ~220 us at 500 kbit/s
        node = ScriptedNode([(10_000, Frame(0x181, b"\x01")), (20_000, Frame(0x181, b"\x02")),
                             (20_000, Frame(0x701, b"\x05")), (5_000_000, Frame(0x181, b"\x03"))])
        node.tx_by_priority = by_priority
        bus.attach(busy, "busy")
        bus.attach(node, "drive")
        bus.run_until(10_000_000)
        return [(e.frame.can_id, e.frame.data) for e in bus.trace], bus._part("drive").overwritten

    trace, overwritten = run(True)
    assert trace == [(0x080, bytes(8)), (0x181, b"\x02"), (0x701, b"\x05"), (0x181, b"\x03")]
    assert overwritten == 1
    trace, overwritten = run(False)
    assert trace == [(0x080, bytes(8)), (0x181, b"\x01"), (0x181, b"\x02"), (0x701, b"\x05"), (0x181, b"\x03")]
    assert overwritten == 0


def bus_with(filters: bool) -> type:
    """SimBus with the nodes' filters on or off, for code that makes its own bus."""
    class Bus(SimBus):
        def __init__(self, bitrate=500_000, *, rx_filters=filters):
            super().__init__(bitrate, rx_filters=rx_filters)
    return Bus


def test_a_frame_still_in_the_nodes_latency_replaces_nothing():
    """Two frames of one CAN-ID 50 us apart from a node with a 100 us latency, on an idle bus: the first is sent
    before the second is ready (in the buffer), so both go."""
    bus = SimBus()
    node = ScriptedNode([(0, Frame(0x181, b"\x01")), (50_000, Frame(0x181, b"\x02"))])
    node.tx_by_priority = True
    bus.attach(node, "drive", latency_ns=100_000)
    bus.run_until(5_000_000)
    assert [e.frame.data for e in bus.trace] == [b"\x01", b"\x02"] and bus._part("drive").overwritten == 0


@pytest.mark.parametrize("axes", [2, 8])
def test_the_demo_puts_the_same_frames_on_the_bus_with_and_without_the_drives_filters(monkeypatch, axes):
    """The demo's scenario (commissioning with real drive timings, then the motion steps; 8 axes load the bus
    enough for TxPDOs to wait): the emulated drive's filter (E1100Drive.rx_filter) only spares the calls, the
    trace, phases and steps are identical to offering every frame to every drive."""
    import dataclasses

    from linmot_st.jobs.commission import runner as runner_mod
    from linmot_st.jobs.commission.runner import RunOptions
    from linmot_st.jobs.commission.testing import project_build
    from linmot_st.jobs.motion.budget import job_budget, job_inputs
    from linmot_st.jobs.motion.job import job_drives, motion_phase, run
    from linmot_st.jobs.motion.plan import plan as make_plan
    from linmot_st.pvl import load_pvl

    pvl = load_pvl(REPO / "examples" / "two_axes.pvl")
    steps = make_plan(pvl, 50.0)
    inhibit = job_budget(axes, 500_000)[1].interval_100us       # TxPDO2's inhibit time as the job plans it
    build = project_build("builtin")
    out = {}
    for filters in (False, True):
        monkeypatch.setattr(runner_mod, "SimBus", bus_with(filters))       # the bus the run makes
        opts = RunOptions(axes=axes, timings="real")
        res = run(pvl, opts, build, after=motion_phase(steps, 60.0, None, inhibit, budget_in=job_inputs(axes, 500_000)),
                  drive_factory=job_drives(steps, opts))
        assert res.after is not None and res.after.finished
        out[filters] = res
    plain, filtered = out[False], out[True]
    assert len(plain.trace) > 1000
    assert plain.trace == filtered.trace
    assert [[dataclasses.astuple(p) for p in a.phases] for a in plain.axes] == \
        [[dataclasses.astuple(p) for p in a.phases] for a in filtered.axes]
    assert [[dataclasses.astuple(s) for s in a.steps] for a in plain.after.axes] == \
        [[dataclasses.astuple(s) for s in a.steps] for a in filtered.after.axes]


def test_the_motion_bench_with_sync_is_the_same_with_and_without_the_drives_filters(monkeypatch):
    """Three drives moving with TxPDO2 on every SYNC (the emulator's bench scenario): SYNC, the RxPDOs and the
    other drives' frames, with the filters and without, give the same trace and trajectories."""
    from linmot_st_bench import emulator_mc as bench

    out = {}
    for filters in (False, True):
        monkeypatch.setattr(bench, "SimBus", bus_with(filters))
        bus, master, drives = bench._setup(3)
        bus.run_until(master.moves_from + 1_500_000_000)
        out[filters] = ([(e.start_ns, e.sender, e.frame) for e in bus.trace],
                        [list(d.mc.trajectory.samples) for d in drives])
    (trace, samples), (ftrace, fsamples) = out[False], out[True]
    assert sum(f.can_id == 0x080 for _, _, f in trace) > 300 and trace == ftrace
    assert all(len(s) > 1000 for s in samples) and samples == fsamples
