"""Re-commissioning (FB_LmCommission with Force FALSE, the default of `linmot-st commission`): the PLC reads
what the drive holds and writes only what differs; no flash save and no reset when nothing does
(docs/commissioning.md, "Re-commissioning")."""

from __future__ import annotations

import json

from linmot_st.cli import main
from linmot_st.emulator import DriveTimings, E1100Drive
from linmot_st.emulator.linmot.curves import Curve
from linmot_st.jobs.commission.testing import EXAMPLE, commission, example
from linmot_st.protocol.errors import BY_NAME
from linmot_st.pvl.dataset import INFO_WORDS, from_pvl

DS = from_pvl(example())
ITEMS = len(DS.params) + len(DS.curves) + len(DS.entries)


class Drives:
    """One emulated drive kept from run to run (each run switches it on again: RAM = ROM / flash)."""

    def __init__(self, cls=E1100Drive) -> None:
        self.drive = cls(1, timings=DriveTimings.fast())

    def __call__(self, node: int):
        assert node == 1
        return self.drive


def run(drives: Drives, **kw):
    kw.setdefault("force", False)
    kw.setdefault("reset", True)                # as the command: a reset wherever one is needed
    o = commission(axes=1, drive_factory=drives, **kw)
    assert o.axis(1).done and o.verification.ok, o.report.text()
    return o


def items(o) -> tuple[int, int, int]:
    a = o.axis(1)
    return a.written, a.skipped, a.verified


def phases(o) -> list[str]:
    return [p.phase for p in o.axis(1).phases]


def requests(o, sub: int) -> list[bytes]:
    """The PLC's SDO requests to node 1 with this manufacturer sub-index."""
    return [bytes(e.frame.data) for e in o.result.trace if e.frame.can_id == 0x601 and e.frame.data[3] == sub]


def compare_exchanges() -> int:
    """What COMPARE reads on a drive that holds the dataset: every record as the verify pass reads it, 60h on
    each curve ID the dataset lacks, the 8 entry lists."""
    records = len(DS.params) + sum(1 + INFO_WORDS + len(p) for _, _, p in DS.curves) + 33 * len(DS.entries)
    return 3 * len(DS.layers) + records + (100 - len(DS.curves)) + 8


def commissioned() -> Drives:
    drives = Drives()
    run(drives)
    return drives


def test_a_second_run_writes_nothing_and_takes_no_flash_cycle():
    drives = Drives()
    new = drives.drive.params
    fresh_defaults = sum(new[u].d.type.from_raw(v) == new[u].d.default for u, v in DS.params)   # rows a new
    assert 0 < fresh_defaults < len(DS.params)                       # drive holds already: not written
    first = run(drives)
    assert items(first) == (ITEMS - fresh_defaults, fresh_defaults, ITEMS)
    assert first.result.wear(1) == dict(flash_curves=1, flash_ct=1, rom_writes=len(DS.params) - fresh_defaults)
    second = run(drives)
    assert items(second) == (0, ITEMS, ITEMS)
    assert second.result.wear(1) == dict(flash_curves=0, flash_ct=0, rom_writes=0)
    assert phases(second) == ["start", "check", "compare"]           # no write, flash, reset or second read
    assert second.axis(1).exchanges == compare_exchanges()
    assert "items: 0 written, 36 skipped (the drive held them), 36 verified; drive: 0 flash save(s)" in second.report.text()
    # its time against the full write's read-back alone (make bench prints it): <= 1.2 x
    full = run(drives, force=True)
    verify = next(p for p in full.axis(1).phases if p.phase == "verify")
    run2 = second.axis(1)
    assert (run2.ended_ns - run2.started_ns) <= 1.2 * verify.duration_ns


def test_one_parameter_changed_on_the_drive_is_the_one_written_then_reset():
    drives = commissioned()
    d = drives.drive
    upid, raw = next((u, v) for u, v in DS.params if d.params[u].d.type.from_raw(v) != d.params[u].d.default)
    p = d.params[upid]
    p.rom = p.ram = p.d.default                               # as if set back on the drive
    o = run(drives)
    assert items(o) == (1, ITEMS - 1, ITEMS)
    assert o.result.wear(1) == dict(flash_curves=0, flash_ct=0, rom_writes=1)
    assert phases(o) == ["start", "check", "compare", "preflight", "params", "reset", "verify"]
    assert next(p for p in o.axis(1).phases if p.phase == "verify").exchanges == 1
    assert p.rom == p.ram == p.d.type.from_raw(raw)


