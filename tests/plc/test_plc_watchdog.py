"""The scan watchdog (docs/toolchain.md): a scan that never ends is a PlcFault naming its POU, on both
backends, and the process and the PLC live on; `linmot-st run` reports it, and Ctrl-C stops a long run
promptly with the watched values so far."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from linmot_st.plc import Plc, PlcFault
from linmot_st.toolchain.testing import BACKEND_PARAMS, build_text, write_st

SPIN = """
PROGRAM Spin
  VAR
    N : DINT;
    Go : BOOL;
  END_VAR
  N := N + 1;
  IF Go THEN
    WHILE TRUE DO
      N := N + 1;
    END_WHILE;
  END_IF;
END_PROGRAM

CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK Main(INTERVAL := T#1ms, PRIORITY := 0);
    PROGRAM Inst0 WITH Main : Spin;
  END_RESOURCE
END_CONFIGURATION
"""


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_a_scan_that_never_ends_is_a_fault_naming_the_pou(backend, tmp_path):
    plc = Plc(build_text(SPIN, tmp_path, backend))
    assert plc.watchdog_ns == 1_000_000_000                   # on by default: 1 s of CPU per scan
    plc.watchdog_ns = 100_000_000
    plc.step(10)
    plc["INST0.GO"] = True
    t0 = time.perf_counter()
    with pytest.raises(PlcFault) as fault:
        plc.step(1000)
    assert time.perf_counter() - t0 < 5                       # 100 ms of CPU, whatever else the machine does
    f = fault.value
    assert f.kind == 5 and f.pou == "SPIN" and f.scan == 11
    assert f.file.endswith("prog.st") and "scan watchdog" in str(f)
    assert plc.scan_count == 10                               # the scans before it ran
    plc.reset()                                               # the PLC starts again; the process lives
    plc.step(3)
    assert plc.scan_count == 3 and plc["INST0.N"] == 3


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_normal_scans_never_trip_it_and_zero_turns_it_off(backend, tmp_path):
    plc = Plc(build_text(SPIN, tmp_path, backend))
    plc.watchdog_ns = 4_000_000                               # 4 ms of CPU per scan: far above a scan's cost
    plc.step(200_000)
    assert plc["INST0.N"] == 200_000
    plc.watchdog_ns = 0
    assert plc.watchdog_ns == 0
    with pytest.raises(ValueError):
        plc.watchdog_ns = -1


def _sigint_default() -> None:
    # a test run started in the background (`pytest &` in a script) has SIGINT ignored, and children inherit
    # that: Python then installs no KeyboardInterrupt handler, and the Ctrl-C under test would never arrive
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _cli(*args: str, **kw) -> subprocess.Popen:
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    return subprocess.Popen([sys.executable, "-m", "linmot_st.cli", *args], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, env=env, preexec_fn=_sigint_default, **kw)


def _interrupt(proc: subprocess.Popen, ready: str) -> tuple[str, str, float]:
    """Wait for a stdout line starting with `ready`, send SIGINT; (stdout, stderr, seconds to exit)."""
    try:
        first = proc.stdout.readline()
        assert first.startswith(ready), first + proc.stderr.read()
        t0 = time.monotonic()
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=20)
        return first + out, err, time.monotonic() - t0
    finally:
        if proc.poll() is None:
            proc.kill()


def test_run_reports_the_watchdog_and_exits(tmp_path):
    src = write_st(SPIN, tmp_path)
    proc = _cli("run", str(src), "--backend", "builtin", "--cycles", "100", "--set", "INST0.GO=True",
                "--watch", "INST0.N", "--watchdog", "0.2")
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 3, err
    assert "linmot-st run: error: PLC fault: scan watchdog" in err and "in POU SPIN" in err
    assert "INST0.N" in out


def test_ctrl_c_stops_a_long_run_promptly_with_what_was_done(tmp_path):
    src = write_st(SPIN, tmp_path)
    subprocess.run([sys.executable, "-m", "linmot_st.cli", "build", str(src), "--backend", "builtin"],
                   check=True, capture_output=True)                # the build cached before the clock starts
    proc = _cli("run", str(src), "--backend", "builtin", "--cycles", str(10**12), "--watch", "INST0.N",
                "--watch", "INST0.GO", "--every", "100000")
    out, err, stopped_s = _interrupt(proc, "scan 100000")     # the first --every report: the run is on
    assert proc.returncode == 130, err
    assert stopped_s < 2.0                                     # chunks of ~50 ms between two checks
    assert "linmot-st run: error: interrupted after" in err
    assert "INST0.N = " in out and "INST0.GO = False" in out   # both --watch options are watched


def test_ctrl_c_stops_the_emulator_with_what_it_served():
    import uuid
    proc = _cli("emulate", "--interface", "virtual", "--channel", f"wd-{uuid.uuid4().hex[:8]}", "--fast")
    out, err, stopped_s = _interrupt(proc, "E1100 node 1 on virtual:")
    assert proc.returncode == 0, err
    assert stopped_s < 3.0
    assert "stopped in NMT state" in out and "frames received" in out


def test_ctrl_c_stops_a_commissioning_with_the_report_of_what_was_done(tmp_path):
    """On python-can's virtual bus in real time (realistic drive timings: the flash phase takes seconds),
    Ctrl-C once the parameters are written: the drives' threads stop, the report of the phases done so far
    is printed and written, exit status 130."""
    from linmot_st.jobs.commission.testing import EXAMPLE
    report = tmp_path / "report"
    proc = _cli("commission", str(EXAMPLE), "--bus", "virtual", "--drive-timings", "real", "--report", str(report))
    try:
        for line in proc.stderr:                               # progress lines, one per finished phase
            if "parameters          done" in line:
                break
        else:
            raise AssertionError("the run never finished its parameters: " + proc.stdout.read())
        t0 = time.monotonic()
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=30)
        stopped_s = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 130, (out, err)
    assert stopped_s < 10.0, (out, err)                       # the drives' threads joined, report written
    assert "INTERRUPTED (Ctrl-C)" in out and "result: INTERRUPTED" in out
    assert "parameters" in out                                 # the phases done are in the report
    assert (report / "report.md").exists() and "INTERRUPTED" in (report / "report.md").read_text()
