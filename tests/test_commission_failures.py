"""Commissioning that must fail, and say so precisely: firmware mismatches write nothing (checked in the
drive's memory and on the bus), a refused parameter, lost answers in the middle of a curve, a read-back that
differs, a broken dataset, a failed flash save (MC started again), a drive that does not come back after
the reset. Each time the report names the phase, the item and the ErrorID, and the verification says what
differs."""

from __future__ import annotations

import dataclasses

import pytest

from linmot_st.cli import main
from linmot_st.pvl import dataset as dsf
from linmot_st.commission.testing import EXAMPLE, commission, example, use_local_matiec
from linmot_st.emulator import DriveTimings, E1100Drive, load_profile

use_local_matiec()

PVL = example()
WORDS = dsf.encode(PVL)
DS = "MAIN.DS"


def word_of_param(upid: int) -> int:
    """1-based index of the value word of a parameter record in the dataset."""
    i = WORDS.index(dsf.TAG_PARAM << 24 | upid)
    return i + 2


def fast_drive(profile=None):
    return lambda n: E1100Drive(n, profile, timings=DriveTimings.fast())


def downloads(result, node: int) -> list:
    """SDO download requests (cs 23h: writes of any kind) to a node."""
    return [e for e in result.trace if e.frame.can_id == 0x600 + node and e.frame.data[0] == 0x23]


def untouched(drive) -> None:
    """The drive's memory is as it left the factory: defaults, no curves, no command table."""
    for obj in PVL.parameter_objects:
        for p in obj.parameters:
            d = drive.params[p.upid]
            assert d.rom == d.default and d.ram == d.default, hex(p.upid)
    assert not drive.curves.ram and not drive.curves.flash and not drive.ct.ram and not drive.ct.flash


MISMATCHES = [
    pytest.param("TreeIdMismatch", 0x0501, dict(tree_id=4613), None, (4613, 3, 0), id="tree-id"),
    pytest.param("MainVersionMismatch", 0x0502, dict(main_version=4), None, (4612, 4, 0), id="main-version"),
    # the drive's sub version 0 is below the dataset's: the dataset says MC tree 4612 version 3.1
    pytest.param("SubVersionNewer", 0x0503, None, 0x00030001, (4612, 3, 0), id="sub-version"),
]


@pytest.mark.parametrize("name, error_id, tree, dataset_mc_version, drive_layer", MISMATCHES)
def test_a_mismatching_layer_writes_nothing(name, error_id, tree, dataset_mc_version, drive_layer):
    profile = load_profile().with_tree(2, **tree) if tree else None
    factory = lambda n: E1100Drive(n, profile if n == 2 else None, timings=DriveTimings.fast())   # noqa: E731
    patch = None
    if dataset_mc_version is not None:
        patch = lambda plc: plc.__setitem__(f"{DS}[8]", dataset_mc_version)                       # noqa: E731
    o = commission(axes=2, drive_factory=factory, prepare_plc=patch)
    bad = o.axis(2)
    assert bad.error and bad.error_id == error_id
    assert (bad.fail_phase, bad.fail_item, bad.drive_layer) == ("check", 2, drive_layer)
    assert [p.phase for p in bad.phases] == ["start", "check"]
    assert downloads(o.result, 2) == []                             # not a single write went to node 2
    assert bad.exchanges == len([e for e in o.result.trace if e.frame.can_id == 0x602]) == 6   # 2 x 3 reads
    untouched(o.result.drives[2])
    text = o.report.text()
    assert (f"node 2: Failed in phase compatibility check, layer 2 (Motion Control SW): ErrorID 16#{error_id:04X}"
            in text)
    assert f"the drive has tree ID {drive_layer[0]}, version {drive_layer[1]}.{drive_layer[2]}" in text
    assert "nothing was written" in text
    failed = "node 2" if dataset_mc_version is None else "nodes 1, 2"      # the patched dataset serves both
    assert f"result: FAILED (commissioning failed on {failed};" in text
    assert not o.verification.node_ok(2)                            # and the verification says what differs
    rom = next(c for c in o.verification.for_node(2) if c.what == "parameters ROM")
    assert rom.differences and rom.equal < 30
    node1 = o.axis(1)
    assert node1.done == (dataset_mc_version is None)               # a drive that matches is commissioned


