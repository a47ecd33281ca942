"""Verification from the emulated drives' own state, independent of the PLC (its VERIFY phase reads back
over the bus; this reads the emulator's memory).

For each drive: the ROM of every PVL parameter (as the drive keeps it: the bits of its type, signed
types sign-extended); RAM where it must already hold the value (after a reset, or a live parameter written
RAM+ROM), and otherwise RAM as information (it takes the ROM value at the next firmware start); the
curves and the command table in RAM, and in flash when the flash save was asked. A PVL without curves (or
without command-table entries) leaves that part of the drive as it was, so it is not compared.

A drive whose run stopped in the compatibility check must hold what it held when it was switched on: the
FB writes nothing before every layer passed. Then that is what is checked (`drive_state` before and after),
and the report says "nothing written" instead of listing every PVL item the drive does not have; if the
drive did change, the full comparison is made as well.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class Check:
    node: int
    what: str                    # "parameters ROM", "parameters RAM", "curves RAM", ...
    checked: int = 0
    equal: int = 0
    required: bool = True        # False: shown, never a failure
    differences: list[str] = field(default_factory=list)
    note: str = ""

    @property
    def ok(self) -> bool:
        return not self.required or not self.differences


@dataclass
class Verification:
    checks: list[Check] = field(default_factory=list)
    skipped: str = ""            # why nothing was verified (real drives and --no-verify)
    by_plc: str = ""             # real drives: only the PLC's VERIFY phase checked them (its read-back)

    @property
    def ok(self) -> bool:
        return not self.skipped and all(c.ok for c in self.checks)

    def for_node(self, node: int) -> list[Check]:
        return [c for c in self.checks if c.node == node]

    def node_ok(self, node: int) -> bool:
        return all(c.ok for c in self.for_node(node))


MAX_LINES = 12                   # differences listed per check (the count is always complete)


def _add(check: Check, line: str) -> None:
    if len(check.differences) < MAX_LINES:
        check.differences.append(line)
    elif len(check.differences) == MAX_LINES:
        check.differences.append("...")


def _params(pvl, drive, node: int, opts, ram_at: dict | None = None) -> list[Check]:
    """ROM and RAM of each PVL parameter on the drive; RAM as `ram_at` {UPID: RAM} has it where given (the
    state when the commissioning ended, before a motion job's live writes)."""
    ram_at = ram_at or {}
    rom = Check(node, "parameters ROM")
    ram = Check(node, "parameters RAM", required=False)
    pending = 0
    for obj in pvl.parameter_objects:
        for p in obj.parameters:
            rom.checked += 1
            ram.checked += 1
            if p.upid not in drive.params:
                _add(rom, f"{p.upid:04X}h {p.caption}: no such UPID on the drive")
                continue
            d = drive.params[p.upid]
            expected = d.type.from_raw(p.value)
            if d.rom == expected:
                rom.equal += 1
            else:
                _add(rom, f"{p.upid:04X}h {p.caption}: ROM {d.rom}, PVL {expected} ({p.value:08X}h)")
            must = opts.reset or (opts.live_ram and d.live)
            ram_value = ram_at.get(p.upid, d.ram)
            if ram_value == expected:
                ram.equal += 1
            elif must:
                ram.required = True
                _add(ram, f"{p.upid:04X}h {p.caption}: RAM {ram_value}, PVL {expected}")
            else:
                pending += 1
    if pending:
        ram.note = (f"{pending} RAM value(s) still differ: they take the ROM value at the next firmware start "
                    "(--reset)")
    if opts.reset or opts.live_ram:
        ram.required = True
        if not opts.reset:
            ram.note = (ram.note + "; " if ram.note else "") + "checked for live parameters (written RAM+ROM)"
    return [rom, ram]


def _blocks(node: int, what: str, expected: dict, actual: dict, describe) -> Check:
    c = Check(node, what, checked=len(expected))
    for key in sorted(set(expected) | set(actual)):
        if key not in actual:
            _add(c, f"{describe(key)}: missing on the drive")
        elif key not in expected:
            _add(c, f"{describe(key)}: on the drive, not in the PVL (should have been deleted)")
        elif actual[key] == expected[key]:
            c.equal += 1
        else:
            _add(c, f"{describe(key)}: {_first_difference(expected[key], actual[key])}")
    return c


def _first_difference(exp, act) -> str:
    if isinstance(exp, tuple):            # curve: (info, setpoints)
        (ei, es), (ai, as_) = exp, act
        if ei != ai:
            k = next(i for i in range(min(len(ei), len(ai))) if ei[i] != ai[i]) if len(ei) == len(ai) else 0
            return f"info block differs from byte {k}"
        if len(es) != len(as_):
            return f"{len(as_)} setpoints, PVL {len(es)}"
        bad = [i for i in range(len(es)) if es[i] != as_[i]]
        return f"{len(bad)} setpoint(s) differ, first: #{bad[0]} is {as_[bad[0]]}, PVL {es[bad[0]]}"
    k = next((i for i in range(min(len(exp), len(act))) if exp[i] != act[i]), min(len(exp), len(act)))
    return f"block differs from byte {k} ({act[k:k + 1].hex() or '-'} vs {exp[k:k + 1].hex() or '-'})"


def drive_state(drive) -> dict:
    """What commissioning can change in an emulated drive: every parameter's ROM and RAM, the curves and the
    command table in RAM and flash, the blocks being written (compared before and after a run)."""
    return dict(params={p.upid: (p.rom, p.ram) for p in drive.params if p.kind == "par"},
                curves_ram=dict(drive.curves.ram), curves_flash=dict(drive.curves.flash),
                curves_in_progress=drive.curves.in_progress(),
                ct_ram=dict(drive.ct.ram), ct_flash=dict(drive.ct.flash))


def state_changes(before: dict, after: dict) -> list[str]:
    """What differs between two drive_state()s, in words."""
    out = []
    for upid in sorted(set(before["params"]) | set(after["params"])):
        b, a = before["params"].get(upid), after["params"].get(upid)
        if b != a:
            out.append(f"{upid:04X}h: ROM/RAM {b} before, {a} after")
    names = {"curves_ram": "curves RAM", "curves_flash": "curves flash", "ct_ram": "command table RAM",
             "ct_flash": "command table flash"}
    for key, name in names.items():
        b, a = before[key], after[key]
        for k in sorted(set(b) | set(a)):
            if b.get(k) != a.get(k):
                out.append(f"{name} {k}: " + ("added" if k not in b else "deleted" if k not in a else "changed"))
    if before["curves_in_progress"] != after["curves_in_progress"]:
        out.append(f"curves being written: {after['curves_in_progress']}")
    return out


def _unchanged(node: int, before: dict, after: dict) -> Check:
    changes = state_changes(before, after)
    size = lambda s: len(s["params"]) + sum(len(s[k]) for k in ("curves_ram", "curves_flash", "ct_ram", "ct_flash"))  # noqa: E731
    c = Check(node, "drive unchanged", checked=size(before), equal=size(before) - len(changes))
    for line in changes:
        _add(c, line)
    return c


# the phases before the first write: a run that fails in them must leave the drive as it was
BEFORE_WRITES = {"wait": "while waiting for the drive", "start": "in the dataset header",
                 "check": "in the compatibility check", "preflight": "in the pre-flight check"}


def verify(pvl, drives: dict, opts, *, before: dict | None = None, stopped_before_writes: dict[int, str] | None = None,
           ram_at: dict | None = None) -> Verification:
    """Compare each emulated drive with the PVL content (see the module docstring). `before`: drive_state()
    of each node when it was switched on; `stopped_before_writes`: node -> phase (BEFORE_WRITES) of the nodes
    whose FB failed before its first write (nothing may have been written to them)."""
    stopped_before_writes = stopped_before_writes or {}
    v = Verification()
    if not drives:
        # real drives: an axis is done only after its VERIFY phase read every item back and found it equal
        if opts.verify:
            v.by_plc = ("real drives: checked by the PLC's VERIFY phase, which read every item back; "
                        "their memory is not inspected here")
        else:
            v.skipped = "real drives and --no-verify: nothing read back"
        return v
    curves = {c.curve_id: (c.info_block, list(c.setpoints)) for c in pvl.curves}
    entries = {e.entry_id: e.data for e in pvl.command_table}
    has_params = any(obj.parameters for obj in pvl.parameter_objects)
    for node, drive in sorted(drives.items()):
        if node in stopped_before_writes and before and node in before:
            where = BEFORE_WRITES[stopped_before_writes[node]]
            same = _unchanged(node, before[node], drive_state(drive))
            v.checks.append(same)
            if same.ok:
                same.note = f"nothing written (as intended: the run stopped {where})"
                continue
            same.note = f"the run stopped {where}, yet the drive changed"
        if has_params:
            v.checks += _params(pvl, drive, node, opts, (ram_at or {}).get(node))
        stores = ["RAM", "flash"] if opts.flash else ["RAM"]
        if curves:
            for name in stores:
                have = drive.curves.ram if name == "RAM" else drive.curves.flash
                actual = {cid: (c.info, c.setpoints) for cid, c in have.items()}
                v.checks.append(_blocks(node, f"curves {name}", curves, actual, lambda k: f"curve {k}"))
        if entries:
            for name in stores:
                have = drive.ct.ram if name == "RAM" else drive.ct.flash
                v.checks.append(_blocks(node, f"command table {name}", entries, dict(have),
                                        lambda k: f"entry {k}"))
    return v


def verify_run(pvl, result) -> Verification:
    """verify() for a runner.RunResult: its emulated drives, their state when switched on, and the axes whose
    FB stopped before its first write."""
    opts = result.options
    early = [a for a in result.axes if a.error and a.fail_phase in BEFORE_WRITES]
    others = {a.node_id for a in result.axes if a not in early}      # another axis on the node may write
    stopped = {a.node_id: a.fail_phase for a in early if a.node_id not in others}
    drives = result.drives if opts.emulate else {}
    ram_at = getattr(result, "ram_commissioned", None)
    datasets = getattr(result, "datasets", None)
    if datasets is None or datasets.single or not drives:
        return verify(pvl, drives, opts, before=result.before, stopped_before_writes=stopped, ram_at=ram_at)
    # per-node datasets: each drive against its own PVL file
    out = Verification()
    for source in datasets.sources:
        mine = {n: d for n, d in drives.items() if datasets.of(n) is source}
        if mine:
            out.checks += verify(source.pvl, mine, opts, before=result.before, stopped_before_writes=stopped,
                                 ram_at=ram_at).checks
    out.checks.sort(key=lambda c: c.node)
    return out
