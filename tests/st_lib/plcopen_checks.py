"""The PLCopen behaviour checks (spec/conventions.md) every FB of the library gets: the one suite over both FB lists,
tests/st_lib/test_plcopen.py, and the motion FBs' own rules in tests/st_lib/motion/test_motion_plcopen.py. `request_starts(b, t0)` names the
frames that show a run started (an SDO request, a motion command): each suite passes its own."""

from __future__ import annotations

from collections.abc import Callable

from stbench import Bench, Fb


def outputs(fb: Fb) -> tuple:
    aborted = fb._aborted()
    return fb["DONE"], fb["BUSY"], fb["ERROR"], aborted, fb["ERRORID"]


def assert_exclusive(state: tuple) -> None:
    done, busy, error, aborted, error_id = state
    assert done + busy + error + aborted <= 1, state
    assert (error_id != 0) == error, state


def requests(b: Bench, t0: int, polls: bool = False) -> list[bytes]:
    """The node's SDO requests since t0; with `polls`, repeated identical requests (flash polls) count once."""
    out = [bytes(e.frame.data) for e in b.sdo_trace(since_ns=t0) if e.frame.can_id == 0x601]
    if polls:
        out = [r for i, r in enumerate(out) if i == 0 or r != out[i - 1]]
    return out


def run_recording(b: Bench, fb: Fb, execute_scans: int | None, max_scans: int = 5000,
                  retrigger_at: int | None = None, alt_at: dict | None = None) -> list[tuple]:
    """Step with Execute TRUE for `execute_scans` scans (None: until the end), recording the outputs each
    scan; stops 3 scans after the FB finished. Execute goes low at `retrigger_at` and high again after it."""
    states, end = [], None
    for k in range(1, max_scans + 1):
        if retrigger_at is not None:
            fb["EXECUTE"] = k != retrigger_at
        else:
            fb["EXECUTE"] = execute_scans is None or k <= execute_scans
        if alt_at and k == 2:
            fb.set(**alt_at)
        b.step(1)
        s = outputs(fb)
        assert_exclusive(s)
        states.append(s)
        if end is None and (s[0] or s[2] or s[3]):
            end = k
        if end is not None and k >= end + 3:
            return states
    raise AssertionError(f"{fb.name} did not finish")


IDLE = (False, False, False, False, 0)


def check_done_held(b: Bench, fb: Fb) -> None:
    """Execute held TRUE: Busy from the Execute scan until Done, then Done held while Execute stays TRUE."""
    states = run_recording(b, fb, execute_scans=None)
    first = next(i for i, s in enumerate(states) if s[0])
    assert all(s[1] for s in states[:first]), "Busy from the Execute scan until Done"
    assert all(s[0] and not s[1] for s in states[first:]), "Done held while Execute stays TRUE"


def check_reset_on_falling_edge(b: Bench, fb: Fb) -> None:
    """Execute falls after the FB finished: every output is reset in that scan."""
    fb["EXECUTE"] = False
    b.step(1)
    assert outputs(fb) == IDLE


def check_one_scan_pulse(b: Bench, fb: Fb, which: int) -> None:
    """Execute for one scan only: the end (which = 0 Done, 2 Error) shows for exactly one scan, Busy before."""
    states = run_recording(b, fb, execute_scans=1)
    assert [s[which] for s in states].count(True) == 1
    first = next(i for i, s in enumerate(states) if s[which])
    assert all(s[1] for s in states[:first])
    assert states[first + 1:] == [IDLE] * (len(states) - first - 1)


def finish_pulse(b: Bench, fb: Fb, max_scans: int = 5000) -> tuple:
    """Execute for one scan, then low until the FB shows its one-scan Done/Error pulse; returns that state."""
    fb["EXECUTE"] = True
    for _ in range(max_scans):
        b.step(1)
        fb["EXECUTE"] = False
        s = outputs(fb)
        if s[0] or s[2]:
            return s
    raise AssertionError(f"{fb.name} did not finish")


def sdo_request_starts(b: Bench, t0: int) -> list[int]:
    return [e.start_ns for e in b.sdo_trace(since_ns=t0) if e.frame.can_id == 0x601]


def check_rising_edge_after_the_pulse(b: Bench, fb: Fb, first_request_scans: int = 1,
                                      request_starts: Callable[[Bench, int], list[int]] = sdo_request_starts) -> None:
    """Execute rises in the scan right after the one-scan Done pulse: a new run (Busy in that scan, the old
    Done gone), its first request on the bus within `first_request_scans` scans, and it finishes."""
    assert finish_pulse(b, fb)[0]
    t0 = b.plc.time_ns
    fb["EXECUTE"] = True                                       # the very next scan
    b.step(1)
    assert outputs(fb) == (False, True, False, False, 0)
    states = run_recording(b, fb, execute_scans=None)
    assert states[-1][0] or states[-1][2]
    starts = request_starts(b, t0)
    assert starts and starts[0] < t0 + first_request_scans * b.plc.tick_ns


def check_toggled_execute(b: Bench, fb: Fb, runs: int = 3, first_request_scans: int = 1,
                          request_starts: Callable[[Bench, int], list[int]] = sdo_request_starts) -> None:
    """Execute TRUE, FALSE, TRUE, ...: every rising edge that finds the FB not Busy starts a run, edges while
    Busy are ignored, every run ends with one Done/Error, and each run's first request reaches the bus."""
    t0 = b.plc.time_ns
    prev = outputs(fb)
    idle_edges = started = ends = 0
    run_starts = []
    for k in range(20_000):
        execute = k % 2 == 0
        fb["EXECUTE"] = execute
        t = b.plc.time_ns
        b.step(1)
        s = outputs(fb)
        assert_exclusive(s)
        if execute and not prev[1]:
            idle_edges += 1
        if s[1] and not prev[1]:
            started += 1
            run_starts.append(t)
            assert execute, "a run starts only at a rising edge"
        if (s[0] or s[2]) and prev[1]:
            ends += 1
        prev = s
        if ends >= runs and not execute:
            break
    assert started == idle_edges == ends >= runs
    b.step(first_request_scans)
    starts = request_starts(b, t0)
    window = first_request_scans * b.plc.tick_ns
    assert all(any(t <= r < t + window for r in starts) for t in run_starts)
