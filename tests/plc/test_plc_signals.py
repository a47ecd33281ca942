"""The glue's signal handling: faults inside a scan become PlcFault; faults anywhere else still reach the
handler installed before (here Python's faulthandler), so real crashes are not swallowed. Each case runs
in a child process, since some of them end it."""

from __future__ import annotations

import signal
import subprocess
import sys
import threading

import pytest

from linmot_st.plc import Plc, PlcFault
from linmot_st.toolchain.testing import BACKEND_PARAMS, build_text, requires_matiec

PROGRAM = """
PROGRAM Main
  VAR
    Den : INT := 1;
    Q : INT;
    N : INT;
  END_VAR
  N := N + 1;
  Q := 100 / Den;
END_PROGRAM

CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK T1(INTERVAL := T#1ms, PRIORITY := 0);
    PROGRAM Inst0 WITH T1 : Main;
  END_RESOURCE
END_CONFIGURATION
"""


@pytest.fixture(scope="module", params=BACKEND_PARAMS)
def built(request, tmp_path_factory):
    return build_text(PROGRAM, tmp_path_factory.mktemp(f"signals-{request.param}"), request.param)


def run_child(code: str, built) -> subprocess.CompletedProcess:
    prelude = ("import ctypes, faulthandler, sys\n"
               "faulthandler.enable()\n"
               "from linmot_st.plc import Plc, PlcFault\n"
               f"LIB, MANIFEST = {str(built.library)!r}, {str(built.manifest)!r}\n")
    return subprocess.run([sys.executable, "-c", prelude + code], capture_output=True, text=True, timeout=60)


def test_segfault_outside_a_scan_reaches_the_previous_handler(built):
    proc = run_child("p = Plc((LIB, MANIFEST)); p.step(3)\n"
                     "print('stepped', flush=True)\n"
                     "ctypes.string_at(0)\n", built)
    assert "stepped" in proc.stdout
    assert proc.returncode == -signal.SIGSEGV
    assert "Fatal Python error: Segmentation fault" in proc.stderr   # faulthandler got it


def test_faults_in_each_of_several_instances_are_caught(built):
    proc = run_child("ps = [Plc((LIB, MANIFEST)) for _ in range(3)]\n"
                     "for i in (0, 2, 1):\n"
                     "    ps[i]['INST0.DEN'] = 0\n"
                     "    try:\n"
                     "        ps[i].step(5)\n"
                     "    except PlcFault as f:\n"
                     "        print(i, f.kind, f.pou, ps[i].scan_count, flush=True)\n"
                     "ps[0].reset(); ps[0].step(2); print('after', ps[0]['INST0.N'])\n", built)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout.split("\n")[:4] == ["0 1 MAIN 0", "2 1 MAIN 0", "1 1 MAIN 0", "after 2"]


@requires_matiec
def test_sigfpe_outside_a_scan_reaches_the_previous_handler(tmp_path):
    """A division by zero in PLC code called outside plc_step (here config_run__ directly) is not a PLC
    fault of a scan: it must reach faulthandler, not be swallowed."""
    built = build_text(PROGRAM, tmp_path, "matiec")
    proc = run_child("p = Plc((LIB, MANIFEST)); p['INST0.DEN'] = 0\n"
                     "p._lib.config_run__(0)\n", built)
    assert proc.returncode == -signal.SIGFPE
    assert "Fatal Python error: Floating point exception" in proc.stderr


def test_step_on_another_thread(built):
    plc = Plc(built)
    caught = []

    def worker():
        plc.step(2)
        plc["INST0.DEN"] = 0
        try:
            plc.step(1)
        except PlcFault as fault:
            caught.append(fault)

    t = threading.Thread(target=worker)
    t.start()
    t.join(30)
    assert len(caught) == 1 and caught[0].pou == "MAIN" and caught[0].kind == 1
    assert plc.scan_count == 2
