"""Every command checks its arguments before doing any work, in one style: one line
`linmot-st CMD: error: ...` and exit status 2 (linmot_st.cliargs); output paths are probed, /proc and
/sys included, and no folder is created but the one named."""

from __future__ import annotations

import pytest

from linmot_st.cli import main
from linmot_st.jobs.commission.testing import EXAMPLE


def run_cli(capsys, *args: str) -> tuple[int, str]:
    try:
        rc = main(list(args))
    except SystemExit as exc:               # argparse's own checks end the same way
        rc = exc.code
    return rc, capsys.readouterr().err


@pytest.mark.parametrize("args, message", [
    (["build", str(EXAMPLE.parent.parent / "plc_project"), "--out", "/proc/linmot-out"],
     "linmot-st build: error: --out /proc/linmot-out: cannot write in /proc"),
    (["build", str(EXAMPLE.parent.parent / "plc_project"), "--out", "no/such/out"],
     "linmot-st build: error: --out no/such/out: folder no/such does not exist"),
    (["bench", "nosuch"], "linmot-st bench: error: no benchmark named nosuch"),
    (["run", "x.st", "--cycles", "-1"], "linmot-st run: error: argument --cycles: -1: must be >= 0"),
    (["run", "x.st", "--cycles", "1", "--watchdog", "-1"], "linmot-st run: error: argument --watchdog"),
    (["run", "x.st", "--cycles", "1", "--set", "X"], "linmot-st run: error: --set 'X': expected VAR=VALUE"),
    (["commission", str(EXAMPLE), "--timeout", "0"], "linmot-st commission: error: argument --timeout: 0:"),
    (["commission", str(EXAMPLE), "--timeout", "-5"], "linmot-st commission: error: argument --timeout: -5:"),
    (["commission", str(EXAMPLE), "--bitrate", "333333"], "linmot-st commission: error: argument --bitrate"),
    (["commission", str(EXAMPLE), "--axes", "-2"], "linmot-st commission: error: argument --axes: -2"),
    (["commission", str(EXAMPLE), "--curve-memory", "-1"], "linmot-st commission: error: argument --curve-memory"),
    (["commission", str(EXAMPLE), "--trace", "/sys/run.log"], "linmot-st commission: error: --trace /sys/run.log:"),
    (["emulate", "--interface", "virtual", "--channel", "x", "--bitrate", "100"], "linmot-st emulate: error: argument --bitrate"),
    (["export", "st", "/proc/lib.st"], "linmot-st export st: error: /proc/lib.st: cannot write in /proc"),
    (["pvl", "to-st", str(EXAMPLE), "-o", "/sys/x.st"], "linmot-st pvl to-st: error: -o /sys/x.st: cannot write in /sys"),
], ids=["build-out-proc", "build-out-parents", "bench", "cycles", "watchdog", "set", "timeout-0", "timeout-neg",
        "bitrate", "axes", "curve-memory", "trace-sys", "emulate-bitrate", "export-proc", "to-st-sys"])
def test_bad_arguments_one_line_exit_2_before_any_work(capsys, monkeypatch, args, message):
    from linmot_st import toolchain
    monkeypatch.setattr(toolchain, "build", lambda *a, **k: pytest.fail("built despite a bad argument"))
    rc, err = run_cli(capsys, *args)
    assert rc == 2
    assert err.startswith(message), err
    assert err.count("\n") == 1 and "Traceback" not in err
