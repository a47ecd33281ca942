"""Commissioning that must fail, and say so precisely: firmware mismatches write nothing (checked in the
drive's memory and on the bus), a refused parameter, lost answers in the middle of a curve, a read-back that
differs, a broken dataset, a failed flash save (MC started again), a drive that does not come back after
the reset. Each time the report names the phase, the item and the ErrorID, and the verification says what
differs."""

from __future__ import annotations

import dataclasses

import pytest

from linmot_st.cli import main
from linmot_st.emulator import DriveTimings, E1100Drive, load_profile
from linmot_st.jobs.commission.testing import EXAMPLE, commission, example
from linmot_st.pvl import dataset as dsf

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
    assert bad.fail_kind == "layer"
    failed = "node 2" if dataset_mc_version is None else "nodes 1, 2"      # the patched dataset serves both
    assert f"result: FAILED (commissioning failed on {failed})" in text   # the verification has nothing to add
    # the verification checks that the drive is as it was when switched on (not the ~40 PVL items it lacks)
    assert [c.what for c in o.verification.for_node(2)] == ["drive unchanged"] and o.verification.node_ok(2)
    assert ("node 2: nothing written (as intended: the run stopped in the compatibility check); drive unchanged"
            in text)
    assert "missing on the drive" not in text.split("node 2: nothing written")[1]
    # the plots and the report do not call the PVL's curves "written" on that drive
    for c in o.report.figures["curves"]:
        assert next(n for n in c["nodes"] if n["node"] == 2)["verdict"] == "not written"
    node1 = o.axis(1)
    assert node1.done == (dataset_mc_version is None)               # a drive that matches is commissioned


def refusing_friction():
    profile = load_profile()
    friction = next(d for d in profile.parameters if d.upid == 0x13A5)
    return friction, profile.with_parameters([dataclasses.replace(friction, max=50)])   # the PVL writes 100


def test_the_pre_flight_refuses_a_value_beyond_the_drives_maximum_and_writes_nothing():
    _friction, profile = refusing_friction()
    o = commission(axes=1, drive_factory=fast_drive(profile))
    ax = o.axis(1)
    assert ax.error and ax.error_id == 0x0606
    assert (ax.fail_phase, ax.fail_kind, ax.fail_item) == ("preflight", "param", 0x13A5)
    assert (ax.fail_expected, ax.fail_actual) == (50, 100)
    assert all(e.frame.data[3] == 0x20 for e in downloads(o.result, 1))     # the UPID list starts only
    untouched(o.result.drives[1])
    text = o.report.text()
    assert ("Failed in phase pre-flight check, UPID 13A5h Motion Control SW\\Position Controller\\Control "
            "Parameter Set A\\FF Friction: ErrorID 16#0606 pre-flight: the dataset's value (FailActual) is above "
            "the drive's maximum (FailExpected); nothing was written (the dataset's value 00000064h, the drive's "
            "maximum 00000032h)") in text
    assert [c.what for c in o.verification.for_node(1)] == ["drive unchanged"] and o.verification.node_ok(1)


def test_without_pre_flight_a_refused_parameter_stops_at_that_upid():
    friction, profile = refusing_friction()
    o = commission(axes=1, drive_factory=fast_drive(profile), preflight=False)
    ax = o.axis(1)
    assert ax.error and (ax.error_id, ax.abort_code) == (0x0302, 0x06090030)
    assert (ax.fail_phase, ax.fail_kind, ax.fail_item) == ("params", "param", 0x13A5)
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

    def after_220(frame) -> bool:                                   # the drive's 221st answer and all later ones
        if frame.can_id != 0x581:
            return False
        seen["n"] += 1
        return seen["n"] > 220

    o = commission(axes=1, prepare_bus=lambda bus, drives: bus.drop(after_220))
    ax = o.axis(1)
    # answers 1..6 layers, 7..126 pre-flight, 127..156 parameters, 157 delete all curves, 158..186 curve 23
    # (50h, 18 info, 10 points), 187 curve 1's 50h, 188..205 its info block: answer 221 is the one to
    # setpoint 15 of curve 1
    assert ax.error and ax.error_id == 0x0301
    assert (ax.fail_phase, ax.fail_kind, ax.fail_item, ax.fail_step) == ("curves", "curve", 1, 19 + 15)
    assert ax.exchanges == 221
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

    o = commission(axes=1, prepare_plc=patch, preflight=False)      # the pre-flight would refuse 00010064h
    ax = o.axis(1)
    assert ax.error and ax.error_id == 0x0603
    # 1005h (checked before 13A5h) matched: the drive keeps 16 bits, FFFF05DCh and 000005DCh are the same value
    assert (ax.fail_phase, ax.fail_item, ax.fail_expected, ax.fail_actual) == ("verify", 0x13A5, 0x00010064, 0x64)
    assert "read 00000064h, expected 00010064h" in o.report.text()
    assert [p.phase for p in ax.phases][-1] == "verify"


