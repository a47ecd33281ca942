"""PLCopen conformance of every service FB (spec/conventions.md), data-driven over a table of FBs:
edge latching, exclusive outputs, Done/Error held while Execute stays TRUE, one-scan Done/Error pulse when
Execute fell before the end, re-trigger while Busy ignored, outputs reset on the falling edge, Abort."""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field

import pytest

from linmot_st.emulator import build_entry
from plcopen_checks import (
    assert_exclusive,
    check_done_held,
    check_one_scan_pulse,
    check_reset_on_falling_edge,
    check_rising_edge_after_the_pulse,
    check_toggled_execute,
    outputs,
    requests,
    run_recording,
)
from stbench import VECTORS, Bench

MS = 1_000_000
SEED = json.loads((VECTORS / "curve_info.json").read_text())["curves"][0]
SEED_INFO = list(bytes.fromhex(SEED["info_block"]))
ENTRY = list(build_entry(0x0103, bytes(32), name="conf"))


def seed_setpoints(b: Bench) -> None:
    b.set_setpoints(SEED["setpoints"])


def seed_curve_on_drive(b: Bench) -> None:
    seed_setpoints(b)
    assert b.fb("CA").run(CURVEID=23, INFO=SEED_INFO, DATASIZE=40).done


def ct_entry_on_drive(b: Bench) -> None:
    assert b.fb("CTWR").run(ENTRY=5, BLOCK=ENTRY).done


@dataclass
class Spec:
    name: str
    inputs: dict
    alt: dict | None = None                  # other inputs, set while Busy: must change nothing
    bad: dict | None = None                  # invalid inputs: Error before any frame
    setup: Callable[[Bench], None] | None = None
    abort: bool = False                      # has Abort / CommandAborted
    fail: dict = field(default_factory=dict)  # extra inputs for the timeout error run
    polls: bool = False                      # polls a busy drive: the number of polls depends on timing


SPECS = [
    Spec("RD", dict(UPID=0x1005, MEM="LM_RAM"), dict(UPID=0x1018, MEM="LM_ROM"), dict(UPID=0x4000)),
    Spec("WR", dict(UPID=0x1005, VALUE=1500, MEM="LM_RAM"), dict(VALUE=1600), dict(MEM="LM_MIN")),
    Spec("SRD", dict(UPID=0x03E8, COUNT=8, MEM="LM_RAM"), dict(COUNT=2), dict(COUNT=0)),
    Spec("SWR", dict(UPID=0x03F2, COUNT=8, TEXT="conformance", MEM="LM_RAM_ROM"), dict(TEXT="other"), dict(COUNT=40)),
    Spec("DEF", dict(LAYER=3), dict(LAYER=1), dict(LAYER=9), fail=dict(TIMEOUT=20 * MS)),
    Spec("UL", dict(MODIFIED=False, STARTUPID=0x2000, ENDUPID=0x2EFF), dict(ENDUPID=0x2010),
         dict(STARTUPID=0x3000, ENDUPID=0x2000), abort=True),
    Spec("CA", dict(CURVEID=23, INFO=SEED_INFO, DATASIZE=40), dict(CURVEID=24), dict(CURVEID=0),
         setup=seed_setpoints, abort=True),
    Spec("CAF", dict(CURVEID=5, NAME="conf", OBJECTTYPE=3, XLENGTH=1000, NUMSETPOINTS=10), dict(NAME="other"),
         dict(NUMSETPOINTS=1), setup=seed_setpoints, abort=True),
    Spec("CG", dict(CURVEID=23), dict(CURVEID=24), dict(CURVEID=0), setup=seed_curve_on_drive, abort=True),
    Spec("CDA", {}),
    Spec("FS", dict(CURVES=True, COMMANDTABLE=False, POLLINTERVAL=0), dict(COMMANDTABLE=True),
         dict(CURVES=False, COMMANDTABLE=False), fail=dict(MCTIMEOUT=20 * MS), polls=True),
    Spec("CTWR", dict(ENTRY=5, BLOCK=ENTRY), dict(ENTRY=6), dict(ENTRY=256), abort=True),
    Spec("CTWRF", dict(ENTRY=5, HEADER=0x0103, NAME="conf"), dict(NAME="other"), dict(NAME="x" * 17), abort=True),
    Spec("CTRD", dict(ENTRY=5), dict(ENTRY=6), dict(ENTRY=256), setup=ct_entry_on_drive, abort=True),
    Spec("CTDEL", dict(ENTRY=5), dict(ENTRY=6), dict(ENTRY=256), setup=ct_entry_on_drive),
    Spec("CTDELALL", {}),
    Spec("CTPRES", {}),
    Spec("LC", dict(LAYER=2, CHECK=True, SOURCE={"TREEID": 4612, "MAINVERSION": 3, "SUBVERSION": 0}),
         dict(LAYER=1), dict(LAYER=0)),
    Spec("MST", {}, fail=dict(TIMEOUT=20 * MS)),
    Spec("MSA", {}, fail=dict(TIMEOUT=20 * MS)),
    Spec("RST", {}, fail=dict(BOOTTIMEOUT=40 * MS)),
    Spec("SDO", dict(INDEX=0x1018, SUBINDEX=1, WRITE=False), dict(SUBINDEX=2), dict(INDEX=0)),
    Spec("CMD", dict(SUBINDEX=0x41, E1100ONLY=True), dict(SUBINDEX=0x81), dict(WRAPPERERROR=0x0101)),
]
IDS = [s.name for s in SPECS]


