"""The PLC task's interval as the user's choice (`linmot-st commission --task-interval`, testing.commission's
task_interval): built into the program's CONFIGURATION, checked with clear errors, and what it changes (the
scan bound of few drives at 1 Mbit/s: docs/commissioning.md, "Task interval")."""

from __future__ import annotations

import json

import pytest

from linmot_st import resources
from linmot_st.cli import main
from linmot_st.jobs.commission.project import TASK_INTERVAL_NS, configuration_text, parse_task_interval, prepare
from linmot_st.jobs.commission.testing import EXAMPLE, commission, example


@pytest.mark.parametrize("text, ns", [("250us", 250_000), ("1ms", 1_000_000), ("0.5ms", 500_000),
                                      ("T#250us", 250_000), ("0.0005s", 500_000), ("10ms", 10_000_000),
                                      ("50US", 50_000)])
def test_task_interval_texts(text, ns):
    assert parse_task_interval(text) == ns


@pytest.mark.parametrize("text, message", [("250", "not a task interval"), ("fast", "not a task interval"),
                                           ("1.5us", "whole number of microseconds"),
                                           ("20us", "50 us..10 ms"), ("11ms", "50 us..10 ms")])
def test_task_interval_errors(text, message):
    with pytest.raises(ValueError, match=message):
        parse_task_interval(text)


def test_cli_refuses_a_bad_interval_before_building(capsys):
    with pytest.raises(SystemExit) as e:
        main(["commission", str(EXAMPLE), "-q", "--task-interval", "5us"])
    assert e.value.code == 2 and "50 us..10 ms" in capsys.readouterr().err


def test_the_interval_is_the_configurations():
    config = (resources.library_tree() / "plc_project" / "config.st").read_text()
    assert "INTERVAL := T#1ms" in config and TASK_INTERVAL_NS == 1_000_000
    assert "INTERVAL := T#0.25ms" in configuration_text(config, 250_000)
    assert "INTERVAL := T#2ms" in configuration_text(config, 2_000_000)
    with pytest.raises(ValueError, match="expected one"):
        configuration_text(config.replace("TASK Cyclic", "TASK Other"), 250_000)
    # the default is plc_project itself; another interval a generated entry with its own configuration
    assert prepare(example(), EXAMPLE.name).committed
    p = prepare(example(), EXAMPLE.name, task_interval_ns=250_000)
    assert not p.committed and p.task_interval_ns == 250_000
    assert "T#0.25ms" in (p.root / "config.st").read_text() and '"config.st"' in p.entry.read_text()


def test_a_shorter_task_lifts_the_scan_bound_of_two_drives_at_1_mbit():
    """1 ms: each drive gets one exchange per scan, about 240 us of bus at 1 Mbit/s, so two drives leave the
    bus half idle; 250 us: the bus is the limit."""
    slow = commission(axes=2, bitrate=1_000_000)
    fast = commission(axes=2, bitrate=1_000_000, task_interval="250us")
    assert slow.result.tick_ns == 1_000_000 and fast.result.tick_ns == 250_000
    assert slow.verification.ok and fast.verification.ok
    s, f = slow.report.figures, fast.report.figures
    assert s["options"]["task_ms"] == 1.0 and f["options"]["task_ms"] == 0.25
    assert s["transfer"]["ratio_stuffed"] > 1.8 and f["transfer"]["ratio_stuffed"] < 1.1


def test_cli_run_with_an_interval(tmp_path, capsys):
    out = tmp_path / "report"
    assert main(["commission", str(EXAMPLE), "-q", "--drive-timings", "fast", "--no-reset",
                 "--task-interval", "500us", "--report", str(out)]) == 0
    figures = json.loads((out / "report.json").read_text())
    assert figures["options"]["task_ms"] == 0.5
    assert "--task-interval 500us" in capsys.readouterr().out
