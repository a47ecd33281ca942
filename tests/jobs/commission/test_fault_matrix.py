"""The fault-injection matrix (linmot_st.jobs.commission.faultmatrix, docs/commissioning.md "The fault-injection
matrix"): every fault family at every phase of a commissioning run against an emulated drive. Each cell:
the failure reported within its phase's bound or the fault tolerated, no false success (checked against
the drive's memory and state), no stale confirmation, no hang or crash, the MC running again after a
reported failure, nothing written by a run that failed before its first write, and the next run on the
same PLC and drive commissioned and verified. `make bench` prints the totals."""

from __future__ import annotations

import pytest

from linmot_st.jobs.commission.faultmatrix import FAMILIES, PHASES, TOLERATED, run_cell


@pytest.mark.parametrize("phase", PHASES)
@pytest.mark.parametrize("family", FAMILIES)
def test_cell(family, phase):
    cell = run_cell(family, phase)
    assert cell.armed_ns is not None, f"the run never reached phase {phase}"
    assert cell.problems() == [], (cell.problems(), cell.notes)
    if family in TOLERATED:
        assert cell.done
    if family in ("lost", "wrong_cs", "abort", "removed"):
        assert cell.error and cell.fault_ns is not None      # a fault the FB cannot ride out is reported


@pytest.mark.parametrize("family", ["drive_reset", "removed"])
@pytest.mark.parametrize("phase", ["params", "curves"])
def test_a_run_right_after_one_that_failed_while_the_drive_rebooted_waits_for_its_boot(family, phase):
    """The drive boots for 3 s, longer than the SdoTimeout (1 s): run 1 fails while it still reboots (or is
    switched on again, "removed"), and run 2, started two scans later, found a silent drive (SdoTimeout, or
    DriveRebooted when its boot-up message came; issue 24). Run 2 now waits for it in its WAIT phase (the
    channel re-synchronising since run 1's timeout) and commissions it."""
    import dataclasses

    from linmot_st.emulator import DriveTimings
    cell = run_cell(family, phase, timings=dataclasses.replace(DriveTimings.fast(), boot_ns=3_000_000_000))
    assert cell.error and cell.error_id == 0x0301, cell.error_id          # run 1: SdoTimeout, drive silent
    assert cell.problems() == [], (cell.problems(), cell.notes, hex(cell.second_error_id))
    assert cell.second_done and cell.second_verified
