"""The fault-injection matrix (linmot_st.commission.faultmatrix, docs/commissioning.md "The fault-injection
matrix"): every fault family at every phase of a commissioning run against an emulated drive. Each cell:
the failure reported within its phase's bound or the fault tolerated, no false success (checked against
the drive's memory and state), no stale confirmation, no hang or crash, the MC running again after a
reported failure, nothing written by a run that failed before its first write, and the next run on the
same PLC and drive commissioned and verified. `make bench` prints the totals."""

from __future__ import annotations

import pytest

from linmot_st.commission.faultmatrix import FAMILIES, PHASES, TOLERATED, run_cell


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