def test_real_drives_are_verified_by_the_plcs_read_back_and_fail_without_it():
    """--no-emulate: the drives' memory cannot be inspected; the PLC's VERIFY phase is the verification (an
    axis is done only after it read every item back), and without it nothing is verified."""
    from types import SimpleNamespace

    from linmot_st.jobs.commission.verify import verify

    v = verify(PVL, {}, SimpleNamespace(verify=True))
    assert v.ok and "VERIFY phase" in v.by_plc and not v.skipped and not v.checks
    v = verify(PVL, {}, SimpleNamespace(verify=False))
    assert not v.ok and not v.by_plc and "nothing read back" in v.skipped


def test_a_drive_that_changed_although_the_check_failed_is_compared_in_full():
    """The condensed "nothing written" is checked, not assumed: a change shows up, with the full comparison."""
    from types import SimpleNamespace

    from linmot_st.jobs.commission.verify import drive_state, verify

    drive = E1100Drive(1)
    before = {1: drive_state(drive)}
    opts = SimpleNamespace(reset=False, live_ram=False, flash=True)
    v = verify(PVL, {1: drive}, opts, before=before, stopped_before_writes={1: "check"})
    assert [c.what for c in v.checks] == ["drive unchanged"] and v.ok
    drive.params.write(0x1194, 2, ram=False, rom=True)            # something wrote the motor type
    v = verify(PVL, {1: drive}, opts, before=before, stopped_before_writes={1: "check"})
    same = v.checks[0]
    assert same.what == "drive unchanged" and not same.ok and same.differences == ["1194h: ROM/RAM (0, 0) before, (2, 0) after"]
    assert "yet the drive changed" in same.note
    assert {"parameters ROM", "curves RAM", "command table RAM"} <= {c.what for c in v.checks}


def _mutate_answer(node: int, index: int, sub: int, nth: int = 1):
    """prepare_bus: the drive's nth upload answer for (index, sub) reaches the PLC with its value changed."""
    seen = {"n": 0}

    def pred(f) -> bool:
        if (f.can_id == 0x580 + node and f.data[0] & 0xE0 == 0x40
                and f.data[1:4] == bytes([index & 0xFF, index >> 8, sub])):
            seen["n"] += 1
            return seen["n"] == nth
        return False

    def mutate(f):
        d = bytearray(f.data)
        d[6] ^= 0xFF
        return type(f)(can_id=f.can_id, data=bytes(d))

    return lambda bus, drives: bus.mutate_payload(pred, mutate, count=1)


READ_BACK_FAILURES = [
    # examples/two_axes.pvl has curves 1, 2, 23 and command-table entries 1, 2, 3: "1" alone is ambiguous
    pytest.param(0x2001, 0x86, "entry", 1, "command-table entry 1, 2-byte step 1", id="entry"),
    pytest.param(0x2001, 0x61, "curve", 1, "curve 1 'MinJerk_100mm_400ms', info word 1", id="curve"),
    pytest.param(0x3194, 0x02, "param", 0x1194, "UPID 1194h Motion Control SW\\Motor Configuration\\Motor Type",
                 id="parameter"),
]


