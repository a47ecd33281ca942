"""Commissioning end to end: the PLC (plc_project with the dataset of examples/two_axes.pvl) commissions
emulated E1100 drives on the simulated bus; checked from the drives' memory, the bus trace and the report.

One build per backend serves every test (linmot_st.jobs.commission.testing)."""

from __future__ import annotations

import json
import os
import re

import pytest

from linmot_st.bus.bits import bus_bits, unstuffed_bus_bits
from linmot_st.cli import main
from linmot_st.jobs.commission.testing import EXAMPLE, commission, example
from linmot_st.pvl.dataset import INFO_WORDS, PREFLIGHT_EXCHANGES
from linmot_st.toolchain.testing import BACKEND_PARAMS

PVL = example()
CURVE_EXCHANGES = 1 + sum(1 + INFO_WORDS + len(c.setpoints) for c in PVL.curves)   # 41h, then 50h, 54h x 18, 53h x N
EXPECTED = {"check": 3 * 2, "preflight": PREFLIGHT_EXCHANGES * 30, "params": 30, "curves": CURVE_EXCHANGES,
            "ct": 1 + 33 * 3, "verify": 30 + (CURVE_EXCHANGES - 1) + 33 * 3}


TRANSFER = sum(EXPECTED.values())                    # one axis' exchanges in CHECK, PARAMS, CURVES, CT, VERIFY
FLASH_NECESSARY = 1 + 2 + 2 + 1                      # stop MC, save and one poll per store (curves, CT), start MC
FRAME_BITS = unstuffed_bus_bits(8)                   # 111


def bound_ms(exchanges: int, bitrate: int = 500_000) -> float:
    """The bus-time lower bound: exchanges x 2 frames x 111 bits / bit rate."""
    return exchanges * 2 * FRAME_BITS / bitrate * 1e3


def requests(result, node: int) -> list:
    return [e for e in result.trace if e.frame.can_id == 0x600 + node and e.status != "error"]


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_one_axis(backend):
    o = commission(backend, axes=1)
    ax = o.axis(1)
    assert ax.done and not ax.error and ax.error_id == 0
    assert o.verification.ok, o.report.text()
    phases = {p.phase: p for p in ax.phases}
    assert list(phases) == ["start", "check", "preflight", "params", "curves", "ct", "flash", "verify"]
    for name, n in EXPECTED.items():
        assert phases[name].exchanges == n, name
    # the answer is checked and the next request sent in the scan that sees it, across items and phases:
    # a request leaves at most one task interval after the previous answer ended; the exceptions are the
    # pre-flight's curve records (read from the dataset, one per scan, no exchange) and the header
    tick = o.result.tick_ns
    windows = [(p.t0_ns, p.t1_ns) for p in ax.phases if p.phase in ("check", "preflight", "params", "curves", "ct",
                                                                      "verify")]
    frames = [e for e in o.result.trace if e.status != "error" and e.frame.can_id in (0x581, 0x601)]
    gaps = [b.start_ns - a.end_ns for w0, w1 in windows for a, b in zip(frames, frames[1:])
            if a.frame.can_id == 0x581 and w0 <= a.start_ns and b.start_ns < w1]
    assert gaps and min(gaps) >= 0
    assert sum(g > tick for g in gaps) <= len(PVL.curves) + 2, sorted(gaps)[-8:]
    assert max(gaps) <= (len(PVL.curves) + 2) * tick
    assert (phases["start"].scans, phases["start"].exchanges) == (2, 0)
    # the bus carried exactly the FB's requests, each answered
    assert len(requests(o.result, 1)) == ax.exchanges
    assert sum(1 for e in o.result.trace if e.frame.can_id == 0x581) == ax.exchanges
    drive = o.result.drives[1]
    assert sorted(drive.curves.flash) == sorted(drive.curves.ram) == [1, 2, 23]
    assert sorted(drive.ct.flash) == [1, 2, 3]
    assert drive.string(0x03E8) == "LinMot-ST Demo" and drive.rom(0x146E) == -100000
    text = o.report.text()
    assert "result: PASSED" in text and re.search(r"curves +532 +[0-9]+ ", text)


