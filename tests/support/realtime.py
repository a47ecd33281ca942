"""Real-time tests on a loaded machine (issue 24, section 4; docs/testing.md, "Real-time tests under load").

A real-time run (RealTimeCoSim, NodeServer threads) measures the host as much as the program: when the host
does not run the test process for a while (a loaded CI runner), the PLC's next scan starts late and its clock
jumps to the wall time (cosim.py: an overrun), and the emulated drive's thread is held as well. A stall longer
than what the program's own watchdogs allow (the motion program's PdoTimeout, 200 ms, against TxPDO1's 50 ms
event time; an SDO timeout) is then reported by the program, as a real PLC whose task overran that long
reports it: a correct result, not a defect of the code under test. The tests therefore assert what holds
under load (counts and order, not wall-clock tightness) and take another measurement only when a failed one
measured such a stall, the stall recorded; a failure without a stall fails the test at once.
"""

from __future__ import annotations

import warnings

MS = 1_000_000
STALL_NS = 50 * MS           # a scan this late: the TxPDO1 event period the motion program watches
ATTEMPTS = 3


def retry_after_stall(run, ok, stall_ns: int = STALL_NS, attempts: int = ATTEMPTS):
    """Call run() (a commissioning RunResult) until ok(result); another attempt only after a failed one whose
    latest scan started stall_ns or more late (RunResult.max_lateness_ns). Returns (result, the stalls that
    caused the retries, ns)."""
    stalls: list[int] = []
    for _ in range(attempts):
        result = run()
        if ok(result) or result.max_lateness_ns < stall_ns:
            return result, stalls
        stalls.append(result.max_lateness_ns)
        warnings.warn(f"real-time run measured again: it failed after a host stall of "
                      f"{result.max_lateness_ns / 1e6:.0f} ms (a scan that late)", stacklevel=2)
    return result, stalls


def measure_again_if_the_host_stalled(attempt, stalled, attempts: int = ATTEMPTS):
    """For tests of the real-time pacing itself: call attempt() until not stalled(result) (a scan that the
    host, not the test, made late: an overrun the test did not cause), at most `attempts` times, a warning
    each time; the caller asserts on the returned result. A defect of the pacing fails every attempt. The
    pacing tests are cheap (under 0.1 s each) and pass attempts=10: on two cores beside two CPU hogs and the
    other real-time tests, three in a row were seen stalled."""
    for k in range(attempts):
        result = attempt()
        if not stalled(result) or k == attempts - 1:
            return result
        warnings.warn("real-time pacing measured again: the host made a scan late", stacklevel=2)
    return result
