"""Verification from the emulated drives' own state, independent of the PLC (its VERIFY phase reads back
over the bus; this reads the emulator's memory).

For each drive: the ROM of every PVL parameter (as the drive keeps it: the bits of its type, signed
types sign-extended); RAM where it must already hold the value (after a reset, or a live parameter written
RAM+ROM), and otherwise RAM as information (it takes the ROM value at the next firmware start); the
curves and the command table in RAM, and in flash when the flash save was asked. A PVL without curves (or
without command-table entries) leaves that part of the drive as it was, so it is not compared.
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
    skipped: str = ""            # why nothing was verified (real drives)

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


def _params(pvl, drive, node: int, opts) -> list[Check]:
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
            if d.ram == expected:
                ram.equal += 1
            elif must:
                ram.required = True
                _add(ram, f"{p.upid:04X}h {p.caption}: RAM {d.ram}, PVL {expected}")
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


def verify(pvl, drives: dict, opts) -> Verification:
    """Compare each emulated drive with the PVL content (see the module docstring)."""
    v = Verification()
    if not drives:
        v.skipped = "real drives: verified only by the PLC's own VERIFY phase"
        return v
    curves = {c.curve_id: (c.info_block, list(c.setpoints)) for c in pvl.curves}
    entries = {e.entry_id: e.data for e in pvl.command_table}
    has_params = any(obj.parameters for obj in pvl.parameter_objects)
    for node, drive in sorted(drives.items()):
        if has_params:
            v.checks += _params(pvl, drive, node, opts)
        stores = [("RAM", True)] + ([("flash", True)] if opts.flash else [])
        if curves:
            for name, _ in stores:
                have = drive.curves.ram if name == "RAM" else drive.curves.flash
                actual = {cid: (c.info, c.setpoints) for cid, c in have.items()}
                v.checks.append(_blocks(node, f"curves {name}", curves, actual, lambda k: f"curve {k}"))
        if entries:
            for name, _ in stores:
                have = drive.ct.ram if name == "RAM" else drive.ct.flash
                v.checks.append(_blocks(node, f"command table {name}", entries, dict(have),
                                        lambda k: f"entry {k}"))
    return v