@pytest.mark.parametrize("force", [True, False], ids=["full", "recommission"])
def test_both_backends_put_the_same_frames_on_the_bus(force):
    from linmot_st.toolchain import builtin_available, matiec_available
    if not (matiec_available() and builtin_available()):
        pytest.skip("needs both MatIEC and the builtin compiler")
    traces = []
    for backend in ("matiec", "builtin"):
        o = commission(backend, axes=1, verify=not force, flash=not force, force=force)
        traces.append([(e.start_ns, e.frame.can_id, e.frame.data) for e in o.result.trace])
    assert traces[0] == traces[1]


def test_two_axes_in_parallel():
    one = commission(axes=1)
    two = commission(axes=2)
    assert all(a.done for a in two.result.axes) and two.verification.ok, two.report.text()
    for node in (1, 2):
        assert len(requests(two.result, node)) == two.axis(node).exchanges == one.axis(1).exchanges
        assert {c.what: c.equal for c in two.verification.for_node(node) if c.required} == {
            "parameters ROM": 30, "curves RAM": 3, "curves flash": 3, "command table RAM": 3,
            "command table flash": 3}
    # the two axes progress together: the run takes about as long as one axis alone, not twice as long
    t1 = one.result.t_end_ns - one.result.t_start_ns
    t2 = two.result.t_end_ns - two.result.t_start_ns
    assert t2 <= t1 + 10_000_000, (t1, t2)
    assert two.report.figures["bus"]["load"] > 1.8 * one.report.figures["bus"]["load"]


def test_other_node_ids_and_live_ram():
    o = commission(axes=2, node_ids=[5, 17], live_ram=True, verify=False)
    assert [a.node_id for a in o.result.axes] == [5, 17] and all(a.done for a in o.result.axes)
    drive = o.result.drives[17]
    live = [p.upid for obj in PVL.parameter_objects for p in obj.parameters if drive.params[p.upid].live]
    assert 0 < len(live) < 30
    ax = o.axis(17)
    assert ax.live_written == len(live)
    # RAM+ROM first; a non-live parameter is refused as a whole, then written to ROM only
    params = next(p for p in ax.phases if p.phase == "params")
    assert params.exchanges == 30 + (30 - len(live))
    assert o.verification.ok, o.report.text()                      # RAM of the live parameters checked
    for upid in live:
        assert drive.ram(upid) == drive.rom(upid)
    assert {e.frame.can_id for e in o.result.trace} >= {0x605, 0x611, 0x585, 0x591}