def test_one_curve_setpoint_changed_rewrites_the_curves_and_saves_only_them():
    drives = commissioned()
    d = drives.drive
    cid = DS.curves[-1][0]
    data = bytearray(d.curves.ram[cid].data)
    data[4 * 7] ^= 0x01                                        # setpoint 7
    changed = Curve(cid, d.curves.ram[cid].info, bytes(data))
    d.curves.ram[cid] = d.curves.flash[cid] = changed
    o = run(drives)
    # the E1100 has no single-curve delete over CANopen: all of the dataset's curves are written again
    assert items(o) == (len(DS.curves), ITEMS - len(DS.curves), ITEMS)
    assert o.result.wear(1) == dict(flash_curves=1, flash_ct=0, rom_writes=0)
    assert phases(o) == ["start", "check", "compare", "preflight", "curves", "flash", "verify"]   # RAM items: no reset
    assert len(requests(o, 0x41)) == 1 and not requests(o, 0x80) and not requests(o, 0x81)


def test_one_entry_changed_is_the_one_written_and_saved():
    drives = commissioned()
    d = drives.drive
    eid = DS.entries[-1][0]
    block = bytearray(d.ct.ram[eid])
    block[20] ^= 0x01
    d.ct.ram[eid] = d.ct.flash[eid] = bytes(block)
    o = run(drives)
    assert items(o) == (1, ITEMS - 1, ITEMS)
    assert o.result.wear(1) == dict(flash_curves=0, flash_ct=1, rom_writes=0)
    assert phases(o) == ["start", "check", "compare", "ct", "flash", "verify"]     # no parameter: no pre-flight
    assert [r[1] for r in requests(o, 0x82)] == [eid] and not requests(o, 0x81) and not requests(o, 0x40)


def test_a_curve_or_entry_the_dataset_lacks_replaces_that_store():
    drives = commissioned()
    d = drives.drive
    cid, info, _ = DS.curves[0]
    extra_curve = max(c for c, _, _ in DS.curves) + 1
    d.curves.ram[extra_curve] = d.curves.flash[extra_curve] = Curve(extra_curve, d.curves.ram[cid].info,
                                                                    d.curves.ram[cid].data)
    extra_entry = max(e for e, _ in DS.entries) + 1
    d.ct.ram[extra_entry] = d.ct.flash[extra_entry] = d.ct.ram[DS.entries[0][0]]
    o = run(drives)
    assert items(o) == (len(DS.curves) + len(DS.entries), len(DS.params), ITEMS)
    assert extra_curve not in d.curves.ram and extra_curve not in d.curves.flash
    assert extra_entry not in d.ct.ram and extra_entry not in d.ct.flash
    assert len(requests(o, 0x41)) == 1 and len(requests(o, 0x81)) == 1


def test_force_writes_everything():
    drives = commissioned()
    o = run(drives, force=True)
    assert items(o) == (ITEMS, 0, ITEMS)
    assert o.result.wear(1) == dict(flash_curves=1, flash_ct=1, rom_writes=len(DS.params))
    assert "compare" not in phases(o)


class RefusesTheFirstSave(E1100Drive):
    """Confirms its first MC stop without stopping: that flash save is refused (D7h)."""
    refused = False

    def stop_mc(self):
        if not self.refused:
            self.refused = True
            return 0
        return super().stop_mc()


