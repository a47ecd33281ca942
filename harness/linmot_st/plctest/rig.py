"""A user's PLC co-simulated against emulated E1100 drives, with the helpers a PLC test needs.

    rig = Rig(build, nodes=(1, 2))                 # the PLC, a SimBus at 500 kbit/s, drives 1 and 2 switched on
    rig["MAIN.START"] = True                       # variables by IEC path (a unique suffix is enough)
    rig.step_until("MAIN.READY", ms=6000)          # or a callable; fails with the PLC time, watched variables
                                                   # and the last CAN frames
    rig.expect_done("MAIN.STATION.COM", ms=30_000) # an FB's Done (its Error fails the test, with the ErrorID)
    rig.inject_fault("drop", sender="drive1", count=3, when="MAIN.STATION.COM.PHASE = LM_COM_CURVES")

`RealTimeRig` is the same on a python-can bus (virtual, or socketcan:vcan0) in real time. docs/testing.md.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from .condition import Condition, ConditionError, condition  # noqa: F401 - re-exported: the rig's API

if TYPE_CHECKING:
    from linmot_st.plc import Plc
    from linmot_st.toolchain import BuildResult

MAILBOX = "CONFIG0.RES0.CAN0"
FRAMES_SHOWN = 12               # CAN frames in a failure message
FRAME_FAULTS = ("drop", "delay", "duplicate", "corrupt", "mutate_payload")
NODE_FAULTS = ("reset", "power_off")


class RigTimeout(AssertionError):
    """A condition did not hold within its scan or time budget (the message shows why)."""


class FbFailed(AssertionError):
    """An FB reported Error (or CommandAborted) where the test expected Done."""


# ---- conditions: plctest/condition.py (IEC text parsed, type-checked and compiled before any scan) ---------

# ---- FB results ------------------------------------------------------------------------------------

@dataclass
class FbResult:
    """How an FB run ended: its PLCopen outputs and the scans it took (from its Execute scan, inclusive)."""
    done: bool
    busy: bool
    error: bool
    error_id: int
    scans: int
    outputs: dict = field(default_factory=dict)
    aborted: bool = False

    def __getitem__(self, key: str) -> Any:
        return self.outputs[key.upper()]

    @property
    def error_name(self) -> str:
        from linmot_st.protocol.errors import name_of
        return name_of(self.error_id)


class FbHandle:
    """One PLCopen-style FB instance of the PLC (Execute -> Done/Busy/Error/ErrorID/CommandAborted)."""

    def __init__(self, rig: Rig, path: str):
        self.rig = rig
        self.path = path.upper()

    def __getitem__(self, member: str) -> Any:
        return self.rig.plc[f"{self.path}.{member}"]

    def __setitem__(self, member: str, value: Any) -> None:
        self.rig.plc[f"{self.path}.{member}"] = value

    def set(self, **inputs: Any) -> None:
        for k, v in inputs.items():
            self[k] = v

    def start(self, **inputs: Any) -> None:
        """Set the inputs and raise Execute (takes effect at the next scan)."""
        self.set(**inputs)
        self["EXECUTE"] = True

    def outputs(self) -> dict:
        return {k.upper(): v for k, v in self.rig.plc[self.path].items()}

    def finished(self) -> bool:
        return bool(self["DONE"] or self["ERROR"] or self._member("COMMANDABORTED"))

    def _member(self, name: str) -> Any:
        path = f"{self.path}.{name}"
        return self.rig.plc[path] if path in self.rig.plc else False

    def result(self, scans: int) -> FbResult:
        return FbResult(bool(self["DONE"]), bool(self["BUSY"]), bool(self["ERROR"]), int(self["ERRORID"]), scans,
                        self.outputs(), bool(self._member("COMMANDABORTED")))

    def run(self, scans: int | None = 20_000, ms: float | None = None, release: bool = True,
            **inputs: Any) -> FbResult:
        """Execute with these inputs, step until Done, Error or CommandAborted (RigTimeout after the
        budget), then (release) drop Execute and step once."""
        __tracebackhide__ = True
        self.start(**inputs)
        k = self.rig.step_until(self.finished, scans=None if ms is not None else scans, ms=ms,
                                what=f"{self.path} Done, Error or CommandAborted", watch=[f"{self.path}.BUSY"],
                                check_first=False)
        res = self.result(k)
        if release:
            self["EXECUTE"] = False
            self.rig.step(1)
        return res


# ---- the rig -------------------------------------------------------------------------------------------

@dataclass
class InjectedFault:
    """A fault waiting for its condition (`when`), then installed on the bus (`fault`, its `hits`)."""
    kind: str
    when: Condition | None
    install: Callable[[int], Any]
    installed_ns: int | None = None
    fault: Any = None                                     # the bus Fault of a frame fault, once installed

    @property
    def hits(self) -> list:
        return list(self.fault.hits) if self.fault is not None else []


def _timings(timings: Any):
    from linmot_st.emulator import DriveTimings
    if timings is None or timings == "real":
        return DriveTimings()
    if timings == "fast":
        return DriveTimings.fast()
    if isinstance(timings, DriveTimings):
        return timings
    raise ValueError(f"timings {timings!r}: expected 'real', 'fast' or a DriveTimings")


def frame_predicate(can_id: int | list[int] | tuple | set | None = None,
                    match: Callable | None = None) -> Callable:
    """Which frames a fault hits: an identifier (or several), a predicate on the Frame, or both."""
    ids = None if can_id is None else ({can_id} if isinstance(can_id, int) else set(can_id))
    return lambda f: (ids is None or f.can_id in ids) and (match is None or bool(match(f)))


def model_of(model: Any, node: int) -> Any:
    """The drive model of `node`: `model` itself, or from a dict {node ID: model} (a mixed bus; E1100 where
    a node is not named)."""
    return model.get(node, "E1100") if isinstance(model, dict) else model


class Rig:
    """The PLC of `build` on a SimBus with emulated drives (node IDs `nodes`), stepped in virtual time.

    model (the drives' model: a name of emulator/models.py's MODELS or a DriveModel, or a dict {node ID:
    model} for a mixed bus; default the E1100),
    bitrate, timings ('real', 'fast' or DriveTimings), protocol (ProtocolOptions), profile (DriveProfile),
    latency_ns (added to the drives' frames), drive_factory(node_id) -> node (replaces all of those),
    power_on (switch the drives on at t = 0), mailbox (the PLC's T_CanMailbox; None or absent: no bus
    coupling, the PLC runs alone), echo (the transmit confirmation of the co-simulation, linmot_st.cosim:
    None on where the mailbox has TxEcho, False for a CAN driver without one).
    """

    def __init__(self, build: BuildResult, *, nodes: tuple[int, ...] | list[int] = (1,), bitrate: int = 500_000,
                 timings: Any = "real", protocol: Any = None, profile: Any = None, latency_ns: int = 0,
                 drive_factory: Callable[[int], Any] | None = None, power_on: bool = True,
                 mailbox: str | None = MAILBOX, watch: list[str] | tuple = (), echo: bool | None = None,
                 model: Any = "E1100"):
        # the simulation stack loads when a rig is made: the pytest11 plugin imports plctest in every session
        from linmot_st.bus import SimBus
        from linmot_st.cosim import CoSim
        from linmot_st.emulator.models import make_drive
        from linmot_st.plc import Plc

        self.build = build
        self.plc = Plc(build)
        self.bus = SimBus(bitrate)
        self.drives: dict[int, Any] = {}
        for n in nodes:
            drive = drive_factory(n) if drive_factory else make_drive(
                model_of(model, n), n, profile=profile, timings=_timings(timings), protocol=protocol)
            self.bus.attach(drive, self.drive_name(n), latency_ns)
            if power_on:
                drive.power_on(0)
            self.drives[n] = drive
        self.sim = (CoSim(self.plc, self.bus, mailbox=mailbox, echo=echo)
                    if mailbox and mailbox in self.plc else None)
        self.watched: list[str] = list(watch)
        self.faults: list[InjectedFault] = []
        self._armed: list[InjectedFault] = []
        self.scopes: list = []
        self._default_scope()

    @staticmethod
    def drive_name(node_id: int) -> str:
        """The bus participant name of a drive (the `sender` of its frames)."""
        return f"drive{node_id}"

    @property
    def drive(self):
        """The first drive."""
        return next(iter(self.drives.values()))

    def io(self, node: int | None = None):
        """The I/O of a drive (the first by default): emulator/linmot/io.py's DriveIO (input, set_input,
        pulse_train, analog_ramp, output, outputs)."""
        return (self.drive if node is None else self.drives[node]).io

    def set_input(self, name: str, level: float, *, at_ms: float | None = None, node: int | None = None) -> None:
        """A drive input changes at at_ms (rig time; default now): a digital pin ("X4.6") to 0/1, or "X4.4" to
        volts."""
        drive = self.drive if node is None else self.drives[node]
        with drive.lock:                    # a drive served in real time runs in its own thread
            if self.bus is None:            # RealTimeRig: the drive's own clock
                if at_ms is not None:
                    raise ValueError("in real time an input changes now: at_ms is for the simulated bus")
                t = drive.clock_now_ns()
            else:
                t = self.bus.now if at_ms is None else round(at_ms * 1e6)
            t = max(t, drive.io.clock())
            if name == "X4.4":
                drive.io.set_analog(level, t)
            else:
                drive.io.set_input(name, int(level), t)

    # -- variables ---------------------------------------------------------------------------------------
    def __getitem__(self, path: str) -> Any:
        return self.plc[path]

    def __setitem__(self, path: str, value: Any) -> None:
        self.plc[path] = value

    def force(self, path: str, value: Any) -> None:
        """Force a variable: the PLC's own writes no longer change it, until unforce()."""
        self.plc.force(path, value)

    def unforce(self, path: str) -> None:
        self.plc.unforce(path)

    def watch(self, *paths: str) -> None:
        """Variables every failure message of this rig shows."""
        for p in paths:
            self.plc.var(p)                       # an unknown path fails now, not in the failure message
            if p not in self.watched:
                self.watched.append(p)

    def fb(self, path: str) -> FbHandle:
        return FbHandle(self, path)

    @property
    def time_ns(self) -> int:
        return self.plc.time_ns

    @property
    def time_ms(self) -> float:
        return self.plc.time_ns / 1e6

    # -- running -----------------------------------------------------------------------------------------
    def _step_n(self, n: int) -> None:
        if self.sim is not None:
            self.sim.step(n)
        else:
            self.plc.step(n)

    def step(self, n: int = 1) -> None:
        """Run n scans (scan by scan while a fault waits for its condition or a scope records)."""
        if not self._armed and not self.scopes:
            self._step_n(n)
            return
        for _ in range(n):
            self._arm()
            self._step_n(1)
            for s in self.scopes:
                s.sample()

    # -- scope -------------------------------------------------------------------------------------------
    def scope(self, *paths: str, every: int = 1, drives: bool = False, write: bool = False):
        """Record these PLC variables (and drive signals `driveN.position`..., or all drives' with
        drives=True) every `every` scans from now on; the plugin writes the scope's PNG, VCD and CSV when the
        test fails (also when it passes with write=True). Returns the Scope (plctest/scope.py)."""
        from . import scope as scope_mod
        if every < 1:
            raise ValueError(f"every={every}: a scope samples every n >= 1 scans")
        s = scope_mod.Scope(self, scope_mod.signals_of(self, paths, drives), every=every, write_always=write,
                            observe=self.bus is not None)
        s.sample()                                        # the state before the next scan
        self.scopes.append(s)
        return scope_mod.register(s)

    def _default_scope(self) -> None:
        """The scope that the ini option linmot_st_scope or the `scope` marker asks of every rig of a test."""
        from . import scope as scope_mod
        d = scope_mod.DEFAULTS
        if d and (d["paths"] or d["drives"]):
            self.scope(*d["paths"], every=d["every"], drives=d["drives"], write=d["write"])

    def _arm(self) -> None:
        for f in list(self._armed):
            if f.when is None or f.when.test():
                f.installed_ns = self.plc.time_ns
                f.fault = f.install(max(self.plc.time_ns, self.bus.now))
                self._armed.remove(f)

    def budget(self, scans: int | None, ms: float | None) -> int:
        """A budget in scans: `scans`, or `ms` of PLC time in scans of its task interval."""
        if (scans is None) == (ms is None):
            raise ValueError("give exactly one of scans= or ms=")
        if scans is not None:
            return int(scans)
        return max(1, int(round(ms * 1e6 / self.plc.tick_ns)))

    def step_until(self, cond: str | Callable[[], Any], *, scans: int | None = None, ms: float | None = None,
                   watch: list[str] | tuple = (), what: str | None = None, check_first: bool = True) -> int:
        """Step until the condition holds (checked before the first scan, unless check_first is False, and
        after each); returns the scans run. RigTimeout after the budget, with the condition, the PLC time,
        the watched variables and the last CAN frames."""
        __tracebackhide__ = True
        c = condition(self.plc, cond, what)
        n = self.budget(scans, ms)
        if check_first and c.test():
            return 0
        for k in range(1, n + 1):
            self.step(1)
            if c.test():
                return k
        limit = f"{n} scans" if ms is None else f"{ms:g} ms ({n} scans)"
        raise RigTimeout(self.explain(f"not reached within {limit}: {c.text}", [*c.paths, *watch]))

    def expect_done(self, fb_path: str, *, scans: int | None = None, ms: float | None = None,
                    watch: list[str] | tuple = ()) -> FbResult:
        """Step until the FB at fb_path shows Done; its Error or CommandAborted, or the budget running
        out, fails the test (FbFailed / RigTimeout) with the FB's outputs and the rig's state."""
        __tracebackhide__ = True
        fb = self.fb(fb_path)
        k = self.step_until(fb.finished, scans=scans, ms=ms, what=f"{fb.path} Done, Error or CommandAborted",
                            watch=[*watch, f"{fb.path}.BUSY"])
        res = fb.result(k)
        if not res.done:
            how = (f"Error, ErrorID 16#{res.error_id:04X} ({res.error_name})" if res.error else "CommandAborted")
            raise FbFailed(self.explain(f"{fb.path} ended with {how} after {k} scans, not Done",
                                        [f"{fb.path}.{m}" for m in _fb_members(res.outputs)] + list(watch)))
        return res

    # -- faults ------------------------------------------------------------------------------------------
    def inject_fault(self, kind: str, *, when: str | Callable[[], Any] | None = None,
                     can_id: int | list[int] | None = None, match: Callable | None = None,
                     sender: str | None = None, count: int | None = None, delay_ns: int = 0,
                     mutate: Callable | None = None, node: int | None = None) -> InjectedFault:
        """A bus fault, installed now or at the first scan where `when` holds (a phase, a state...).

        Frame faults (linmot_st.bus.faults): drop, delay (delay_ns), duplicate, corrupt, mutate_payload
        (mutate); which frames: can_id and/or match(frame), sender (a drive: Rig.drive_name(n), the PLC:
        "plc"), count (at most this many). Drive faults: reset (the drive restarts, as at power-on) and
        power_off (it leaves the bus), of drive `node`."""
        bus = self.bus
        if kind in FRAME_FAULTS:
            pred = frame_predicate(can_id, match)
            extra = {"delay": (delay_ns,), "mutate_payload": (mutate,)}.get(kind, ())
            if kind == "mutate_payload" and mutate is None:
                raise ValueError("mutate_payload needs mutate=")
            install = lambda t: getattr(bus, kind)(pred, *extra, sender=sender, count=count)  # noqa: E731
        elif kind in NODE_FAULTS:
            if node not in self.drives:
                raise ValueError(f"{kind} needs node= one of the rig's drives {sorted(self.drives)}")
            name = self.drive_name(node)
            install = ((lambda t: bus.reset_node(name, t)) if kind == "reset"
                       else (lambda t: bus.remove_node(name, t)))
        else:
            raise ValueError(f"fault {kind!r}: one of {', '.join(FRAME_FAULTS + NODE_FAULTS)}")
        f = InjectedFault(kind, condition(self.plc, when) if when is not None else None, install)
        self.faults.append(f)
        self._armed.append(f)
        if when is None:
            self._arm()
        return f

    # -- failure messages --------------------------------------------------------------------------------
    @property
    def trace(self) -> list:
        """Every CAN frame so far (TraceEntry: start_ns, end_ns, sender, frame, status)."""
        return self.bus.trace

    def frames(self, last: int = FRAMES_SHOWN) -> list:
        """The last CAN frames (all of them for last=0)."""
        trace = self.trace
        return trace[-last:] if last else list(trace)

    def explain(self, headline: str, paths: list[str] | tuple = ()) -> str:
        lines = [headline, f"PLC time {self.plc.time_ns / 1e9:.6f} s, scan {self.plc.scan_count} "
                           f"({self.plc.backend} backend)"]
        shown = list(dict.fromkeys([*paths, *self.watched]))
        if shown:
            lines.append("watched:")
            lines += [f"  {p} = {_value(self.plc, p)}" for p in shown]
        lines += format_frames(self.frames(), len(self.trace))
        return "\n".join(lines)


