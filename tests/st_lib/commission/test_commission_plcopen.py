"""PLCopen conformance of FB_LmCommission, with the checks of the st_lib suite (tests/st_lib/plcopen_checks.py:
run_recording, outputs, assert_exclusive, requests) on plc_project's first axis: Execute is the
program's Start (WaitBoot off), Abort its Abort, the options its LiveRam / Flash / Reset / Verify."""

from __future__ import annotations

import pytest

from linmot_st.jobs.commission.project import INSTANCE, MAILBOX
from linmot_st.jobs.commission.testing import project_build
from plcopen_checks import (
    assert_exclusive,
    check_rising_edge_after_the_pulse,
    check_toggled_execute,
    outputs,
    requests,
    run_recording,
)

MS = 1_000_000
INPUTS = {"EXECUTE": "START", "ABORT": "ABORT", "LIVERAM": "LIVERAM", "FLASH": "FLASH", "RESET": "RESET",
          "VERIFY": "VERIFY", "FORCE": "A1.FORCE"}
RUN = dict(FLASH=False, VERIFY=False, RESET=False, LIVERAM=False)   # a short run: check, write (670 exchanges)
ALT = dict(VERIFY=True, LIVERAM=True, FLASH=True, FORCE=True)       # changed while Busy: must change nothing
BAD = dict(RESET=True, FLASH=False)                                 # a reset would lose the curves: ResetNeedsFlash


class ComFb:
    """FB_LmCommission of axis 1, addressed like the st_lib suite's Fb."""

    name = "COM"

    def __init__(self, bench: ComBench) -> None:
        self.bench = bench

    def _path(self, member: str) -> str:
        m = member.upper()
        return f"{INSTANCE}.{INPUTS[m]}" if m in INPUTS else f"{INSTANCE}.A1.COM.{m}"

    def __getitem__(self, member: str):
        return self.bench.plc[self._path(member)]

    def __setitem__(self, member: str, value) -> None:
        self.bench.plc[self._path(member)] = value

    def set(self, **inputs) -> None:
        for k, v in inputs.items():
            self[k] = v

    def start(self, **inputs) -> None:
        self.set(**inputs)
        self["EXECUTE"] = True

    def _aborted(self) -> bool:
        return bool(self["COMMANDABORTED"])


class ComBench:
    """plc_project, one axis, one emulated drive (booted), as the st_lib suite's Bench."""

    def __init__(self) -> None:
        from linmot_st.bus import SimBus
        from linmot_st.cosim import CoSim
        from linmot_st.emulator import DriveTimings, E1100Drive
        from linmot_st.plc import Plc

        self.plc = Plc(project_build())
        self.bus = SimBus(500_000)
        self.drive = E1100Drive(1, timings=DriveTimings.fast())
        self.bus.attach(self.drive, "drive1")
        self.drive.power_on(0)
        self.sim = CoSim(self.plc, self.bus, mailbox=MAILBOX)
        self.plc[f"{INSTANCE}.AXES"] = 1
        self.plc[f"{INSTANCE}.WAITBOOT"] = False
        self.fb("COM").set(**RUN)
        self.sim.run_until(lambda: self.plc[f"{INSTANCE}.A1.UP"], max_scans=1000)
        self.step(2)

    def fb(self, name: str) -> ComFb:
        return ComFb(self)

    def step(self, n: int = 1) -> None:
        self.sim.step(n)

    def __setitem__(self, path: str, value) -> None:
        assert path == "CH1.SDOTIMEOUT"
        self.plc[f"{INSTANCE}.A1.CH.SDOTIMEOUT"] = value

    def sdo_trace(self, node: int = 1, since_ns: int = 0) -> list:
        ids = (0x600 + node, 0x580 + node)
        return [e for e in self.bus.trace if e.frame.can_id in ids and e.start_ns >= since_ns and e.status != "error"]


def reference_requests() -> list[bytes]:
    b = ComBench()
    t0 = b.plc.time_ns
    run_recording(b, b.fb("COM"), execute_scans=None)
    return requests(b, t0)


def test_done_held_while_execute_then_reset_on_falling_edge():
    b = ComBench()
    fb = b.fb("COM")
    fb["FORCE"] = True                   # the full write: its exchanges are known from the dataset
    states = run_recording(b, fb, execute_scans=None)
    first = next(i for i, s in enumerate(states) if s[0])
    assert all(s[1] for s in states[:first]), "Busy from the Execute scan until Done"
    assert all(s[0] and not s[1] for s in states[first:]), "Done held while Execute stays TRUE"
    assert fb["PHASE"] == "LM_COM_DONE" and fb["EXCHANGES"] == 6 + 4 * 30 + 30 + 532 + 100   # + the pre-flight
    fb["EXECUTE"] = False
    b.step(1)
    assert outputs(fb) == (False, False, False, False, 0)
    # a new rising edge commissions again, from the start
    states = run_recording(b, fb, execute_scans=None)
    assert states[-1][0] and fb["EXCHANGES"] == 788


def test_done_is_a_one_scan_pulse_when_execute_fell_before():
    b = ComBench()
    fb = b.fb("COM")
    states = run_recording(b, fb, execute_scans=1)
    assert [s[0] for s in states].count(True) == 1
    first = next(i for i, s in enumerate(states) if s[0])
    assert all(s[1] for s in states[:first])
    assert states[first + 1:] == [(False, False, False, False, 0)] * (len(states) - first - 1)