class Station:
    """plc_project and one drive on the simulated bus, kept over several runs (Start falls and rises: the
    same PLC, so the FB's memory of what an earlier run left unsaved is kept too)."""

    def __init__(self, drive) -> None:
        from linmot_st.bus import SimBus
        from linmot_st.cosim import CoSim
        from linmot_st.jobs.commission.project import INSTANCE, MAILBOX
        from linmot_st.jobs.commission.runner import RunOptions, _configure
        from linmot_st.jobs.commission.testing import project_build
        from linmot_st.plc import Plc

        self.plc, self.drive, self.main = Plc(project_build()), drive, INSTANCE
        bus = SimBus(500_000)
        bus.attach(drive, "drive1")
        drive.power_on(0)
        self.sim = CoSim(self.plc, bus, mailbox=MAILBOX)
        _configure(self.plc, RunOptions(axes=1, reset=False, timings="fast"), [1], drive.curves.capacity_bytes)
        self.plc[f"{INSTANCE}.START"] = False
        self.com = f"{INSTANCE}.A1.COM"

    def run(self, motion_enabled: bool = False, force: bool = False):
        """One run from a Start edge to Done or Error; with motion_enabled the axis counts as powered (as
        FB_LmPdo says while the drive runs a motion) in every scan."""
        plc = self.plc
        plc[f"{self.main}.A1.FORCE"] = force
        self.sim.step(2)
        plc[f"{self.main}.START"] = True

        def finished() -> bool:
            if motion_enabled:
                plc[f"{self.main}.A1.AX.MOTIONENABLED"] = True
            return bool(plc[f"{self.com}.ERROR"] or plc[f"{self.com}.DONE"])
        self.sim.run_until(finished, max_scans=60_000)
        plc[f"{self.main}.START"] = False
        return plc[self.com]


def test_a_save_that_failed_is_done_by_the_next_run_although_ram_matches():
    """RAM holds the dataset after a failed save, the flash does not: the FB remembers it (same PLC)."""
    st = Station(RefusesTheFirstSave(1, timings=DriveTimings.fast()))
    d = st.drive
    com = st.run()
    assert com["ERROR"] and com["ERRORID"] == 0x04D7 and d.curves.flash != d.curves.ram
    com = st.run()
    assert com["DONE"] and com["WRITTEN"] == 0 and com["SKIPPED"] == ITEMS
    assert d.curves.flash == d.curves.ram and d.ct.flash == d.ct.ram
    assert d.flash_cycles == {"curves": 1, "ct": 1}


def test_under_a_powered_axis_only_a_run_that_needs_no_save_or_reset_goes_on():
    from linmot_st.jobs.commission.verify import drive_state

    st = Station(E1100Drive(1, timings=DriveTimings.fast()))
    d = st.drive
    assert st.run()["DONE"]
    com = st.run(motion_enabled=True)                          # nothing differs: checked, nothing needed
    assert com["DONE"] and com["WRITTEN"] == 0
    cid = DS.curves[0][0]
    data = bytearray(d.curves.ram[cid].data)
    data[0] ^= 0x01
    d.curves.ram[cid] = Curve(cid, d.curves.ram[cid].info, bytes(data))
    before = drive_state(d)
    com = st.run(motion_enabled=True)                          # a curve differs: the save would stop the MC
    assert com["ERROR"] and com["ERRORID"] == BY_NAME["AxisEnabled"].value and com["FAILPHASE"] == "LM_COM_COMPARE"
    assert drive_state(d) == before                            # refused before any write
    com = st.run(motion_enabled=True, force=True)              # the full write is refused at the edge
    assert com["ERROR"] and com["ERRORID"] == BY_NAME["AxisEnabled"].value and com["EXCHANGES"] == 0


def test_the_command_re_commissions_drives_kept_in_a_folder(tmp_path, capsys):
    memory = tmp_path / "drives"
    args = ["commission", str(EXAMPLE), "--drive-memory", str(memory), "-q"]
    assert main(args) == 0
    first = capsys.readouterr().out
    assert (memory / "node1.json").exists() and "items: 0 written" not in first
    assert main(args) == 0
    second = capsys.readouterr().out
    assert "items: 0 written, 36 skipped (the drive held them), 36 verified; drive: 0 flash save(s) (curves 0, " \
           "command table 0), 0 ROM write(s)" in second
    assert "result: PASSED" in second and "compare (read drive)" in second and "flash save  " not in second
    dump = json.loads((memory / "node1.json").read_text())
    upid = f"{DS.params[0][0]:04X}"
    rom, ram = dump["params"][upid]
    dump["params"][upid] = [rom ^ 1, ram ^ 1]                   # one parameter changed on the drive
    (memory / "node1.json").write_text(json.dumps(dump))
    assert main(args) == 0
    third = capsys.readouterr().out
    assert "items: 1 written, 35 skipped (the drive held them), 36 verified; drive: 0 flash save(s) (curves 0, " \
           "command table 0), 1 ROM write(s)" in third
    assert main(args + ["--force"]) == 0
    forced = capsys.readouterr().out
    assert "--force" in forced.splitlines()[0].split() and "items: 36 written, 0 skipped" in forced
