"""The station against an emulated E1100 on a simulated CAN bus, in virtual time: no hardware.

Fixtures and markers come from the linmot-st pytest plugin: `rig` is this project's PLC (plc.st) with one
emulated drive (node 1, pyproject.toml); docs/testing.md of linmot-st lists the rest.
"""

import pytest

from linmot_st.protocol.errors import name_of
from linmot_st.pvl import load_pvl
from linmot_st.pvl.to_st import to_st

STATION = "MAIN.STATION"
MM = 10_000                                     # the drive's position unit is 0.1 um
PVL = load_pvl("drive.pvl")


def limit(upid: int) -> int:
    """A position limit of drive.pvl (its raw 32-bit value, as the DINT the PLC reads; unit 0.1 um)."""
    raw = next(p.value for o in PVL.parameter_objects for p in o.parameters if p.upid == upid)
    return raw - (1 << 32) if raw >= 1 << 31 else raw


MAX_POSITION, MIN_POSITION = limit(0x146F), limit(0x146E)


def test_the_dataset_is_generated_from_drive_pvl(linmot_project):
    """dataset.st is what `linmot-st pvl to-st drive.pvl -o dataset.st` writes: regenerate it after
    editing drive.pvl."""
    assert (linmot_project.root / "dataset.st").read_text() == to_st(PVL, source_name="drive.pvl")


@pytest.mark.each_backend
def test_the_station_commissions_its_axis_and_reads_its_limits(rig):
    rig.watch(f"{STATION}.STATE", f"{STATION}.ERRORID")
    rig.step_until(f"{STATION}.COMMISSIONED", ms=60_000)
    assert rig[f"{STATION}.MAXPOSITION"] == MAX_POSITION
    assert rig[f"{STATION}.MINPOSITION"] == MIN_POSITION
    # what the PLC wrote is in the drive: a parameter, the curves and the command table, in flash
    assert rig.drive.params[0x146F].rom == MAX_POSITION & 0xFFFFFFFF
    assert sorted(rig.drive.curves.flash) == sorted(c.curve_id for c in PVL.curves)
    assert len(rig.drive.ct.flash) == len(PVL.command_table)


@pytest.mark.each_backend
def test_the_station_moves_then_runs_its_curve(rig):
    """The job: a move to MoveTarget (20 mm), then curve 1 of drive.pvl from there. The emulated drive's
    trajectory shows what the axis did: the move's end, then the curve's shape as drive.pvl has it."""
    rig.watch(f"{STATION}.STATE", f"{STATION}.ERRORID", f"{STATION}.DRIVEERROR")
    rig.step_until(f"{STATION}.STATE = ST_CURVE", ms=90_000)
    t_curve = rig.time_ns
    assert abs(rig.drive.mc.axis.position - 20 * MM) <= 0.1 * MM            # the move ended at 20 mm
    rig.step_until(f"{STATION}.READY", ms=5_000)
    curve = next(c for c in PVL.curves if c.curve_id == 1)
    run = [s for s in rig.drive.mc.trajectory.between(t_curve) if s.demand != 20 * MM]
    duration_ms = (run[-1].t_ns - run[0].t_ns) / 1e6
    assert abs(duration_ms - 400) <= 2                                        # "MinJerk_100mm_400ms"
    assert abs(run[-1].demand - (20 * MM + curve.setpoints[-1])) <= 1         # from where the move ended
    assert abs(rig.drive.mc.axis.position - 120 * MM) <= 0.1 * MM
    assert rig[f"{STATION}.ERRORID"] == 0


def test_a_move_target_outside_the_limits_moves_nothing(rig):
    """The station checks its target against the drive's limits before it switches anything on."""
    rig["MAIN.STATION.MOVETARGET"] = 250.0                                 # beyond MaxPosition (200 mm)
    rig.step_until(f"{STATION}.ERROR", ms=60_000, watch=[f"{STATION}.STATE"])
    assert name_of(rig[f"{STATION}.ERRORID"]) == "PositionRange"
    rig.step(500)
    rxpdos = [e for e in rig.frames(0) if e.frame.can_id in (0x201, 0x301, 0x401)]
    assert rxpdos == []                                                     # not even powered
    assert rig.drive.mc.state != 8


def test_the_commissioning_fb_is_done_within_its_budget(rig):
    rig.step_until(f"{STATION}.STATE = ST_COMMISSION", ms=10_000)     # the drive booted
    result = rig.expect_done(f"{STATION}.COM", ms=30_000)
    assert result["ITEMSDONE"] == result["ITEMSTOTAL"] > 0


def test_lost_answers_during_the_curves_stop_the_station(rig):
    """An answer of the drive lost while the curves are written: the library's timeout fires, the station
    reports the phase and the ErrorID and goes no further."""
    fault = rig.inject_fault("drop", sender=rig.drive_name(1), can_id=0x581, count=1,
                             when=f"{STATION}.COM.PHASE = LM_COM_CURVES")
    rig.step_until(f"{STATION}.ERROR", ms=60_000, watch=[f"{STATION}.STATE"])
    assert len(fault.hits) == 1 and fault.installed_ns > 0
    assert rig[f"{STATION}.FAILPHASE"] == "LM_COM_CURVES"
    assert name_of(rig[f"{STATION}.ERRORID"]) == "SdoTimeout"
    rig.step(1000)
    assert rig[f"{STATION}.STATE"] == "ST_ERROR"


@pytest.mark.drives(1, timings="fast")
def test_a_forced_node_id_talks_to_no_drive(rig):
    """Forcing a variable by its IEC path: with the station on node 5 nobody answers, it waits for a boot."""
    rig.force(f"{STATION}.CH.NODEID", 5)
    rig.step(2000)
    assert rig[f"{STATION}.STATE"] == "ST_BOOT"
    assert not any(e.frame.can_id == 0x605 for e in rig.frames(0))        # it never got to send a request


def test_the_station_on_a_python_can_bus_in_real_time(pycan_rig):
    """The same PLC against a drive served on a python-can `virtual` bus, scan by scan in real time (fast
    drive timings: the boot takes 20 ms)."""
    pycan_rig.step_until(f"{STATION}.STATE = ST_COMMISSION", scans=2000)
    assert pycan_rig[f"{STATION}.CH.NODEID"] == 1


@pytest.mark.needs_vcan("vcan0")
def test_the_station_on_vcan0(pycan_rig):
    """On a SocketCAN interface (skipped where vcan0 does not exist, as on most CI runners)."""
    pycan_rig.step_until(f"{STATION}.STATE = ST_COMMISSION", scans=2000)