def test_report_figures_agree_with_the_trace():
    """Every figure of the report recomputed from its definition: the bounds from the exchange counts, the
    bus's busy time from the frames' bit lengths, the plotted read-back from the 62h answers on the bus."""
    from linmot_st.jobs.commission.plots import read_back_from_trace

    o = commission(axes=2)
    f, r = o.report.figures, o.result
    assert FRAME_BITS == 111 and f["bus"]["frame_bits"] == FRAME_BITS
    for a in f["axes"]:
        for p in a["phases"]:
            assert p["lower_bound_ms"] == pytest.approx(bound_ms(p["exchanges"]), rel=1e-12), p["phase"]
            if p["exchanges"] and p["phase"] not in ("start", "flash", "reset"):
                assert p["ratio"] == pytest.approx(p["time_ms"] / p["lower_bound_ms"])
        assert a["transfer"]["exchanges"] == TRANSFER
        assert a["transfer"]["lower_bound_ms"] == pytest.approx(bound_ms(TRANSFER), rel=1e-12)
    # the run: the bound counts the necessary exchanges of both axes; the actual ones stand beside it
    assert f["run"]["necessary_exchanges"] == 2 * (TRANSFER + FLASH_NECESSARY)      # no reset in this run
    assert f["run"]["exchanges"] == sum(a.exchanges for a in r.axes) > f["run"]["necessary_exchanges"]  # polls
    assert f["bus"]["lower_bound_ms"] == pytest.approx(bound_ms(2 * (TRANSFER + FLASH_NECESSARY)), rel=1e-12)
    assert f["bus"]["lower_bound_actual_ms"] == pytest.approx(bound_ms(f["run"]["exchanges"]), rel=1e-12)
    assert f["bus"]["ratio"] == pytest.approx(f["run"]["time_ms"] / f["bus"]["lower_bound_ms"])
    # transfer phases of all axes: one bus, two drives writing at once
    tr = f["transfer"]
    assert tr["exchanges"] == tr["necessary_exchanges"] == 2 * TRANSFER
    assert tr["lower_bound_ms"] == pytest.approx(bound_ms(2 * TRANSFER), rel=1e-12)
    assert tr["ratio"] == pytest.approx(tr["time_ms"] / tr["lower_bound_ms"]) and 1.0 < tr["ratio"] < 1.2
    assert tr["load"] > 0.9                                          # the bus is the limit for two axes
    # the bus's busy time is the frames' bit lengths (stuff bits and IFS included) clipped to the window: the
    # drives' PDOs on entering Operational (the channel's NMT start on their boot-up) are still on the wire
    # when the axes start together, so the first of them straddles the window's start
    t0, t1 = r.t_start_ns, r.t_end_ns
    assert not any(e.status == "error" for e in r.trace)
    window = [e for e in r.trace if t0 <= e.start_ns < t1]
    assert f["bus"]["frames"] == len(window) < f["bus"]["frames_in_trace"] == len(r.trace)

    def busy_in_window(e):
        return max(0, min(e.start_ns + bus_bits(e.frame) * r.bit_ns, t1) - max(e.start_ns, t0))
    busy_ns = sum(busy_in_window(e) for e in r.trace)
    assert r.stats.busy_ns == busy_ns
    assert f["bus"]["busy_ms"] == pytest.approx(busy_ns / 1e6, rel=1e-12)
    # what the plots show as read back is what the PVL says, for every curve and drive
    for ax in r.axes:
        t_verify = next(p.t0_ns for p in ax.phases if p.phase == "verify")
        for c in PVL.curves:
            assert read_back_from_trace(r.trace, ax.node_id, c.curve_id, t_verify) == list(c.setpoints)
    assert all(n["verdict"] == "read back = written" and n["source"] == "bus"
               for c in f["curves"] for n in c["nodes"])
    text = o.report.text()
    assert "bus LB: bus-time lower bound = exchanges x 2 frames x 111 bits / 500 kbit/s" in text
    assert f"  transfer phases{2 * TRANSFER:>17}{2 * TRANSFER:>11}" in text


def test_reset_then_verify_reads_what_survives_the_restart():
    o = commission(axes=1, reset=True)
    ax = o.axis(1)
    assert ax.done and o.verification.ok, o.report.text()
    assert [p.phase for p in ax.phases] == ["start", "check", "preflight", "params", "curves", "ct", "flash", "reset",
                                            "verify"]
    drive = o.result.drives[1]
    assert drive.nmt_state == "OPERATIONAL"
    ram = next(c for c in o.verification.for_node(1) if c.what == "parameters RAM")
    assert ram.required and ram.equal == 30                         # after the reset RAM = ROM everywhere
    assert sum(1 for e in o.result.trace if e.frame.can_id == 0x701 and e.frame.data == b"\x00") == 2
    # back only once it said Operational: 0Bh, then 1017h read (0: no heartbeat), set to 10 ms, set back
    reset = next(p for p in ax.phases if p.phase == "reset")
    assert reset.exchanges == 4 and drive.comm.value(0x1017) == 0
    beats = [e for e in o.result.trace if e.frame.can_id == 0x701 and reset.t0_ns <= e.start_ns < reset.t1_ns
             and e.frame.data != b"\x00"]
    assert beats and beats[-1].frame.data == b"\x05"              # the heartbeat that ended the check