@pytest.mark.parametrize("index, sub, kind, item, words", READ_BACK_FAILURES)
def test_a_read_back_failure_names_the_kind_of_item(index, sub, kind, item, words):
    """FailItem is a number; FailKind says whether it is a UPID, a curve or an entry (the PLC knows)."""
    o = commission(axes=1, prepare_bus=_mutate_answer(1, index, sub))
    ax = o.axis(1)
    assert ax.error and ax.error_id == 0x0603
    assert (ax.fail_phase, ax.fail_kind, ax.fail_item) == ("verify", kind, item)
    assert o.report.figures["axes"][0]["fail"]["kind"] == kind
    assert f"node 1: Failed in phase verify (read back), {words}: ErrorID 16#0603" in o.report.text()


def test_a_changed_setpoint_in_the_read_back_is_shown(tmp_path):
    """The 10th (last) setpoint answer of curve 23 reaches the PLC changed: the FB fails there, and the
    report and the plot (its data) say that 1 setpoint of the read-back differs."""
    o = commission(axes=1, prepare_bus=_mutate_answer(1, 0x2017, 0x62, nth=10))
    ax = o.axis(1)
    assert (ax.error_id, ax.fail_kind, ax.fail_item, ax.fail_step) == (0x0603, "curve", 23, 19 + 9)
    curve = next(c for c in o.report.figures["curves"] if c["curve"] == 23)
    assert curve["nodes"] == [dict(node=1, written=True, read_back=10, source="bus", differ=1,
                                   verdict="1 setpoint(s) differ")]
    text = o.report.text()
    assert "curve 23 'Example_Curve', setpoint 9: ErrorID 16#0603" in text
    assert "curve 23 'Example_Curve', 10 setpoints: node 1 1 setpoint(s) differ" in text
    # the drive holds the right curve: only the answer on the bus was changed
    assert o.verification.ok
    files = o.report.write(tmp_path)
    assert "curve_23.png" in files["plots"]


def test_a_broken_dataset_header_fails_before_any_frame():
    o = commission(axes=1, prepare_plc=lambda plc: plc.__setitem__(f"{DS}[1]", 0x12345678))
    ax = o.axis(1)
    assert ax.error and ax.error_id == 0x0601 and (ax.fail_phase, ax.fail_step) == ("start", 1)
    assert ax.fail_kind == "dataset" and "dataset word 1" in o.report.text()
    assert ax.exchanges == 0 and not [e for e in o.result.trace if e.frame.can_id == 0x601]
    assert [(p.phase, p.scans) for p in ax.phases] == [("start", 1)]


def test_a_broken_record_fails_where_it_is():
    curve = WORDS.index(dsf.TAG_CURVE << 24 | 23 << 16 | 10) + 1      # 1-based index of curve 23's record
    o = commission(axes=1, prepare_plc=lambda plc: plc.__setitem__(f"{DS}[{curve}]", 0x07170000 | 10))
    ax = o.axis(1)
    assert ax.error and ax.error_id == 0x0601 and ax.fail_step == curve
    assert ax.fail_phase == "preflight"                             # found when the pre-flight walked the records
    assert downloads(o.result, 1) == [] or all(e.frame.data[3] == 0x20 for e in downloads(o.result, 1))
    untouched(o.result.drives[1])                                   # so nothing was written
    assert ax.fail_kind == "dataset" and f"dataset word {curve}" in o.report.text()
    assert "dataset malformed" in o.report.text()


class StubbornDrive(E1100Drive):
    """Confirms the stop of its MC software (35h) without stopping it: the save then finds it running."""

    def stop_mc(self):
        return 0


def test_a_failed_flash_save_starts_the_mc_again():
    o = commission(axes=1, drive_factory=lambda n: StubbornDrive(n, timings=DriveTimings.fast()))
    ax = o.axis(1)
    assert ax.error and ax.error_id == 0x04D7 and (ax.fail_phase, ax.fail_kind, ax.fail_item) == ("flash", "service", 0x40)
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
    with pytest.raises(SystemExit) as exit_:
        main(["commission", str(EXAMPLE), "--axes", "33"])
    assert exit_.value.code == 2
    assert "linmot-st commission: error: argument --axes: 33: must be 1..32" in capsys.readouterr().err
    assert main(["commission", str(EXAMPLE), "--axes", "2", "--node-ids", "3,3"]) == 2
    assert main(["commission", str(EXAMPLE), "--axes", "3", "--node-ids", "1,2"]) == 2
    assert main(["commission", str(EXAMPLE), "--no-emulate"]) == 2
    bad = tmp_path / "bad.pvl"
    bad.write_text("@FileType,PVL\n@FormatVersion,1\n@StartObject,Curve\n")
    assert main(["commission", str(bad)]) == 1
    assert "bad.pvl:" in capsys.readouterr().err


