"""The one PLCopen suite (spec/conventions.md; for motion spec/linmot-motion.md 5): every Execute-type FB of
st_lib, the configuration (service) FBs and the motion FBs that end Done, gets the same checks
(tests/st_lib/plcopen_checks.py): edge latching, exclusive outputs, Done/Error held while Execute stays TRUE,
one-scan Done/Error pulses when Execute fell before the end, re-trigger while Busy ignored, inputs latched at the
rising edge, invalid inputs ending in Error before any frame, outputs reset on the falling edge, a new run on an
edge in the scan after the pulse, Execute toggled every scan. The FB lists, and how each family's runs are seen
and disturbed on its testbench, are tests/st_lib/plcopen_service_fbs.py and plcopen_motion_fbs.py. The ends only
one family has: Abort (the service FBs' input) and a newer command aborting a motion (CommandAborted); the motion
FBs' own rules (velocity, cams, jog, reset) are tests/st_lib/motion/test_motion_plcopen.py."""

from __future__ import annotations

import pytest

from plcopen_checks import (
    assert_exclusive,
    check_done_held,
    check_one_scan_pulse,
    check_reset_on_falling_edge,
    check_rising_edge_after_the_pulse,
    check_toggled_execute,
    outputs,
    run_recording,
)
from plcopen_motion_fbs import MotionFamily
from plcopen_service_fbs import ServiceFamily

MS = 1_000_000
FAMILIES = (ServiceFamily, MotionFamily)


def cases(keep=lambda family, spec: True):
    return [pytest.param(family, spec, id=f"{family.name}-{spec.name}")
            for family in FAMILIES for spec in family.specs if keep(family, spec)]


def active_only_while_busy(fb) -> None:
    try:
        active = fb["ACTIVE"]
    except Exception:
        return                                                 # an FB without Active
    assert not active or fb["BUSY"]


def started(family, spec):
    b = family.bench(spec)
    fb = b.fb(spec.name)
    fb.set(**spec.inputs)
    return b, fb


@pytest.mark.parametrize("family, spec", cases())
def test_done_held_while_execute_then_reset_on_falling_edge(family, spec):
    b, fb = started(family, spec)
    check_done_held(b, fb)
    active_only_while_busy(fb)
    check_reset_on_falling_edge(b, fb)


@pytest.mark.parametrize("family, spec", cases())
def test_done_is_a_one_scan_pulse_when_execute_fell_before(family, spec):
    b, fb = started(family, spec)
    check_one_scan_pulse(b, fb, 0)


@pytest.mark.parametrize("family, spec", cases())
def test_retrigger_while_busy_is_ignored_and_inputs_are_latched(family, spec):
    """An edge while Busy (Execute low in scan 3, high again) and other inputs set in scan 2 change nothing: one
    run, with the inputs of the first edge, the same frames as a run left alone."""
    ref = family.bench(spec)
    t0 = ref.plc.time_ns
    assert ref.fb(spec.name).run(**spec.inputs).done
    reference = family.frames(ref, spec, t0)

    b = family.bench(spec)
    family.keep_busy(b)
    fb = b.fb(spec.name)
    fb.set(**spec.inputs)
    t0 = b.plc.time_ns
    states = run_recording(b, fb, execute_scans=None, retrigger_at=3, alt_at=spec.alt)
    assert any(s[0] for s in states) and not any(s[2] for s in states)
    # one run: Busy from its first scan on (it never rises again), Done from its first scan to the end
    assert sum(1 for a, z in zip(states, states[1:]) if z[1] and not a[1]) == 0
    assert [s[0] for s in states].count(True) == len(states) - next(i for i, s in enumerate(states) if s[0])
    b.step(20)
    if getattr(spec, "same_frames", True):
        assert family.frames(b, spec, t0) == reference


@pytest.mark.parametrize("family, spec", cases(lambda family, spec: spec.alt is not None))
def test_inputs_are_latched_at_the_rising_edge(family, spec):
    ref = family.bench(spec)
    t0 = ref.plc.time_ns
    assert ref.fb(spec.name).run(**spec.inputs).done
    reference = family.frames(ref, spec, t0)

    b = family.bench(spec)
    family.keep_busy(b)
    fb = b.fb(spec.name)
    fb.set(**spec.inputs)
    t0 = b.plc.time_ns
    states = run_recording(b, fb, execute_scans=None, alt_at=spec.alt)
    assert any(s[0] for s in states) and not any(s[2] for s in states)
    if getattr(spec, "same_frames", True):
        assert family.frames(b, spec, t0) == reference


@pytest.mark.parametrize("family, spec", cases(lambda family, spec: spec.bad is not None))
def test_invalid_input_error_held_then_reset(family, spec):
    b = family.bench(spec)
    fb = b.fb(spec.name)
    fb.set(**{**spec.inputs, **spec.bad})
    t0 = b.plc.time_ns
    states = run_recording(b, fb, execute_scans=None)
    assert states[0][2] and states[0][4] != 0                  # Error in the Execute scan itself
    assert all(s[2] for s in states)                           # held while Execute stays TRUE
    assert family.frames_of_a_refused_run(b, spec, t0) == []   # before any frame
    check_reset_on_falling_edge(b, fb)


@pytest.mark.parametrize("family, spec", cases(lambda family, spec: family.fails(spec)))
def test_error_is_a_one_scan_pulse_when_execute_fell_before(family, spec):
    b = family.bench(spec)
    extra = family.make_it_fail(b, spec)
    fb = b.fb(spec.name)
    fb.set(**{**spec.inputs, **extra})
    check_one_scan_pulse(b, fb, 2)


@pytest.mark.parametrize("family, spec", cases())
def test_execute_rising_in_the_scan_after_the_pulse_starts_a_new_run(family, spec):
    """PLCopen: a rising edge of Execute after the FB finished starts a new command, also when it comes in
    the scan right after the one-scan Done pulse (not swallowed, the old Done not shown for it).
    CA / CAF add the same curve again: the drive answers D4h (exists), an Error end of the new run."""
    b, fb = started(family, spec)
    check_rising_edge_after_the_pulse(b, fb, **family.pulse_options(spec))


@pytest.mark.parametrize("family, spec", cases())
def test_execute_toggled_every_scan_gives_one_run_per_edge_after_completion(family, spec):
    b, fb = started(family, spec)
    check_toggled_execute(b, fb, **family.pulse_options(spec))


# ---------------------------------------------------------------- the ends of one family
@pytest.mark.parametrize("family, spec", cases(lambda family, spec: family is ServiceFamily and spec.abort))
def test_abort(family, spec):
    b = family.bench(spec)
    family.keep_busy(b)
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


@pytest.mark.parametrize("family, spec", cases(lambda family, spec: family is MotionFamily and spec.abortable))
def test_a_newer_command_aborts_it(family, spec):
    b = family.bench(spec)
    b.bus.delay(lambda f: f.can_id == 0x181, 5 * MS)             # keep it busy
    fb = b.fb(spec.name)
    fb.start(**spec.inputs)
    b.step(2)
    assert fb["BUSY"]
    newer = b.fb(spec.newer[0])
    newer.start(**spec.newer[1])
    b.sim.run_until(lambda: fb["COMMANDABORTED"] or fb["DONE"] or fb["ERROR"], max_scans=200)
    s = outputs(fb)
    assert_exclusive(s)
    assert s[3] and not s[1], s
    b.step(3)
    assert fb["COMMANDABORTED"]                                  # held while Execute stays TRUE
    check_reset_on_falling_edge(b, fb)
    b.sim.run_until(lambda: newer["DONE"], max_scans=1000)       # the newer one runs to its end