def test_the_demo_command(tmp_path, capsys):
    """`make demo`'s commissioning as the full write (--force; realistic drive timings, flash, reset, verify): its
    figures are known from the dataset (the default, re-commissioning: tests/jobs/commission/test_commission_recommission.py)."""
    report = tmp_path / "report"
    trace = tmp_path / "run.blf"
    report.mkdir()
    (report / "curve_99.png").write_bytes(b"an earlier report's plot")     # a reused folder
    (report / "can.asc").write_text("an earlier report's trace")
    assert main(["commission", str(EXAMPLE), "--axes", "2", "--report", str(report), "--trace", str(trace),
                 "--force"]) == 0
    out = capsys.readouterr()
    assert "result: PASSED (2 axes commissioned and verified)" in out.out
    assert "node 1   parameters          done: 30 parameters, 30 exchanges, 30 scans" in out.err
    command = f"linmot-st commission {EXAMPLE} --axes 2 --trace {trace} --report {report} --force"
    assert out.out.splitlines()[0] == command
    names = sorted(p.name for p in report.iterdir())
    assert names == sorted(["report.md", "report.json", "can.log"] +
                           [f"curve_{c}.png" for c in (1, 2, 23)])
    fig = json.loads((report / "report.json").read_text())
    assert fig["result"] == {"commissioned": True, "verified": True, "passed": True}
    assert [p["phase"] for p in fig["axes"][0]["phases"]] == ["start", "check", "preflight", "params", "curves", "ct",
                                                             "flash", "reset", "verify"]
    assert fig["axes"][1]["exchanges"] == fig["axes"][1]["exchanges_on_bus"]
    need = 2 * (TRANSFER + FLASH_NECESSARY + 1)                       # + the reset request
    assert fig["run"]["necessary_exchanges"] == need
    assert fig["bus"]["lower_bound_ms"] == pytest.approx(bound_ms(need), rel=1e-12)
    assert fig["bus"]["ratio"] == pytest.approx(fig["run"]["time_ms"] / bound_ms(need))
    assert (report / "report.md").read_text().splitlines()[0] == f"# Commissioning report: `{command}`"
    # the progress lines and the report give the same end times
    for a in fig["axes"]:
        assert f"{a['end_ms']:9.1f} ms  node {a['node']:<3} commissioned" in out.err
    assert (report / "curve_1.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    from linmot_st.bus.trace import read_trace
    logged = read_trace(report / "can.log")
    assert len(logged) == len(read_trace(trace)) >= fig["bus"]["frames"]


def test_progress_on_a_terminal_and_in_a_log():
    import io

    from linmot_st.jobs.commission.progress import Progress

    tty, log = io.StringIO(), io.StringIO()
    commission(axes=2, verify=False, progress=Progress(tty, tty=True, interval_s=0))
    commission(axes=2, verify=False, progress=Progress(log, tty=False))
    assert "\r\x1b[2K" in tty.getvalue() and "node 2: curves [" in tty.getvalue()     # the redrawn status line
    lines = log.getvalue().splitlines()
    assert "\r" not in log.getvalue() and len(lines) == 2 * 7                          # 6 phases + the end, per axis
    assert lines[0].endswith("node 1   compatibility check done: 2 layers, 6 exchanges, 6 scans")
    assert lines[-1].endswith("node 2   commissioned")


def test_virtual_bus_in_real_time():
    if os.environ.get("CI_NO_REALTIME"):
        pytest.skip("real-time tests disabled")
    # under load (tests/support/realtime.py): a run that failed after a host stall longer than 50 ms is measured again
    from realtime import retry_after_stall

    outcomes = []

    def attempt():
        outcomes.append(commission(axes=1, bus="virtual", verify=False))
        return outcomes[-1].result

    _, stalls = retry_after_stall(attempt, lambda r: outcomes[-1].axis(1).done and outcomes[-1].verification.ok)
    o = outcomes[-1]
    ax = o.axis(1)
    assert ax.done and o.verification.ok, (stalls, o.report.text())
    assert len(requests(o.result, 1)) == ax.exchanges                # the recorded trace holds every frame
    assert [p.phase for p in ax.phases] == ["start", "check", "preflight", "params", "curves", "ct", "flash"]
    # PLC time runs with the wall clock and never ahead of it: an overrun moves the PLC's clock to the wall
    # time in whole ticks (cosim.py), so this holds however loaded the machine
    assert o.result.wall_s >= (o.result.t_end_ns - o.result.t_start_ns) / 1e9 * 0.95