def _fb_members(outputs: dict) -> list[str]:
    return [m for m in ("DONE", "BUSY", "ERROR", "ERRORID", "COMMANDABORTED", "PHASE") if m in outputs]


def _value(plc: Plc, path: str) -> str:
    try:
        v = plc[path]
    except Exception as exc:  # noqa: BLE001 - a failure message must not fail itself
        return f"<{exc}>"
    if isinstance(v, int) and not isinstance(v, bool) and abs(v) > 9:
        return f"{v} (16#{v & 0xFFFFFFFFFFFFFFFF:X})"
    text = repr(v)
    return text if len(text) <= 200 else text[:200] + "..."


def format_frames(entries: list, total: int) -> list[str]:
    if not total:
        return ["no CAN frames so far"]
    out = [f"last {len(entries)} of {total} CAN frames:"]
    for e in entries:
        status = "" if getattr(e, "status", "ok") == "ok" else f"  ({e.status})"
        out.append(f"  {e.end_ns / 1e9:12.6f} s  {e.sender:<8} {e.frame}{status}")
    return out


# ---- the python-can variant ----------------------------------------------------------------------------

class RealTimeRig(Rig):
    """The PLC in real time on a python-can bus (`virtual` by default, or `socketcan:vcan0`...), with
    emulated drives served from background threads (fast timings by default: nothing waits seconds).
    Budgets in scans are real scans (one per task interval of wall time). Close it (or use it in a `with`)."""

    def __init__(self, build: BuildResult, *, bus: str = "virtual", nodes: tuple[int, ...] | list[int] = (1,),
                 bitrate: int = 500_000, timings: Any = "fast", protocol: Any = None, profile: Any = None,
                 drive_factory: Callable[[int], Any] | None = None, emulate: bool = True,
                 mailbox: str = MAILBOX, watch: list[str] | tuple = (), model: Any = "E1100"):
        import os
        import uuid

        from linmot_st.bus import open_bus
        from linmot_st.cosim import RealTimeCoSim
        from linmot_st.emulator.models import make_drive
        from linmot_st.jobs.commission.runner import _RecordingBus  # the PLC side's frame record
        from linmot_st.plc import Plc

        if bus == "virtual":                      # a channel of its own: parallel tests never share frames
            bus = f"virtual:linmot-st-test-{os.getpid()}-{uuid.uuid4().hex[:8]}"
        self.build, self.spec = build, bus
        self.plc = Plc(build)
        self.drives, self._buses = {}, []
        self.watched, self.faults, self._armed, self.scopes = list(watch), [], [], []
        try:
            # the PLC's side first: a python-can bus receives only what is sent after it opened, and an
            # attached drive boots at once (fast timings: 20 ms), so its boot-up must find the PLC listening
            self.can = _RecordingBus(open_bus(bus, bitrate=bitrate), time.monotonic_ns(), 1_000_000_000 // bitrate)
            self._buses.append(self.can.bus)
            if emulate:
                for n in nodes:
                    drive_bus = open_bus(bus, bitrate=bitrate)
                    self._buses.append(drive_bus)
                    drive = drive_factory(n) if drive_factory else make_drive(
                        model_of(model, n), n, profile=profile, timings=_timings(timings), protocol=protocol)
                    drive.attach(drive_bus)
                    self.drives[n] = drive
        except BaseException:
            self.close()
            raise
        self.bus = None
        self.sim = RealTimeCoSim(self.plc, self.can, mailbox=mailbox)
        self._default_scope()

    def _step_n(self, n: int) -> None:
        self.sim.step(n)

    def inject_fault(self, *args, **kwargs):
        raise NotImplementedError("fault injection needs the simulated bus (Rig): a python-can bus has no hooks")

    @property
    def trace(self) -> list:
        """The frames the PLC sent and received (times in ns since the rig opened its bus)."""
        return self.can.records

    def explain(self, headline: str, paths: list[str] | tuple = ()) -> str:
        text = super().explain(headline, paths)
        return text.replace("last ", f"on {self.spec}: last ", 1) + (
            f"\nreal-time scans late by more than one task interval: {self.sim.overruns}" if self.sim.overruns else "")

    def close(self) -> None:
        for d in self.drives.values():
            d.detach()
        for b in self._buses:
            b.shutdown()
        self._buses = []

    def __enter__(self) -> RealTimeRig:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
