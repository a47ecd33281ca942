"""The motion job (`linmot-st motion`): plc_project commissions emulated drives from the example PVL file and
then moves them through its motion program; every step is checked against the PVL as written."""

from __future__ import annotations

import json

import pytest

from linmot_st.cli import main
from linmot_st.jobs.commission.project import build_project, prepare
from linmot_st.jobs.commission.runner import RunOptions
from linmot_st.jobs.motion.check import check_motion
from linmot_st.jobs.motion.job import run_job
from linmot_st.jobs.motion.plan import CURVE_DEMAND_TOLERANCE_MM, STREAM_DEMAND_TOLERANCE_MM, plan
from linmot_st.protocol import commands as C
from linmot_st.pvl import load_pvl
from repo_paths import EXAMPLES

EXAMPLE = EXAMPLES / "two_axes.pvl"
MS = 1_000_000


@pytest.fixture(scope="module")
def pvl():
    return load_pvl(EXAMPLE)


@pytest.fixture(scope="module")
def build(pvl):
    return build_project(prepare(pvl, EXAMPLE.name))


def test_plan_from_the_example(pvl):
    p = plan(pvl, 40.0)
    assert [s.kind for s in p.steps] == ["setup", "power", "home", "move", "jog", "jog", "velocity", "stop",
                                         "trigger", "probe", "stream", "cam", "move", "curve", "move", "curve", "ct",
                                         "ctwrite", "ctloop", "stop", "off"]
    assert p.steps[3].target_mm == 40.0
    curves = [s for s in p.steps if s.kind == "curve"]
    assert [s.curve_id for s in curves] == [23, 1]
    # MinJerk_100mm_400ms as written: 400 setpoints over 400 ms, 0 .. 100 mm
    run = curves[1].curve
    assert run.duration_ns == 400 * MS and run.position(0) == 0 and run.position(400 * MS) == 100 * 10_000
    assert run.position(200 * MS) == pytest.approx(50 * 10_000, abs=1500)
    ct = next(s for s in p.steps if s.kind == "ct")
    assert ct.entry == 1 and ct.chain == [1, 2] and ct.target_mm == 0.0         # Go_Out, linked Go_Home
    cam = next(s for s in p.steps if s.kind == "cam")                       # Sine_Cam_5mm now runs
    assert cam.curve_id == 2 and cam.cam.length == 4096 and not p.not_run
    assert cam.cam.position(0, 0) == 0 and max(cam.cam.position(n, 0) for n in range(4097)) == pytest.approx(
        49984, abs=1)
    assert [s.kind for s in plan(pvl, fb_steps=False).steps].count("cam") == 0
    # the PLC's command-table loop: 8 entries from 200 on, none of the file's (1..3), started as a CT step
    write, loop = (next(s for s in p.steps if s.kind == k) for k in ("ctwrite", "ctloop"))
    assert write.entry == loop.entry == 200 and not {e.entry_id for e in pvl.command_table} & set(range(200, 208))
    assert loop.plc_value()["KIND"] == "PLC_STEP_CT" and loop.count == 3 and loop.target_mm == 10.0