def test_retrigger_while_busy_is_ignored():
    reference = reference_requests()
    b = ComBench()
    b.bus.delay(lambda f: f.can_id == 0x581, 3 * MS)               # every answer 3 ms late: Busy for longer
    fb = b.fb("COM")
    t0 = b.plc.time_ns
    states = run_recording(b, fb, execute_scans=None, retrigger_at=3, max_scans=5000)
    assert [s[0] for s in states].count(True) == len(states) - next(i for i, s in enumerate(states) if s[0])
    assert not any(s[2] for s in states)
    b.step(20)
    assert requests(b, t0) == reference                             # one run, the same frames


def test_inputs_are_latched_at_the_rising_edge():
    reference = reference_requests()
    b = ComBench()
    b.bus.delay(lambda f: f.can_id == 0x581, 3 * MS)
    fb = b.fb("COM")
    t0 = b.plc.time_ns
    states = run_recording(b, fb, execute_scans=None, alt_at=ALT, max_scans=5000)
    assert any(s[0] for s in states) and not any(s[2] for s in states)
    assert requests(b, t0) == reference


def test_invalid_input_error_held_then_reset():
    b = ComBench()
    fb = b.fb("COM")
    fb.set(**BAD)
    t0 = b.plc.time_ns
    states = run_recording(b, fb, execute_scans=None)
    assert states[0][2] and states[0][4] == 0x0602                 # ResetNeedsFlash in the Execute scan itself
    assert all(s[2] for s in states)
    assert requests(b, t0) == []
    fb["EXECUTE"] = False
    b.step(1)
    assert outputs(fb) == (False, False, False, False, 0)


def test_error_is_a_one_scan_pulse_when_execute_fell_before():
    b = ComBench()
    b["CH1.SDOTIMEOUT"] = 20 * MS
    b.bus.drop(lambda f: f.can_id == 0x581)                        # the drive's answers never arrive
    fb = b.fb("COM")
    states = run_recording(b, fb, execute_scans=1)
    assert [s[2] for s in states].count(True) == 1
    first = next(i for i, s in enumerate(states) if s[2])
    assert all(s[1] for s in states[:first])
    assert states[first + 1:] == [(False, False, False, False, 0)] * (len(states) - first - 1)
    assert (fb["FAILPHASE"], fb["FAILITEM"]) == ("LM_COM_CHECK", 1)   # diagnostics stay until the next start


def test_execute_rising_in_the_scan_after_the_pulse_starts_a_new_run():
    b = ComBench()
    check_rising_edge_after_the_pulse(b, b.fb("COM"), first_request_scans=3)   # START: 2 scans, no frame


def test_execute_toggled_every_scan_gives_one_run_per_edge_after_completion():
    b = ComBench()
    check_toggled_execute(b, b.fb("COM"), runs=2, first_request_scans=3)


@pytest.mark.parametrize("at_scan", [2, 40, 300])
def test_abort(at_scan):
    b = ComBench()
    b.bus.delay(lambda f: f.can_id == 0x581, 3 * MS)
    fb = b.fb("COM")
    fb.start()
    b.step(at_scan)
    assert fb["BUSY"]
    fb["ABORT"] = True
    b.step(1)
    s = outputs(fb)
    assert_exclusive(s)
    assert s[3] and not s[1]
    b.step(3)
    assert fb["COMMANDABORTED"]
    fb.set(EXECUTE=False, ABORT=False)
    b.step(1)
    assert outputs(fb) == (False, False, False, False, 0)
    states = run_recording(b, fb, execute_scans=None, max_scans=5000)   # the channel is free again
    assert states[-1][0]


@pytest.mark.parametrize("lost", [0x35, 0x40, 0x42], ids=["stop", "save", "poll"])
def test_flash_phase_lost_answer_starts_mc_again(lost):
    """As FB_LmFlashSave: a missing answer in the FLASH phase (SdoTimeout) once the MC may be stopped still
    sends 36h before the failure is reported, and the drive's MC runs again."""
    b = ComBench()
    b["CH1.SDOTIMEOUT"] = 30 * MS
    b.bus.drop(lambda f: f.can_id == 0x581 and f.data[1:4] == bytes([0x00, 0x20, lost]), count=1)
    fb = b.fb("COM")
    fb.set(FLASH=True)
    t0 = b.plc.time_ns
    states = run_recording(b, fb, execute_scans=None, max_scans=20_000)
    assert states[-1][2] and fb["ERRORID"] == 0x0301                  # SdoTimeout
    assert (fb["FAILPHASE"], fb["FAILITEM"]) == ("LM_COM_FLASH", lost)
    subs = [e.frame.data[3] for e in b.sdo_trace(since_ns=t0)
            if e.frame.can_id == 0x601 and e.frame.data[1:3] == b"\x00\x20" and e.frame.data[3] in (0x35, 0x36, 0x40, 0x42)]
    assert subs[0] == 0x35 and subs[-2:] == [lost, 0x36] and subs.count(0x36) == 1
    assert b.drive.mc_phase == "running"