class Built(Exception):
    """Raised instead of building: the arguments were accepted."""


@pytest.fixture
def no_build(monkeypatch):
    """The command's build step raises Built: a refusal must come before it."""
    from linmot_st.jobs.commission import project

    def build(*a, **k):
        raise Built
    monkeypatch.setattr(project, "build_project", build)


SEED_CURVE = EXAMPLE.parent / "seed_curve.pvl"
SEED_PARAMS = EXAMPLE.parent / "seed_parameters.pvl"


@pytest.mark.parametrize("args, message", [
    (["--report", "/proc/nope"], "linmot-st commission: error: --report /proc/nope: cannot write in /proc"),
    (["--report", "/sys/kernel"], "error: --report /sys/kernel: cannot write in /sys/kernel"),
    (["--trace", "/proc/run.log"], "error: --trace /proc/run.log: cannot write in /proc"),
    (["--report", "no/such/folder"], "error: --report no/such/folder: folder no/such does not exist"),
    (["--bus", "foo"], "error: --bus 'foo': expected sim, virtual[:CHANNEL], or INTERFACE:CHANNEL"),
    (["--bus", "foo:bar"], "error: --bus 'foo:bar': python-can has no interface 'foo'"),
    (["--bus", "udp_multicast:x"], "not supported"),
    (["--trace", "run.txt"], "error: --trace run.txt: the extension says the format"),
    (["--no-flash"], "error: --no-flash with the reset (on by default)"),
    (["--no-flash", "--reset"], "Add --no-reset"),
], ids=["report", "report-sys", "trace-proc", "report-parents", "bus", "bus-interface", "udp", "trace", "no-flash",
        "no-flash-reset"])
def test_bad_arguments_are_refused_before_the_build(no_build, capsys, args, message):
    assert main(["commission", str(SEED_CURVE), "-q", *args]) == 2
    assert message in capsys.readouterr().err


@pytest.mark.parametrize("pvl, args", [
    (SEED_CURVE, ["--no-flash", "--no-reset"]),                     # RAM holds the curve until the next power cycle
    (SEED_PARAMS, ["--no-flash"]),                                  # nothing to lose in flash: the reset is fine
])
def test_no_flash_is_accepted_where_it_can_work(no_build, tmp_path, pvl, args):
    with pytest.raises(Built):
        main(["commission", str(pvl), "-q", "--report", str(tmp_path / "folder"), *args])
    assert list(tmp_path.iterdir()) == []                           # checked, created only when written


def test_no_flash_without_reset_commissions_a_curve(capsys):
    """The combination the command accepts does work: the curve is written to RAM and read back (and the
    report counts in the singular)."""
    assert main(["commission", str(SEED_CURVE), "-q", "--drive-timings", "fast", "--no-flash", "--no-reset"]) == 0
    out = capsys.readouterr().out
    assert "  dataset: 0 layers, 0 parameters, 1 curve (10 setpoints), 0 command-table entries = 35 words" in out
    assert "curve 23 'Example_Curve', 10 setpoints: node 1 read back = written" in out
    assert "result: PASSED (1 axis commissioned and verified)" in out


def test_a_report_folder_that_cannot_be_written_after_the_run(tmp_path, capsys):
    """The result is printed first; the failed write is an error message and exit status 1, no traceback."""
    report = tmp_path / "r"
    (report / "report.json").mkdir(parents=True)                    # a folder where the file must go
    assert main(["commission", str(EXAMPLE), "-q", "--drive-timings", "fast", "--report", str(report)]) == 1
    out = capsys.readouterr()
    assert "result: PASSED (1 axis commissioned and verified)" in out.out
    assert f"error: --report {report}: Is a directory" in out.err


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
    # the pre-flight skips the curve record (19 + 5000 words): the program's Ds[DataIndex] faults there,
    # after the layer reads and the 4 pre-flight exchanges per parameter
    assert o.axis(1).exchanges == 6 + 4 * 30
