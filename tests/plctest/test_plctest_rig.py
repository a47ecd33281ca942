"""The rig helpers of the pytest plugin on the example station (examples/user_project): conditions, failure
messages that show the condition, the PLC time, the watched variables and the last CAN frames, FBs that
end in Error, faults installed at a phase, forced variables, the python-can variant; and the example
project run by pytest exactly as a user runs it."""

from __future__ import annotations

import os
import subprocess
import sys
import xml.etree.ElementTree as ET

import pytest

from linmot_st import resources
from linmot_st.emulator import DriveTimings, E1100Drive, load_profile
from linmot_st.plctest import FbFailed, RealTimeRig, Rig, RigTimeout
from linmot_st.plctest.rig import ConditionError, condition

EXAMPLE = resources.CHECKOUT / "examples" / "user_project"
ST = "MAIN.STATION"


def test_conditions_in_iec_text(station):
    rig = Rig(station, timings="fast")
    assert condition(rig.plc, f"{ST}.STATE = ST_BOOT").test()
    assert not condition(rig.plc, f"NOT ({ST}.STATE = ST_BOOT)").test()
    with pytest.raises(ConditionError, match=r"column 1: NOT takes a BOOL, not ENUM"):
        condition(rig.plc, f"NOT {ST}.STATE = ST_BOOT")         # IEC: NOT binds before =
    assert condition(rig.plc, f"{ST}.STATE = ST_BOOT AND NOT {ST}.READY OR {ST}.ERROR").test()
    assert condition(rig.plc, f"{ST}.DATAINDEX * 2 - 1 = {ST}.DATAINDEX").test()   # two variables, arithmetic
    assert condition(rig.plc, f"{ST}.DATAINDEX >= 1").test() and not condition(rig.plc, f"{ST}.DATAINDEX > 1").test()
    assert condition(rig.plc, f"{ST}.DATAINDEX <> 16#02").test() and not condition(rig.plc, f"{ST}.READY").test()
    with pytest.raises(Exception, match="NOSUCH"):
        condition(rig.plc, f"{ST}.NOSUCH")                      # an unknown path fails before any scan
    assert rig.plc.scan_count == 0
    with pytest.raises(ConditionError, match=r"column 42: the condition ends too early \(expected \)"):
        rig.step_until(f"{ST}.READY OR (MAIN.STATION.ERROR", ms=100)   # a syntax error: before any scan
    assert rig.plc.scan_count == 0
    k = rig.step_until(f"{ST}.STATE = ST_COMMISSION OR {ST}.ERROR", ms=100)
    assert 20 <= k <= 23 and rig.plc.scan_count == k          # fast timings: the boot-up message after 20 ms


def test_the_rig_builds_its_drives_of_the_model_given(station):
    from linmot_st.emulator.linmot.model import E1100, BootTime, DriveModel

    quick = DriveModel("QUICK", E1100.profile, E1100.services, (BootTime(7_000_000),))
    rig = Rig(station, timings="fast", model=quick)
    assert rig.drive.model is quick
    k = rig.step_until(f"{ST}.STATE = ST_COMMISSION", ms=100)
    assert 7 <= k <= 10                                       # its boot-up message after 7 ms, not 20


def test_a_condition_not_reached_says_what_where_and_when(station):
    rig = Rig(station, nodes=(1,))
    rig.watch(f"{ST}.ERRORID")
    with pytest.raises(RigTimeout) as info:
        rig.step_until(lambda: rig[f"{ST}.READY"], ms=50, watch=[f"{ST}.STATE"])
    text = str(info.value)
    lines = text.splitlines()
    assert lines[0] == 'not reached within 50 ms (50 scans): rig[f"{ST}.READY"]'     # the lambda as written
    assert lines[1] == "PLC time 0.050000 s, scan 50 (builtin backend)"
    assert f"  {ST}.STATE = 'ST_BOOT'" in lines and f"  {ST}.ERRORID = 0" in lines
    assert "last 1 of 1 CAN frames:" in text and "plc      000#0101" in text   # NMT start; the drive boots in 4 s


def test_an_fb_that_ends_in_error_fails_with_its_error_id(station):
    """A drive with another MC tree: commissioning stops in the compatibility check (nothing written)."""
    profile = load_profile().with_tree(2, tree_id=4613)
    rig = Rig(station, drive_factory=lambda n: E1100Drive(n, profile, timings=DriveTimings.fast()))
    with pytest.raises(FbFailed) as info:
        rig.expect_done(f"{ST}.COM", ms=5000)
    text = str(info.value)
    assert text.startswith(f"{ST}.COM ended with Error, ErrorID 16#0501 (TreeIdMismatch) after ")
    assert f"  {ST}.COM.ERROR = True" in text and "drive1   581#" in text


def test_a_fault_at_a_phase_is_installed_when_the_phase_begins(station):
    rig = Rig(station, timings="fast")
    lost = rig.inject_fault("power_off", node=1, when=f"{ST}.COM.PHASE = LM_COM_CT")
    rig.step_until(f"{ST}.ERROR", ms=60_000)
    assert rig[f"{ST}.FAILPHASE"] == "LM_COM_CT" and lost.installed_ns is not None
    curves_end = max(e.end_ns for e in rig.trace if e.sender == "drive1")
    assert curves_end <= lost.installed_ns                  # the drive said nothing after it was switched off
    with pytest.raises(ValueError, match="node="):
        rig.inject_fault("reset")


def test_forcing_a_variable_by_its_path(station):
    rig = Rig(station, timings="fast")
    rig.force(f"{ST}.STATE", "ST_ERROR")
    rig.step(100)
    assert rig[f"{ST}.ERROR"] and rig[f"{ST}.STATE"] == "ST_ERROR"
    rig.unforce(f"{ST}.STATE")
    rig[f"{ST}.STATE"] = "ST_BOOT"
    rig.step_until(f"{ST}.STATE = ST_COMMISSION", scans=100)


def test_the_python_can_variant(station):
    with RealTimeRig(station, nodes=(1,)) as rig:
        rig.step_until(f"{ST}.STATE = ST_COMMISSION", scans=2000)
        assert any(r.sender == "node1" for r in rig.trace)  # the drive's boot-up message, as the PLC got it
        with pytest.raises(NotImplementedError):
            rig.inject_fault("drop")


def test_the_example_project_passes_as_a_user_runs_it(tmp_path):
    """`pytest` in examples/user_project: the plugin comes from the installed package's entry point, the
    settings from the project's pyproject.toml; tests in Python and in ST."""
    env = {k: v for k, v in os.environ.items() if k != "PYTEST_ADDOPTS"}
    proc = subprocess.run([sys.executable, "-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider",
                           f"--junitxml={tmp_path / 'report.xml'}"], cwd=EXAMPLE, env=env, capture_output=True,
                          text=True, timeout=900)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    cases = {c.get("name"): c for c in ET.parse(tmp_path / "report.xml").getroot().iter("testcase")}
    assert {"Test_StationCommissionsThenRunsItsJob", "Test_StationWaitsForTheDrive",
            "test_the_station_commissions_its_axis_and_reads_its_limits[builtin]",
            "test_the_station_moves_then_runs_its_curve[builtin]"} <= set(cases)
    failed = [n for n, c in cases.items() if c.find("failure") is not None or c.find("error") is not None]
    assert failed == []
    assert "no SocketCAN interface vcan0" in proc.stdout or os.path.exists("/sys/class/net/vcan0")
