"""A scope of PLC variables and of the emulated drives' signals, recorded per scan in virtual time.

    scope = rig.scope("MAIN.STATION.STATE", "MAIN.STATION.READY", drives=True)   # every scan from now on
    ...
    scope.write("build/scope", "my_test")      # PNG (one panel per signal), VCD (GTKWave...), CSV

The pytest plugin writes the files of every scope of a failed test and names them in its failure report
(plctest/scope_plugin.py). Signals of a drive are `driveN.position` (mm), `driveN.velocity` (mm/s),
`driveN.state` (the MC state by name), `driveN.status_word` and `driveN.nmt` (NMT state by name);
`drives=True` adds position, velocity and state of every drive of the rig.
"""

from __future__ import annotations

import csv
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from linmot_st.emulator import E1100Drive
    from linmot_st.plc import Plc

DRIVE_SIGNALS = ("position", "velocity", "state", "status_word", "nmt")
DRIVE_DEFAULT = ("position", "velocity", "state")
PU_PER_MM = 10_000                  # the emulator's position unit is 0.1 um (emulator/linmot/motion/settings.py)
_REAL_TYPES = {"REAL", "LREAL"}
_INT_BITS = {"SINT": 8, "USINT": 8, "BYTE": 8, "INT": 16, "UINT": 16, "WORD": 16, "DINT": 32, "UDINT": 32,
             "DWORD": 32, "LINT": 64, "ULINT": 64, "LWORD": 64, "TIME": 64, "DATE": 64, "TOD": 64, "DT": 64}


@dataclass
class Signal:
    """One recorded signal: its name, how to read it now, its kind (BOOL, INT, REAL or ENUM: values by name)."""
    name: str
    read: Callable[[], Any]
    kind: str
    bits: int = 64                    # INT: the width of its IEC type (the VCD variable's size)
    unit: str = ""
    names: tuple = ()                 # ENUM: the type's value names, in order


@dataclass
class Scope:
    """Samples of signals at PLC scans (every `every`-th scan), time in ns of PLC time."""
    rig: Any
    signals: list[Signal]
    every: int = 1
    write_always: bool = False        # write the files after the test even when it passes
    observe: bool = True              # bring simulated drives to the PLC's time (not on a real-time bus)
    times_ns: list[int] = field(default_factory=list)
    scans: list[int] = field(default_factory=list)
    rows: list[tuple] = field(default_factory=list)

    def sample(self) -> None:
        plc = self.rig.plc
        if plc.scan_count % self.every:
            return
        t = plc.time_ns
        if self.observe:
            # the drives' state as of the bus's time (the start of the scan just run): not later, for a
            # frame still on its way to a drive must find it where it was (a drive brought ahead of the bus
            # would take it in late)
            now = self.rig.bus.now
            for drive in self.rig.drives.values():
                _observe(drive, now)
        self.times_ns.append(t)
        self.scans.append(plc.scan_count)
        self.rows.append(tuple(s.read() for s in self.signals))

    def column(self, name: str) -> list:
        i = [s.name for s in self.signals].index(name)
        return [r[i] for r in self.rows]

    # -- files ---------------------------------------------------------------------------------------------
    def write(self, folder: str | Path, stem: str, mark: tuple[int, int] | None = None) -> dict[str, Path]:
        """The PNG, VCD and CSV files of the samples (`mark`: (time_ns, scan) marked on the plot as the
        failing scan); returns {"png": path, "vcd": path, "csv": path}."""
        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        base = folder / re.sub(r"[^\w.\-\[\]]+", "_", stem)
        files = {"png": base.with_name(base.name + ".png"), "vcd": base.with_name(base.name + ".vcd"),
                 "csv": base.with_name(base.name + ".csv")}
        self.write_csv(files["csv"])
        self.write_vcd(files["vcd"])
        self.write_png(files["png"], mark)
        return files

    def write_csv(self, path: Path) -> None:
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["time_ms", "scan", *(f"{s.name} [{s.unit}]" if s.unit else s.name for s in self.signals)])
            for t, scan, row in zip(self.times_ns, self.scans, self.rows):
                w.writerow([f"{t / 1e6:.6f}", scan, *row])

    def write_vcd(self, path: Path) -> None:
        from vcd import VCDWriter
        with open(path, "w") as f, VCDWriter(f, timescale="1 ns", date="PLC time (virtual)",
                                             comment="linmot-st scope") as w:
            handles = [self._register(w, s) for s in self.signals]
            for t, row in zip(self.times_ns, self.rows):
                for h, s, v in zip(handles, self.signals, row):
                    w.change(h, t, _vcd_value(s, v))

    @staticmethod
    def _register(w, s: Signal):
        scope, _, name = re.sub(r"[\[\]]", "_", s.name).rpartition(".")
        scope = scope or "top"
        if s.kind == "BOOL":
            return w.register_var(scope, name, "wire", size=1)
        if s.kind == "INT":
            return w.register_var(scope, name, "integer", size=s.bits)
        if s.kind == "REAL":
            return w.register_var(scope, name, "real")
        return w.register_var(scope, name, "string")

    def write_png(self, path: Path, mark: tuple[int, int] | None = None) -> None:
        import matplotlib
        matplotlib.use("Agg")
        from matplotlib.figure import Figure

        n = max(1, len(self.signals))
        fig = Figure(figsize=(10, 1.2 + 1.5 * n))
        axes = fig.subplots(n, 1, sharex=True, squeeze=False)[:, 0]
        t_ms = [t / 1e6 for t in self.times_ns]
        for ax, s in zip(axes, self.signals):
            ys = [r[self.signals.index(s)] for r in self.rows]
            label = f"{s.name} [{s.unit}]" if s.unit else s.name
            if s.kind == "REAL":
                ax.plot(t_ms, ys, lw=1)
            else:
                values, ticks = _step_values(s, ys)
                ax.step(t_ms, values, where="post", lw=1)
                if ticks:
                    ax.set_yticks(list(ticks.values()), list(ticks.keys()), fontsize=7)
            ax.set_ylabel(label, rotation=0, ha="right", va="center", fontsize=8)
            ax.grid(True, alpha=0.3)
            if mark is not None:
                ax.axvline(mark[0] / 1e6, color="red", lw=1, ls="--")
        axes[-1].set_xlabel("PLC time [ms]")
        title = f"linmot-st scope: {len(self.rows)} samples, every {self.every} scan(s)"
        if mark is not None:
            title += f"; red: scan {mark[1]} at {mark[0] / 1e6:g} ms, where the test failed"
        fig.suptitle(title, fontsize=9)
        fig.tight_layout()
        fig.savefig(path, dpi=80)


