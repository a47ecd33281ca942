"""32 drives on one bus (issue 12): plc_project commissions them all, with one dataset and with a dataset per
node, verified by reading back each emulated drive; the per-axis report; the CLI's --pvl errors.

The datasets are the example without its curves (parameters and command table only), so that a 32-axis run
stays short (docs/commissioning.md, "Tests")."""

from __future__ import annotations

import dataclasses
import time
import types

import pytest

from linmot_st.cli import main
from linmot_st.jobs.commission.datasets import Datasets
from linmot_st.jobs.commission.project import build_project, prepare
from linmot_st.jobs.commission.report import Context, Report
from linmot_st.jobs.commission.runner import RunOptions, run
from linmot_st.jobs.commission.testing import EXAMPLE, example
from linmot_st.jobs.commission.verify import verify_run
from linmot_st.pvl.to_st import to_st

NODES = list(range(1, 33))


def without_curves(pvl, keep_entries: bool = True):
    drop = set(map(id, pvl.curves)) | (set() if keep_entries else set(map(id, pvl.command_table)))
    return dataclasses.replace(pvl, objects=tuple(o for o in pvl.objects if id(o) not in drop))


def commission_all(datasets: Datasets, nodes=NODES, bitrate=1_000_000):
    project = prepare(datasets.default.pvl, datasets.default.name, text=datasets.st_text())
    res = build_project(project)
    # the full write (Force): the bounds are those of the necessary exchanges of a full write (report.py)
    opts = RunOptions(axes=len(nodes), node_ids=nodes, bitrate=bitrate, timings="fast", reset=False, force=True)
    t0 = time.perf_counter()
    result = run(datasets.default.pvl, opts, res, datasets=datasets)
    wall = time.perf_counter() - t0
    verification = verify_run(datasets.default.pvl, result)
    ctx = Context(datasets.default.name, "test", res.backend, 0.0, True, "plc_project/plc.st",
                  datasets.default.dataset.words)
    report = Report(ctx, result, datasets.default.dataset, verification, datasets.default.pvl)
    report.compute()
    return result, verification, report, wall


def test_32_axes_one_dataset():
    pvl = without_curves(example())
    result, verification, report, wall = commission_all(Datasets.build(pvl, "no_curves.pvl"))
    assert [a.node_id for a in result.axes] == NODES and all(a.done for a in result.axes)
    assert verification.ok and {c.node for c in verification.checks} == set(NODES)
    f = report.figures
    assert len(f["axes"]) == 32 and all(a["result"] == "done" for a in f["axes"])
    tr = f["transfer"]
    # both bounds are printed; the stuffed one (exact bits) is longer than the unstuffed one
    assert tr["lower_bound_stuffed_ms"] > tr["lower_bound_ms"] > 0
    text = report.text()
    assert "stuffed bound" in text and text.count("commissioned in") == 32
    assert wall < 30


def test_32_axes_two_datasets_each_drive_holds_its_own():
    a = without_curves(example())
    b = without_curves(example(), keep_entries=False)          # another dataset: no command table
    datasets = Datasets.build(a, "a.pvl", {n: (b, "b.pvl") for n in NODES if n % 2 == 0})
    assert [s.base for s in datasets.sources] == [1, datasets.default.dataset.words + 1]
    result, verification, report, _ = commission_all(datasets)
    assert all(ax.done for ax in result.axes) and verification.ok
    axes = {x["node"]: x for x in report.figures["axes"]}
    assert axes[1]["dataset"] == "a.pvl" and axes[2]["dataset"] == "b.pvl"
    # one dataset line per file, with its nodes and its own counts
    sets = {d["name"]: d for d in report.figures["datasets"]}
    assert sets["a.pvl"]["nodes"] == NODES[0::2] and sets["b.pvl"]["nodes"] == NODES[1::2]
    assert sets["a.pvl"]["entries"] == len(a.command_table) > 0 == sets["b.pvl"]["entries"]
    text = report.text()
    assert "  dataset a.pvl (nodes 1, 3, 5," in text and "  dataset b.pvl (nodes 2, 4, 6," in text


def only_curves(pvl, ids, rename: str = ""):
    """`pvl` with only the curves `ids`, renamed `rename` (when given)."""
    keep = [o for o in pvl.objects if o not in pvl.curves or o.curve_id in ids]
    return dataclasses.replace(pvl, objects=tuple(
        dataclasses.replace(o, info_block=dataclasses.replace(o.info, name=rename).to_bytes())
        if rename and o in pvl.curves else o for o in keep))