def test_a_refused_parameter_stops_at_that_upid():
    profile = load_profile()
    friction = next(d for d in profile.parameters if d.upid == 0x13A5)
    profile = profile.with_parameters([dataclasses.replace(friction, max=50)])   # the PVL writes 100
    o = commission(axes=1, drive_factory=fast_drive(profile))
    ax = o.axis(1)
    assert ax.error and (ax.error_id, ax.abort_code) == (0x0302, 0x06090030)
    assert (ax.fail_phase, ax.fail_item) == ("params", 0x13A5)
    text = o.report.text()
    assert ("Failed in phase parameters, UPID 13A5h Motion Control SW\\Position Controller\\Control Parameter "
            "Set A\\FF Friction: ErrorID 16#0302 the drive answered with an SDO abort (code on the AbortCode output): "
            "06090030h invalid value for parameter (download only)") in text
    drive = o.result.drives[1]
    rows = [p for obj in PVL.parameter_objects for p in obj.parameters]
    k = next(i for i, p in enumerate(rows) if p.upid == 0x13A5)
    for p in rows[:k]:                                              # written before the refusal
        assert drive.rom(p.upid) == drive.params[p.upid].type.from_raw(p.value)
    assert drive.rom(0x13A5) == friction.default
    assert not drive.curves.ram                                     # nothing after it
    failed = {c.what: c for c in o.verification.for_node(1) if not c.ok}
    assert "parameters ROM" in failed and "curves RAM" in failed and "command table RAM" in failed
    assert any(d.startswith("13A5h") for d in failed["parameters ROM"].differences)
    assert "curve 1: missing on the drive" in failed["curves RAM"].differences
    assert "result: FAILED (commissioning failed on node 1; verification found differences)" in text


def test_answers_lost_in_the_middle_of_a_curve():
    seen = {"n": 0}

    def after_100(frame) -> bool:                                   # the drive's 101st answer and all later ones
        if frame.can_id != 0x581:
            return False
        seen["n"] += 1
        return seen["n"] > 100

    o = commission(axes=1, prepare_bus=lambda bus, drives: bus.drop(after_100))
    ax = o.axis(1)
    # answers 1..6 layers, 7..36 parameters, 37 delete all curves, 38..66 curve 23 (50h, 18 info, 10 points),
    # 67 curve 1's 50h, 68..85 its info block: answer 101 is the one to setpoint 15 of curve 1
    assert ax.error and ax.error_id == 0x0301
    assert (ax.fail_phase, ax.fail_item, ax.fail_step) == ("curves", 1, 19 + 15)
    assert ax.exchanges == 101
    curves = next(p for p in ax.phases if p.phase == "curves")
    assert curves.t1_ns - curves.t0_ns >= 1_000_000_000             # the channel's SDO timeout (1 s)
    text = o.report.text()
    assert ("Failed in phase curves, curve 1 'MinJerk_100mm_400ms', setpoint 15: ErrorID 16#0301 no SDO "
            "response within the timeout") in text
    drive = o.result.drives[1]
    assert sorted(drive.curves.ram) == [23] and drive.curves.in_progress() == [1]
    assert "curve 1: missing on the drive" in next(c for c in o.verification.for_node(1)
                                                    if c.what == "curves RAM").differences


def test_a_read_back_that_differs_is_reported_with_both_values():
    def patch(plc):
        plc[f"{DS}[{word_of_param(0x13A5)}]"] = 0x00010064         # the drive keeps 16 bits: 0064h reads back
        plc[f"{DS}[{word_of_param(0x1005)}]"] = 0xFFFF05DC         # same 16 bits, sign fill: equal as kept

    o = commission(axes=1, prepare_plc=patch)
    ax = o.axis(1)
    assert ax.error and ax.error_id == 0x0603
    # 1005h (checked before 13A5h) matched: the drive keeps 16 bits, FFFF05DCh and 000005DCh are the same value
    assert (ax.fail_phase, ax.fail_item, ax.fail_expected, ax.fail_actual) == ("verify", 0x13A5, 0x00010064, 0x64)
    assert "read 00000064h, expected 00010064h" in o.report.text()
    assert [p.phase for p in ax.phases][-1] == "verify"


def test_a_broken_dataset_header_fails_before_any_frame():
    o = commission(axes=1, prepare_plc=lambda plc: plc.__setitem__(f"{DS}[1]", 0x12345678))
    ax = o.axis(1)
    assert ax.error and ax.error_id == 0x0601 and (ax.fail_phase, ax.fail_step) == ("start", 1)
    assert ax.exchanges == 0 and not [e for e in o.result.trace if e.frame.can_id == 0x601]
    assert [(p.phase, p.scans) for p in ax.phases] == [("start", 1)]


def test_a_broken_record_fails_where_it_is():
    curve = WORDS.index(dsf.TAG_CURVE << 24 | 23 << 16 | 10) + 1      # 1-based index of curve 23's record
    o = commission(axes=1, prepare_plc=lambda plc: plc.__setitem__(f"{DS}[{curve}]", 0x07170000 | 10))
    ax = o.axis(1)
    assert ax.error and ax.error_id == 0x0601 and ax.fail_step == curve
    assert ax.fail_phase == "params"                                # found when the parameters were written
    assert "dataset malformed" in o.report.text()