def _step_values(s: Signal, ys: list) -> tuple[list, dict]:
    """Values to draw as steps, and the y ticks that name them (BOOL: FALSE/TRUE, ENUM: the names seen)."""
    if s.kind == "BOOL":
        return [int(bool(y)) for y in ys], {"FALSE": 0, "TRUE": 1}
    if s.kind == "ENUM":
        order = {n: i for i, n in enumerate(s.names)}
        index = [order.get(y, y if isinstance(y, int) else -1) for y in ys]
        seen = sorted({(order.get(y, -1), str(y)) for y in ys})
        return index, {name: i for i, name in seen}
    return ys, {}


def _vcd_value(s: Signal, v: Any) -> Any:
    if s.kind == "BOOL":
        return bool(v)
    if s.kind == "INT":
        return int(v) & ((1 << s.bits) - 1)           # the bit pattern (two's complement) of the IEC type
    if s.kind == "REAL":
        return float(v)
    return re.sub(r"\s+", "_", str(v))


def _observe(drive: E1100Drive, t: int) -> None:
    mc = getattr(drive, "mc", None)
    if mc is not None and mc.running:
        mc.observe(t)                                  # t <= the bus time: nothing changes what happens later


# ---- signals -------------------------------------------------------------------------------------------------

def plc_signal(plc: Plc, path: str) -> Signal:
    """A PLC variable as a signal (an unknown path fails here, before any scan)."""
    var = plc.var(path)
    get = lambda: var.value  # noqa: E731 - the bound accessor: no lookup per scan
    vtype = str(var.type).upper()
    names = tuple(getattr(var, "_names", ()) or ())
    if names:
        return Signal(path, get, "ENUM", names=names)
    if vtype == "BOOL":
        return Signal(path, get, "BOOL")
    if vtype in _INT_BITS:
        return Signal(path, get, "INT", bits=_INT_BITS[vtype], unit="ns" if vtype == "TIME" else "")
    if vtype in _REAL_TYPES:
        return Signal(path, get, "REAL")
    raise TypeError(f"{path} is {var.type}: the scope records BOOL, integers, REAL, TIME and enums "
                    "(name the members of a struct or FB one by one)")


def drive_signal(rig: Any, name: str) -> Signal:
    """`driveN.position|velocity|state|status_word|nmt` of one of the rig's emulated drives."""
    m = re.fullmatch(r"drive(\d+)\.(\w+)", name, re.I)
    if not m or m[2].lower() not in DRIVE_SIGNALS:
        raise ValueError(f"{name}: a drive signal is driveN.<{'|'.join(DRIVE_SIGNALS)}>")
    node, what = int(m[1]), m[2].lower()
    if node not in rig.drives:
        raise ValueError(f"{name}: the rig has drives {sorted(rig.drives)}")
    drive = rig.drives[node]
    if what == "position":
        return Signal(name, lambda: drive.mc.axis.position / PU_PER_MM, "REAL", unit="mm")
    if what == "velocity":
        return Signal(name, lambda: drive.mc.axis.velocity / PU_PER_MM, "REAL", unit="mm/s")
    if what == "status_word":
        return Signal(name, lambda: drive.mc.words[0], "INT", bits=16)
    if what == "state":
        from linmot_st.protocol.words import STATE_NAMES
        names = tuple(STATE_NAMES[k] for k in sorted(STATE_NAMES))
        return Signal(name, lambda: STATE_NAMES.get(drive.mc.state, drive.mc.state), "ENUM", names=names)
    from linmot_st.emulator import BOOTING, OFF, OPERATIONAL, PRE_OPERATIONAL, STOPPED
    return Signal(name, lambda: drive.nmt_state, "ENUM",
                  names=(OFF, BOOTING, PRE_OPERATIONAL, OPERATIONAL, STOPPED))


def signals_of(rig: Any, paths: tuple | list, drives: bool = False) -> list[Signal]:
    out = [drive_signal(rig, p) if re.match(r"drive\d+\.", p, re.I) else plc_signal(rig.plc, p) for p in paths]
    if drives:
        have = {s.name.lower() for s in out}
        out += [drive_signal(rig, f"drive{n}.{w}") for n in rig.drives for w in DRIVE_DEFAULT
                if f"drive{n}.{w}" not in have]
    return out


# ---- the scopes of the running test (the pytest plugin collects them) ------------------------------------------

ACTIVE: list[Scope] | None = None      # a list while the plugin runs a test, else None (nothing kept)
DEFAULTS: dict | None = None           # the ini options / marker of the running test: paths, every, drives


def register(scope: Scope) -> Scope:
    if ACTIVE is not None:
        ACTIVE.append(scope)
    return scope