def test_per_node_datasets_report_and_plot_every_files_curves(tmp_path):
    """Node 1 gets the example, node 2 another file with one of its curves: the read-back and the plots of
    each file's curves are those of its own nodes."""
    b = only_curves(example(), {23}, rename="Only_B")
    datasets = Datasets.build(example(), "a.pvl", {2: (b, "b.pvl")})
    result, verification, report, _ = commission_all(datasets, nodes=[1, 2])
    assert all(ax.done for ax in result.axes) and verification.ok
    curves = [(c["dataset"], c["curve"], [n["node"] for n in c["nodes"]]) for c in report.figures["curves"]]
    assert curves == [("a.pvl", 23, [1]), ("a.pvl", 1, [1]), ("a.pvl", 2, [1]), ("b.pvl", 23, [2])]
    assert all(n["verdict"] == "read back = written" for c in report.figures["curves"] for n in c["nodes"])
    assert "[b.pvl] curve 23 'Only_B'" in report.text() and "[a.pvl] curve 23 'Example_Curve'" in report.text()
    # a failure is told in the words of the axis' own file
    failed = types.SimpleNamespace(fail_kind="curve", fail_item=23, fail_step=0, fail_phase="verify")
    assert "'Only_B'" in report.item_text(types.SimpleNamespace(node_id=2, **vars(failed)))
    assert "'Example_Curve'" in report.item_text(types.SimpleNamespace(node_id=1, **vars(failed)))
    files = report.write(tmp_path / "report")
    assert files["plots"] == ["curve_23.png", "curve_1.png", "curve_2.png", "curve_23_dataset2.png"]
    assert all((tmp_path / "report" / name).stat().st_size > 0 for name in files["plots"])


def test_same_content_is_laid_out_once():
    pvl = without_curves(example())
    d = Datasets.build(pvl, "a.pvl", {3: (pvl, "copy.pvl")})
    assert d.single and d.st_text() == to_st(pvl, source_name="a.pvl")


@pytest.mark.parametrize("extra, message", [
    (["--pvl", "3"], "NODE=FILE.pvl"),
    (["--pvl", "x=a.pvl"], "NODE=FILE.pvl"),
    (["--pvl", "200=a.pvl"], "node ID 1..127"),
    (["--axes", "2", "--pvl", "5=" + str(EXAMPLE)], "node 5 is not commissioned"),
    (["--axes", "2", "--pvl", "2=" + str(EXAMPLE), "--pvl", "2=" + str(EXAMPLE)], "node 2 given twice"),
])
def test_pvl_option_errors(extra, message, capsys):
    try:
        status = main(["commission", str(EXAMPLE), "-q", *extra])
    except SystemExit as e:
        status = e.code
    assert status == 2
    assert message in capsys.readouterr().err


def test_pvl_option_missing_file(tmp_path, capsys):
    assert main(["commission", str(EXAMPLE), "-q", "--axes", "2", "--pvl", f"2={tmp_path / 'none.pvl'}"]) == 1
    assert "none.pvl" in capsys.readouterr().err


def test_32_axes_at_500_kbits_with_real_timings_are_heard_after_their_reset_thanks_to_the_drain():
    """The example dataset on 32 drives at 500 kbit/s with the drives' real timings (flash, reset, boot): while
    the first axes verify, the bus is busy all the time and a boot-up message (700h + node, the lowest
    priority) loses every arbitration. plc_project's drain (DrainEvery, CAN0.SdoHold) lets the bus go idle now
    and then while an axis listens; without it the last axes fail with BootTimeout."""
    from linmot_st.jobs.commission.project import INSTANCE
    from linmot_st.jobs.commission.testing import project_build

    build = project_build("builtin")
    opts = RunOptions(axes=32, node_ids=NODES, bitrate=500_000, timings="real")
    drained = run(example(), opts, build, after=lambda plc, sim, drives: plc[f"{INSTANCE}.DRAINS"])
    assert all(a.done for a in drained.axes), [(a.node_id, a.error_id) for a in drained.axes if not a.done]
    assert drained.after > 0                                    # the drains it took

    def no_drain(plc):
        plc[f"{INSTANCE}.DRAINEVERY"] = 0

    plain = run(example(), opts, build, prepare_plc=no_drain)
    failed = [a for a in plain.axes if not a.done]
    assert failed and all(a.fail_phase == "reset" and a.error_id == 0x0305 for a in failed)   # BootTimeout