def bench(spec: Spec) -> Bench:
    b = Bench(nodes=1)
    if spec.setup:
        spec.setup(b)
    return b


@pytest.mark.parametrize("spec", SPECS, ids=IDS)
def test_done_held_while_execute_then_reset_on_falling_edge(spec):
    b = bench(spec)
    fb = b.fb(spec.name)
    fb.set(**spec.inputs)
    check_done_held(b, fb)
    check_reset_on_falling_edge(b, fb)


@pytest.mark.parametrize("spec", SPECS, ids=IDS)
def test_done_is_a_one_scan_pulse_when_execute_fell_before(spec):
    b = bench(spec)
    fb = b.fb(spec.name)
    fb.set(**spec.inputs)
    check_one_scan_pulse(b, fb, 0)


@pytest.mark.parametrize("spec", SPECS, ids=IDS)
def test_retrigger_while_busy_is_ignored(spec):
    ref = bench(spec)
    t0 = ref.plc.time_ns
    assert ref.fb(spec.name).run(**spec.inputs).done
    reference = requests(ref, t0, spec.polls)

    b = bench(spec)
    b.bus.delay(lambda f: f.can_id == 0x581, 3 * MS)            # keep every FB busy for several scans
    fb = b.fb(spec.name)
    fb.set(**spec.inputs)
    t0 = b.plc.time_ns
    states = run_recording(b, fb, execute_scans=None, retrigger_at=3)
    assert [s[0] for s in states].count(True) == len(states) - next(i for i, s in enumerate(states) if s[0])
    assert not any(s[2] for s in states)
    b.step(20)
    assert requests(b, t0, spec.polls) == reference                        # one run, the same frames


@pytest.mark.parametrize("spec", [s for s in SPECS if s.alt], ids=[s.name for s in SPECS if s.alt])
def test_inputs_are_latched_at_the_rising_edge(spec):
    ref = bench(spec)
    t0 = ref.plc.time_ns
    assert ref.fb(spec.name).run(**spec.inputs).done
    reference = requests(ref, t0, spec.polls)

    b = bench(spec)
    b.bus.delay(lambda f: f.can_id == 0x581, 3 * MS)
    fb = b.fb(spec.name)
    fb.set(**spec.inputs)
    t0 = b.plc.time_ns
    states = run_recording(b, fb, execute_scans=None, alt_at=spec.alt)
    assert any(s[0] for s in states) and not any(s[2] for s in states)
    assert requests(b, t0, spec.polls) == reference


@pytest.mark.parametrize("spec", [s for s in SPECS if s.bad], ids=[s.name for s in SPECS if s.bad])
def test_invalid_input_error_held_then_reset(spec):
    b = bench(spec)
    fb = b.fb(spec.name)
    fb.set(**{**spec.inputs, **spec.bad})
    t0 = b.plc.time_ns
    states = run_recording(b, fb, execute_scans=None)
    assert states[0][2] and states[0][4] != 0                  # Error in the Execute scan itself
    assert all(s[2] for s in states)                           # held while Execute stays TRUE
    assert requests(b, t0) == []
    check_reset_on_falling_edge(b, fb)


@pytest.mark.parametrize("spec", SPECS, ids=IDS)
def test_error_is_a_one_scan_pulse_when_execute_fell_before(spec):
    b = bench(spec)
    b["CH1.SDOTIMEOUT"] = 20 * MS
    b.bus.drop(lambda f: f.can_id == 0x581)                    # the drive's answers never arrive
    if spec.name == "RST":
        b.bus.drop(lambda f: f.can_id == 0x701)
    fb = b.fb(spec.name)
    fb.set(**{**spec.inputs, **spec.fail})
    check_one_scan_pulse(b, fb, 2)


@pytest.mark.parametrize("spec", [s for s in SPECS if s.abort], ids=[s.name for s in SPECS if s.abort])
def test_abort(spec):
    b = bench(spec)
    b.bus.delay(lambda f: f.can_id == 0x581, 3 * MS)
    fb = b.fb(spec.name)
    fb.start(**spec.inputs)
    b.step(2)
    assert fb["BUSY"]
    fb["ABORT"] = True
    b.step(1)
    s = outputs(fb)
    assert_exclusive(s)
    assert s[3] and not s[1]
    b.step(3)
    assert fb["COMMANDABORTED"]                                # held while Execute stays TRUE
    fb.set(EXECUTE=False, ABORT=False)
    b.step(1)
    assert outputs(fb) == (False, False, False, False, 0)
    assert b.fb("RD").run(UPID=0x1005).done                    # the channel is free again



@pytest.mark.parametrize("spec", SPECS, ids=IDS)
def test_execute_rising_in_the_scan_after_the_pulse_starts_a_new_run(spec):
    """PLCopen: a rising edge of Execute after the FB finished starts a new command, also when it comes in
    the scan right after the one-scan Done pulse (not swallowed, the old Done not shown for it).
    CA / CAF add the same curve again: the drive answers D4h (exists), an Error end of the new run."""
    b = bench(spec)
    fb = b.fb(spec.name)
    fb.set(**spec.inputs)
    check_rising_edge_after_the_pulse(b, fb)


@pytest.mark.parametrize("spec", SPECS, ids=IDS)
def test_execute_toggled_every_scan_gives_one_run_per_edge_after_completion(spec):
    b = bench(spec)
    fb = b.fb(spec.name)
    fb.set(**spec.inputs)
    check_toggled_execute(b, fb)