class StubbornDrive(E1100Drive):
    """Confirms the stop of its MC software (35h) without stopping it: the save then finds it running."""

    def stop_mc(self):
        return 0


def test_a_failed_flash_save_starts_the_mc_again():
    o = commission(axes=1, drive_factory=lambda n: StubbornDrive(n, timings=DriveTimings.fast()))
    ax = o.axis(1)
    assert ax.error and ax.error_id == 0x04D7 and (ax.fail_phase, ax.fail_item) == ("flash", 0x40)
    subs = [e.frame.data[3] for e in o.result.trace if e.frame.can_id == 0x601 and e.frame.data[1:3] == b"\x00\x20"]
    assert subs[-3:] == [0x35, 0x40, 0x36]                          # stop, save (refused), start again
    assert o.result.drives[1].mc_phase == "running"
    assert "Failed in phase flash save, save curves (40h): ErrorID 16#04D7 result D7h" in o.report.text()


def test_a_drive_that_does_not_come_back_after_the_reset():
    def lose_second_boot_up(bus, drives):
        seen = {"n": 0}

        def pred(f) -> bool:
            if f.can_id == 0x701 and f.data == b"\x00":
                seen["n"] += 1
                return seen["n"] > 1
            return False
        bus.drop(pred)

    o = commission(axes=1, reset=True, prepare_bus=lose_second_boot_up)
    ax = o.axis(1)
    assert ax.error and ax.error_id == 0x0305 and ax.fail_phase == "reset"
    reset = next(p for p in ax.phases if p.phase == "reset")
    assert 10_000_000_000 <= reset.duration_ns <= 10_010_000_000    # BootTimeout, 10 s by default
    assert "Failed in phase reset + boot, reset (0Bh): ErrorID 16#0305" in o.report.text()


def test_command_exits_non_zero_when_the_drives_never_boot(tmp_path, capsys):
    """Realistic drive timings: the boot-up comes after 4 s; a 1 s limit ends the run before."""
    assert main(["commission", str(EXAMPLE), "--timeout", "1", "--report", str(tmp_path / "r"), "-q"]) == 1
    out = capsys.readouterr().out
    assert "node 1: did not finish (never started: no boot-up heard)" in out
    assert "TIMED OUT" in out and "result: FAILED" in out


def test_command_line_errors(tmp_path, capsys):
    assert main(["commission", str(EXAMPLE), "--axes", "9"]) == 2
    assert "plc_project commissions 1..8" in capsys.readouterr().err
    assert main(["commission", str(EXAMPLE), "--axes", "2", "--node-ids", "3,3"]) == 2
    assert main(["commission", str(EXAMPLE), "--axes", "3", "--node-ids", "1,2"]) == 2
    assert main(["commission", str(EXAMPLE), "--no-emulate"]) == 2
    bad = tmp_path / "bad.pvl"
    bad.write_text("@FileType,PVL\n@FormatVersion,1\n@StartObject,Curve\n")
    assert main(["commission", str(bad)]) == 1
    assert "bad.pvl:" in capsys.readouterr().err


def test_a_plc_fault_ends_the_run_and_is_reported():
    """A header that claims more words than the array holds lets the FB ask beyond it: the program's
    Ds[DataIndex] is then an index out of range, a PLC fault, which the report names."""
    curve = WORDS.index(dsf.TAG_CURVE << 24 | 23 << 16 | 10) + 1

    def patch(plc):
        plc[f"{DS}[4]"] = 100_000                                   # total words
        plc[f"{DS}[{curve}]"] = dsf.TAG_CURVE << 24 | 23 << 16 | 5000
        plc[f"{DS}[{curve + 2}]"] = 0x0004_0000 | 5000             # info block: 5000 setpoints of 4 bytes

    o = commission(axes=1, prepare_plc=patch)
    assert o.result.fault and not o.result.commissioned
    text = o.report.text()
    assert "PLC FAULT:" in text and "result: FAILED (the PLC faulted" in text
    assert "array index out of range in POU PLCCOMMISSION (plc_project/commission.st:" in text
    assert "node 1: did not finish" in text and o.result.t_end_ns > o.result.t_start_ns
    # setpoint j is word curve + 19 + j; sending it, the FB asks for words curve + 20 + j and the next one:
    # the program's Ds[DataIndex + 1] faults once that passes word 652
    assert o.axis(1).exchanges == 6 + 30 + 1 + 1 + 18 + (652 - 20 - curve + 1)