def test_job_on_two_axes_checks_every_step(pvl, build):
    p = plan(pvl)
    res = run_job(pvl, RunOptions(axes=2, timings="fast"), build, p)
    m = res.after
    assert m is not None and m.finished
    chk = check_motion(m, p, res.drives)
    assert chk.passed, [s.what for s in chk.steps if not s.ok]
    assert len(chk.steps) == 2 * len(p.steps)
    for s in chk.steps:
        if s.kind == "curve":
            assert s.demand_dev_mm <= CURVE_DEMAND_TOLERANCE_MM and s.actual_dev_mm < 0.3
            # the drive's own record of when it took the command is the end of that command's RxPDO3 on the bus
            node = s.axis
            frames = [e for e in res.trace if e.frame.can_id == 0x400 + node and e.end_ns == s.t_exec_ns]
            assert frames and C.command_id(int.from_bytes(frames[0].frame.data[:2], "little")) == C.TIME_CURVE
        if s.kind == "stream":                  # the PLC's sine, one setpoint per 2 ms SYNC for 800 ms
            assert s.demand_dev_mm <= STREAM_DEMAND_TOLERANCE_MM and s.what.startswith("400 setpoints")
        if s.kind == "ctloop":                  # the loop the PLC wrote ran as often as it counts
            assert s.what.startswith("3 stroke(s) out to 30 mm")
    # the PLC wrote its program through the configuration services: the drive holds it (RAM) as the catalogue
    # encodes it; a plan that expects another count fails both CT steps (the checks can fail)
    from dataclasses import replace
    steps4 = [replace(s, count=4) if s.kind in ("ctwrite", "ctloop") else s for s in p.steps]
    chk4 = check_motion(m, replace(p, steps=steps4), res.drives)
    assert {(s.kind, s.ok) for s in chk4.steps if s.kind in ("ctwrite", "ctloop")} == {("ctwrite", False),
                                                                                       ("ctloop", False)}
    assert all(s.ok for s in chk4.steps if s.kind not in ("ctwrite", "ctloop"))
    # the SYNC producer ran only for the stream steps: 80h frames about every 2 ms of them, none before
    syncs = [e.start_ns for e in res.trace if e.frame.can_id == 0x080]
    streams = [r for ax in m.axes for r in ax.steps if r.kind == "stream"]
    assert syncs and min(syncs) >= min(r.t0_ns for r in streams) and max(syncs) <= max(r.t1_ns for r in streams)
    # the PLC's steps came one after the other, the curve steps took at least their curve time
    for ax in m.axes:
        assert [r.index for r in ax.steps] == list(range(1, len(p.steps) + 1))
        for r in ax.steps:
            step = p.steps[r.index - 1]
            if step.kind == "curve":
                assert r.duration_ns >= step.curve.duration_ns


def test_an_axis_that_cannot_follow_fails_the_job(pvl, build):
    p = plan(pvl)

    def block_axis_1(bus, drives):
        def block(t):
            drives[1].mc.block(True, t)
        bus.call_at(12_000 * MS, block)              # in the motion program (after the commissioning)

    res = run_job(pvl, RunOptions(axes=2, timings="real"), build, p, prepare_bus=block_axis_1)
    m = res.after
    assert m is not None
    ax1, ax2 = m.axes
    assert ax1.error and ax1.drive_error in (0x000B, 0x000C) and ax2.done
    chk = check_motion(m, p, res.drives)
    assert not chk.passed
    assert all(s.ok for s in chk.steps if s.axis == 2)


