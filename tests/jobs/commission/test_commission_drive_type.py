"""A PVL file for one drive series is refused on a node whose drive is of the other, before anything is sent
to it, with a message that names both (commission/datasets.py check_drive_type, called by the runner where it
makes each node's drive)."""

from __future__ import annotations

import pytest

from linmot_st.emulator import E1100Drive
from linmot_st.jobs.commission.datasets import DriveTypeMismatch, Source, check_drive_type, drive_series
from linmot_st.jobs.commission.testing import commission, example
from linmot_st.pvl import load_pvl
from linmot_st.pvl.dataset import from_pvl
from repo_paths import EXAMPLES

B1100_FILE = EXAMPLES / "b1100_axis.pvl"


def _source(pvl, name):
    return Source(pvl, from_pvl(pvl), name)


def test_check_names_both_series():
    b1100, e1100 = load_pvl(B1100_FILE), example()
    with pytest.raises(DriveTypeMismatch) as err:
        check_drive_type(3, _source(b1100, "b1100_axis.pvl"), "E1100")
    msg = str(err.value)
    assert "node 3: b1100_axis.pvl is a PVL file for a B1100" in msg and "node 3 is an E1100" in msg
    with pytest.raises(DriveTypeMismatch, match=r"two_axes.pvl is a PVL file for an E1100 .* is a B1100"):
        check_drive_type(2, _source(e1100, "two_axes.pvl"), "B1100")
    curves_only = load_pvl(B1100_FILE.with_name("seed_curve.pvl"))    # no tree name: an E1100 file (curves)
    with pytest.raises(DriveTypeMismatch, match=r"for an E1100 \(no parameter object: curves or command table\)"):
        check_drive_type(4, _source(curves_only, "seed_curve.pvl"), "B1100")
    check_drive_type(1, _source(b1100, "b1100_axis.pvl"), "b1100")
    check_drive_type(1, _source(e1100, "two_axes.pvl"), "E1100")


def test_emulated_drive_series():
    assert drive_series(E1100Drive(1)) == "E1100"           # from its profile's definitions


class _SeriesDrive(E1100Drive):
    """An emulated drive that reports another series (the B1100 model comes with the drive-model seam)."""
    series = "B1100"


@pytest.mark.parametrize("pvl_file, factory, names", [
    (B1100_FILE, None, ("for a B1100", "is an E1100")),
    (None, lambda n: _SeriesDrive(n), ("for an E1100", "is a B1100")),
])
def test_runner_refuses_before_any_frame(pvl_file, factory, names):
    pvl = load_pvl(pvl_file) if pvl_file else example()
    bus_seen = []
    # without a factory the runner would give node 1 a B1100 (the series of its file): ask for E1100s
    hooks = {"drive_factory": factory} if factory else {"drive_model": "E1100"}
    with pytest.raises(DriveTypeMismatch) as err:
        commission(pvl=pvl, axes=2, prepare_bus=lambda bus, drives: bus_seen.append(bus), **hooks)
    assert all(n in str(err.value) for n in names) and "node 1" in str(err.value)
    assert bus_seen == []          # refused while the drives were made: before power-on, no frame on the bus