def test_motion_command_writes_the_reports(tmp_path, capsys):
    report = tmp_path / "report"
    rc = main(["motion", str(EXAMPLE), "--axes", "2", "--report", str(report), "--position", "30"])
    out = capsys.readouterr()
    assert rc == 0, out.out[-2000:]
    assert "result: PASSED (2 axes commissioned and verified)" in out.out
    assert "motion job: PASSED" in out.out and "not run:" not in out.out
    assert "axis 1: step 3 home (MC_Home)" in out.err
    fig = json.loads((report / "motion.json").read_text())
    assert fig["passed"] and len(fig["rows"]) == 42 and all(r["ok"] for r in fig["rows"])
    assert fig["rows"][3]["label"] == "move to 30 mm"
    for name in ("report.md", "report.json", "can.log", "motion.md", "motion-axis1.png", "motion-axis2.png"):
        assert (report / name).exists(), name
    assert (report / "motion-axis2.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert out.out.splitlines()[0].startswith(f"linmot-st motion {EXAMPLE} --axes 2")


def test_motion_command_refuses_bad_arguments(capsys):
    with pytest.raises(SystemExit) as exit_:                   # argparse's check, in the commands' one style
        main(["motion", str(EXAMPLE), "--axes", "33"])
    assert exit_.value.code == 2
    assert "linmot-st motion: error: argument --axes: 33: must be 1..32" in capsys.readouterr().err


def test_motion_job_on_python_can_virtual_bus(pvl, build):
    """Real time: the drive served by a NodeServer thread, the PLC by RealTimeCoSim; each has its own clock.
    Under load (tests/support/realtime.py): seen failing with NoProcessData (16#0704) after the host held the process
    for about 300 ms (a 326 ms step in 30 scans), longer than the program's PdoTimeout; such a run is
    measured again. What must hold is what the job checks (every step, in order) and no false success."""
    from realtime import retry_after_stall

    p = plan(pvl, stream=False)             # a Python PLC in real time cannot keep a 2 ms SYNC stream
    assert "stream" not in [s.kind for s in p.steps] and "PLC-streamed" in p.not_run[-1]

    def attempt():
        res = run_job(pvl, RunOptions(axes=1, bus="virtual"), build, p)
        res.check = check_motion(res.after, p, res.drives) if res.after is not None else None
        return res

    def passed(res) -> bool:
        return res.after is not None and res.after.finished and res.check.passed

    res, stalls = retry_after_stall(attempt, passed)
    assert passed(res), (stalls, res.max_lateness_ns, res.after and [s.what for s in res.check.steps if not s.ok])
    ax = res.after.axes[0]
    assert [r.index for r in ax.steps] == list(range(1, len(p.steps) + 1))       # every step, in order
    assert len(res.check.steps) == len(p.steps)


def test_jog_and_velocity_steps_on_two_axes(pvl, build):
    p = plan(pvl)
    res = run_job(pvl, RunOptions(axes=2, timings="fast"), build, p)
    chk = check_motion(res.after, p, res.drives)
    by = {(s.axis, s.index): s for s in chk.steps}
    kinds = [s.kind for s in p.steps]
    jf, jb, vel = kinds.index("jog"), kinds.index("jog") + 1, kinds.index("velocity")
    for axis, node in ((1, 1), (2, 2)):
        assert all(by[(axis, k + 1)].ok for k in (jf, jb, vel, vel + 1, vel + 2, vel + 3)), \
            [by[(axis, k + 1)].what for k in range(len(p.steps))]
        # on the trajectory: forward at the jog velocity, back, then at the velocity, then stopped
        traj = res.drives[node].mc.trajectory
        recs = {r.index: r for r in res.after.axes[axis - 1].steps}
        fwd = traj.between(recs[jf + 1].t0_ns, recs[jf + 1].t1_ns)
        back = traj.between(recs[jb + 1].t0_ns, recs[jb + 1].t1_ns)
        assert max(s.demand_velocity for s in fwd) == pytest.approx(50 * 10_000, rel=1e-3)
        assert min(s.demand_velocity for s in back) == pytest.approx(-50 * 10_000, rel=1e-3)
        assert fwd[-1].actual - fwd[0].actual > 10 * 10_000 and back[-1].actual - back[0].actual < -10 * 10_000
        stop = traj.at(recs[vel + 2].t1_ns)
        assert stop.demand_velocity == 0
    # the RAM parameters MC_Jog / MC_MoveVelocity wrote are listed (the commissioning is checked without them)
    assert set(res.after.ram_changed[1]) >= {0x14BE, 0x14BF}


def test_a_jog_the_wrong_way_fails_with_the_figures(pvl, build):
    import dataclasses
    p = plan(pvl)
    k = [s.kind for s in p.steps].index("jog")
    wrong = dataclasses.replace(p, steps=list(p.steps))
    wrong.steps[k] = dataclasses.replace(p.steps[k], velocity=-p.steps[k].velocity)   # the PLC jogs back
    res = run_job(pvl, RunOptions(axes=2, timings="fast"), build, wrong)
    chk = check_motion(res.after, p, res.drives)                   # checked against the jog forward
    bad = [s for s in chk.steps if not s.ok]
    assert {(s.axis, s.index) for s in bad} == {(1, k + 1), (2, k + 1)}
    assert "forward (command 50" in bad[0].what and "moved -" in bad[0].what


def test_trigger_and_probe_steps_follow_the_edges_the_job_raises(pvl, build):
    p = plan(pvl)
    res = run_job(pvl, RunOptions(axes=2, timings="fast"), build, p)
    kinds = [s.kind for s in p.steps]
    trig, probe = kinds.index("trigger") + 1, kinds.index("probe") + 1
    for ax in res.after.axes:
        recs = {r.index: r for r in ax.steps}
        drive = res.drives[ax.node_id]
        traj = drive.mc.trajectory
        edge = recs[trig].edge_ns
        # armed, then still until the edge on X4.6, at the target after it
        assert recs[trig].t0_ns < edge < recs[trig].t1_ns
        assert all(s.demand_velocity == 0 for s in traj.between(recs[trig].t0_ns, edge))
        assert abs(traj.at(recs[trig].t1_ns).actual / 10_000 - 60.0) <= 0.1
        # the PLC's capture is the drive's 1E62h and the actual position at the X4.5 edge
        pedge = recs[probe].edge_ns
        assert recs[probe].probed_mm == pytest.approx(traj.at(pedge).actual / 10_000, abs=1e-4)
        assert drive.io.input("X4.5") == 0 and drive.io.input("X4.6") == 0      # the pulses ended
    assert check_motion(res.after, p, res.drives).passed


def test_a_trigger_never_raised_fails_with_a_readable_message(pvl, build):
    p = plan(pvl)
    res = run_job(pvl, RunOptions(axes=2, timings="fast"), build, p, toggle_inputs=False, timeout_s=3.0)
    m = res.after
    assert m.timed_out and not m.finished
    chk = check_motion(m, p, res.drives)
    k = [s.kind for s in p.steps].index("trigger") + 1
    for axis in (1, 2):
        bad = [s for s in chk.steps if s.axis == axis and not s.ok]
        assert [s.what for s in bad] == ["the motion program did not finish", bad[1].what]
        assert bad[1].index == k and bad[1].what.startswith("no edge on X4.6: the job never raised the input")


def test_cam_step_follows_the_conveyor_the_job_turns(pvl, build):
    import dataclasses
    p = plan(pvl)
    res = run_job(pvl, RunOptions(axes=2, timings="fast"), build, p)
    k = [s.kind for s in p.steps].index("cam")
    chk = check_motion(res.after, p, res.drives)
    cams = [s for s in chk.steps if s.kind == "cam"]
    assert len(cams) == 2 and all(s.ok and s.demand_dev_mm <= 0.001 for s in cams), [s.what for s in cams]
    for ax in res.after.axes:
        rec = next(r for r in ax.steps if r.index == k + 1)
        drive = res.drives[ax.node_id]
        # the conveyor turned one cam length (4096 counts) while the axis was coupled
        assert drive.mc.encoder.counts(rec.edge_end_ns) - drive.mc.encoder.counts(rec.edge_ns) == pytest.approx(4096)
        traj = drive.mc.trajectory
        swing = [s.demand for s in traj.between(rec.edge_ns, rec.edge_end_ns)]
        assert max(swing) - min(swing) == pytest.approx(2 * 49984, abs=50)          # +-5 mm as written
    # the same run checked against a cam of twice the amplitude fails with the figures
    wrong = dataclasses.replace(p, steps=list(p.steps))
    wrong.steps[k] = dataclasses.replace(p.steps[k], cam=dataclasses.replace(p.steps[k].cam, amplitude=2.0))
    bad = [s for s in check_motion(res.after, wrong, res.drives).steps if not s.ok]
    assert [s.index for s in bad] == [k + 1, k + 1]
    assert bad[0].what.startswith("demand within 4.99") and "of the cam as written at the master count" in bad[0].what
