"""The commissioning report: figures per axis and phase, bus load, the ratio to the bus-time lower bound,
the verification, the failure in words; printed as text, written as Markdown and JSON with the CAN trace
and the curve plots.

Bus-time lower bound (docs/commissioning.md, after shared/spec/can-bus-limits.md): the time the run's SDO
exchanges need on the bus alone, every frame sent back to back with no stuff bits and no device
turnaround: exchanges x 2 frames x 111 bits (an 8-byte data frame without stuff bits, 3-bit interframe
space included) / bit rate. All axes share one bus, so the run's bound counts the exchanges of all axes.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

from linmot_st.errors import describe
from linmot_st.pvl.dataset import Dataset
from .runner import RunResult
from .verify import Verification

SDO_FRAME_BITS = 111            # linmot_st.bus.bits.unstuffed_bus_bits(8)
PHASE_TITLES = {"start": "start (dataset header)", "check": "compatibility check", "params": "parameters",
                "curves": "curves", "ct": "command table", "flash": "flash save", "reset": "reset + boot",
                "verify": "verify (read back)"}
TRANSFER_PHASES = ("check", "params", "curves", "ct", "verify")
WAIT_PHASES = ("start", "flash", "reset")      # their time is the drive's own work, not the bus


def lower_bound_ns(exchanges: int, bit_ns: int) -> int:
    return exchanges * 2 * SDO_FRAME_BITS * bit_ns


@dataclass
class Context:
    """What the report says about the run besides the run itself."""
    pvl_path: str
    command: str
    backend: str
    build_s: float
    build_cached: bool
    project: str
    dataset_words: int


@dataclass
class Report:
    ctx: Context
    run: RunResult
    dataset: Dataset
    verification: Verification
    pvl: object
    figures: dict = field(default_factory=dict)

    # ------------------------------------------------------------------ figures
    def compute(self) -> dict:
        r, bit = self.run, self.run.bit_ns
        axes = []
        for ax in r.axes:
            on_bus = _bus_exchanges(r.trace, ax.node_id, ax.started_ns, ax.ended_ns or r.t_end_ns)
            phases = []
            for p in ax.phases:
                lb = lower_bound_ns(p.exchanges, bit)
                phases.append(dict(phase=p.phase, exchanges=p.exchanges, scans=p.scans,
                                   time_ms=p.duration_ns / 1e6, lower_bound_ms=lb / 1e6,
                                   ratio=(p.duration_ns / lb) if lb else None,
                                   scans_per_exchange=(p.scans / p.exchanges) if p.exchanges else None))
            transfer = [p for p in ax.phases if p.phase in TRANSFER_PHASES]
            t_ns = sum(p.duration_ns for p in transfer)
            t_ex = sum(p.exchanges for p in transfer)
            axes.append(dict(
                axis=ax.axis, node=ax.node_id,
                result="done" if ax.done else ("error" if ax.error else "not finished"),
                error_id=ax.error_id, error=describe(ax.error_id, ax.abort_code) if ax.error else "",
                abort_code=ax.abort_code, failure=self.failure_text(ax) if ax.error else "",
                fail=dict(phase=ax.fail_phase, item=ax.fail_item, step=ax.fail_step,
                          expected=ax.fail_expected, actual=ax.fail_actual) if ax.error else None,
                drive_layer=dict(zip(("tree_id", "main_version", "sub_version"), ax.drive_layer)),
                up_ms=ax.up_ns / 1e6 if ax.up_ns is not None else None,
                start_ms=ax.started_ns / 1e6 if ax.started_ns is not None else None,
                end_ms=ax.ended_ns / 1e6 if ax.ended_ns is not None else None,
                time_ms=((ax.ended_ns or 0) - (ax.started_ns or 0)) / 1e6 if ax.ended_ns else None,
                exchanges=ax.exchanges, exchanges_on_bus=on_bus, live_written=ax.live_written,
                transfer=dict(time_ms=t_ns / 1e6, exchanges=t_ex, lower_bound_ms=lower_bound_ns(t_ex, bit) / 1e6,
                              ratio=t_ns / lower_bound_ns(t_ex, bit) if t_ex else None),
                phases=phases))
        span = r.t_end_ns - r.t_start_ns
        total_ex = sum(a.exchanges for a in r.axes)
        lb = lower_bound_ns(total_ex, bit)
        st = r.stats
        self.figures = dict(
            command=self.ctx.command, pvl=self.ctx.pvl_path, backend=self.ctx.backend,
            build=dict(seconds=round(self.ctx.build_s, 3), cached=self.ctx.build_cached, project=self.ctx.project),
            dataset=dict(layers=len(self.dataset.layers), parameters=len(self.dataset.params),
                         curves=len(self.dataset.curves), setpoints=sum(len(c[2]) for c in self.dataset.curves),
                         entries=len(self.dataset.entries), words=self.dataset.words),
            options=dict(axes=len(r.axes), node_ids=r.node_ids, bus=r.options.bus, bitrate=r.options.bitrate,
                         live_ram=r.options.live_ram, flash=r.options.flash, reset=r.options.reset,
                         verify=r.options.verify, drive_timings=r.options.timing_kind() if r.options.emulate else None,
                         task_ms=r.tick_ns / 1e6),
            axes=axes,
            run=dict(start_ms=r.t_start_ns / 1e6, end_ms=r.t_end_ns / 1e6, time_ms=span / 1e6,
                     exchanges=total_ex, scans=r.scans, wall_s=round(r.wall_s, 3), timed_out=r.timed_out,
                     plc_fault=r.fault,
                     overruns=r.overruns, max_lateness_ms=r.max_lateness_ns / 1e6),
            bus=dict(frames=st.frames if st else 0, errors=st.errors if st else 0,
                     load=st.load if st else 0.0, busy_ms=(st.busy_ns / 1e6) if st else 0.0,
                     stuffing_ratio=st.stuffing_ratio if st else 0.0,
                     lower_bound_ms=lb / 1e6, ratio=(span / lb) if lb else None,
                     scan_bound_ms=max((a.exchanges for a in r.axes), default=0) * r.tick_ns / 1e6),
            verification=dict(ok=self.verification.ok, skipped=self.verification.skipped,
                              checks=[dict(node=c.node, what=c.what, checked=c.checked, equal=c.equal,
                                           required=c.required, ok=c.ok, differences=c.differences, note=c.note)
                                      for c in self.verification.checks]),
            result=dict(commissioned=r.commissioned, verified=self.verification.ok,
                        passed=r.commissioned and self.verification.ok),
        )
        return self.figures

    # ------------------------------------------------------------------ words
    def failure_text(self, ax) -> str:
        where = self.item_text(ax.fail_phase, ax.fail_item, ax.fail_step)
        what = describe(ax.error_id, ax.abort_code)
        extra = ""
        if ax.fail_phase == "check" and ax.fail_item in (1, 2, 3, 4):
            src = next((l for l in self.dataset.layers if l[0] == ax.fail_item), None)
            tid, main, sub = ax.drive_layer
            if src:
                extra = (f"; the drive has tree ID {tid}, version {main}.{sub}, the dataset tree ID {src[1]}, "
                         f"version {src[2]}.{src[3]}; nothing was written")
        elif ax.error_id == 0x0603:
            extra = f"; read {ax.fail_actual:08X}h, expected {ax.fail_expected:08X}h"
        return f"failed in phase {PHASE_TITLES.get(ax.fail_phase, ax.fail_phase)}, {where}: ErrorID {what}{extra}"

    def item_text(self, phase: str, item: int, step: int) -> str:
        if phase == "check":
            from linmot_st.pvl import LAYERS
            return f"layer {item} ({LAYERS[item].name})" if item in LAYERS else f"layer {item}"
        if phase in ("params",) or (phase == "verify" and self._is_param(item, step)):
            caption = next((p.caption for o in self.pvl.parameter_objects for p in o.parameters if p.upid == item), "")
            return f"UPID {item:04X}h {caption}".rstrip()
        if phase == "curves" or (phase == "verify" and self.pvl.curve(item) is not None and step):
            c = self.pvl.curve(item)
            name = f" '{c.name}'" if c else ""
            if step == 0:
                part = "add / get request"
            elif step <= 18:
                part = f"info word {step}"
            else:
                part = f"setpoint {step - 19}"
            return f"curve {item}{name}, {part}"
        if phase == "ct":
            return f"command-table entry {item}, " + ("prepare request" if step == 0 else f"2-byte step {step}")
        if phase == "verify":
            if self.pvl.curve(item) is not None:
                return f"curve {item}, get request"
            return f"item {item}"
        if phase in ("flash", "reset"):
            names = {0x35: "stop MC (35h)", 0x40: "save curves (40h)", 0x42: "poll flash (42h)",
                     0x80: "save / poll command table (80h)", 0x36: "start MC (36h)", 0x0B: "reset (0Bh)"}
            return names.get(item, f"service {item:02X}h")
        if phase == "start":
            return "dataset header" + (f" word {step}" if step else "")
        return f"item {item}"

    def _is_param(self, item: int, step: int) -> bool:
        is_param = any(p.upid == item for o in self.pvl.parameter_objects for p in o.parameters)
        return is_param and not (self.pvl.curve(item) is not None and step)

    # ------------------------------------------------------------------ text
    def text(self) -> str:
        f = self.figures or self.compute()
        o, d, run, bus = f["options"], f["dataset"], f["run"], f["bus"]
        bus_name = ("simulated bus" if o["bus"] == "sim" else o["bus"]) + f" {o['bitrate'] // 1000} kbit/s"
        lines = [
            f"linmot-st commission {self.ctx.pvl_path}",
            f"  {o['axes']} ax{'is' if o['axes'] == 1 else 'es'} (node ID{'s' if o['axes'] > 1 else ''} "
            f"{', '.join(map(str, o['node_ids']))}), {bus_name}, PLC task {o['task_ms']:g} ms, backend {f['backend']} "
            f"({self.ctx.project}, build {'cached' if f['build']['cached'] else f'{self.ctx.build_s:.1f} s'})",
            f"  dataset: {d['layers']} layers, {d['parameters']} parameters, {d['curves']} curves "
            f"({d['setpoints']} setpoints), {d['entries']} command-table entries = {d['words']} words",
            "  options: " + ", ".join(f"{k} {'on' if o[k] else 'off'}" for k in ("live_ram", "flash", "reset", "verify"))
            + (f", drive timings {o['drive_timings']}" if o["drive_timings"] else ""),
            "",
        ]
        for a in f["axes"]:
            head = f"node {a['node']}: "
            if a["result"] == "done":
                head += f"commissioned in {a['time_ms']:.1f} ms, {a['exchanges']} exchanges"
            elif a["result"] == "error":
                head += a["failure"].upper()[:1] + a["failure"][1:]
            else:
                head += "did not finish" + ("" if a["start_ms"] is not None else " (never started: no boot-up heard)")
            if a["up_ms"] is not None and a["start_ms"] is not None:
                head += f" (drive up at {a['up_ms']:.1f} ms, started {a['start_ms']:.1f} ms)"
            lines.append(head)
            if a["phases"]:
                lines.append(f"  {'phase':<24}{'exchanges':>10}{'scans':>8}{'time ms':>11}{'bus LB ms':>11}"
                             f"{'x LB':>8}{'scans/exch':>12}")
                for p in a["phases"]:
                    wait = p["phase"] in WAIT_PHASES
                    lines.append(f"  {PHASE_TITLES.get(p['phase'], p['phase']):<24}{p['exchanges']:>10}{p['scans']:>8}"
                                 f"{p['time_ms']:>11.1f}{p['lower_bound_ms']:>11.2f}"
                                 f"{'-' if wait else _r(p['ratio']):>8}"
                                 f"{'(drive)' if wait and p['exchanges'] else _r(None if wait else p['scans_per_exchange'], 3):>12}")
                t = a["transfer"]
                lines.append(f"  {'transfer phases':<24}{t['exchanges']:>10}{'':>8}{t['time_ms']:>11.1f}"
                             f"{t['lower_bound_ms']:>11.2f}{_r(t['ratio']):>8}")
                if a["exchanges_on_bus"] != a["exchanges"]:
                    lines.append(f"  (the bus carried {a['exchanges_on_bus']} answers to this node: "
                                 f"{a['exchanges'] - a['exchanges_on_bus']} request(s) unanswered)")
            lines.append("")
        lines += [
            f"run: {run['time_ms']:.1f} ms of PLC time from the first start to the last end, {run['exchanges']} exchanges, "
            f"{run['scans']} scans in {run['wall_s']:.2f} s wall"
            + (f", {run['overruns']} late scans (max {run['max_lateness_ms']:.1f} ms)" if o["bus"] != "sim" else "")
            + (" - TIMED OUT" if run["timed_out"] else "")
            + (f" - PLC FAULT: {run['plc_fault']}" if run["plc_fault"] else ""),
            f"bus: {bus['frames']} frames, load {100 * bus['load']:.1f} % (busy {bus['busy_ms']:.1f} ms), "
            f"stuff bits add {100 * (bus['stuffing_ratio'] - 1):.1f} %" if bus["stuffing_ratio"] else
            f"bus: {bus['frames']} frames",
            f"bus-time lower bound: {run['exchanges']} exchanges x 2 frames x {SDO_FRAME_BITS} bits at "
            f"{o['bitrate'] // 1000} kbit/s = {bus['lower_bound_ms']:.1f} ms; the run took {_r(bus['ratio'])} x that "
            f"(one exchange per scan and drive: at least {bus['scan_bound_ms']:.0f} ms)",
            "",
            "(drive): the phase waits for the drive's own work (MC stop/start, flash writes, boot), not for the bus",
            "",
            "verification (the emulated drives' memory against the PVL file):",
        ]
        v = self.verification
        if v.skipped:
            lines.append(f"  not done: {v.skipped}")
        for node in f["options"]["node_ids"]:
            checks = v.for_node(node)
            if not checks:
                continue
            parts = [f"{c.what} {c.equal}/{c.checked}" for c in checks]
            lines.append(f"  node {node}: " + ", ".join(parts) + (": OK" if v.node_ok(node) else ": DIFFERENT"))
            for c in checks:
                for diff in c.differences:
                    lines.append(f"    {c.what}: {diff}" + ("" if c.required else " (not required)"))
                if c.note:
                    lines.append(f"    {c.what}: {c.note}")
        res = f["result"]
        verdict = "PASSED" if res["passed"] else "FAILED"
        why = []
        if not res["commissioned"]:
            bad = [str(a["node"]) for a in f["axes"] if a["result"] != "done"]
            if run["plc_fault"]:
                why.append("the PLC faulted")
            elif bad:
                why.append(f"commissioning failed on node{'s' if len(bad) > 1 else ''} {', '.join(bad)}")
        if not res["verified"]:
            why.append("verification " + ("not done" if v.skipped else "found differences"))
        lines += ["", f"result: {verdict}" + (f" ({'; '.join(why)})" if why else
                                            f" ({len(f['axes'])} ax{'is' if len(f['axes']) == 1 else 'es'} "
                                            "commissioned and verified)")]
        return "\n".join(lines) + "\n"

    def markdown(self) -> str:
        return "# Commissioning report\n\n```\n" + self.text() + "```\n\n" + self._files_md()

    def _files_md(self) -> str:
        files = self.figures.get("files", {})
        out = []
        if files.get("trace"):
            out.append(f"- CAN trace: [{files['trace']}]({files['trace']})")
        for p in files.get("plots", []):
            out.append(f"- ![{p}]({p})")
        if files.get("json"):
            out.append(f"- figures for machines: [{files['json']}]({files['json']})")
        return "\n".join(out) + ("\n" if out else "")

    # ------------------------------------------------------------------ files
    def write(self, folder: Path, trace_format: str = "log") -> dict:
        """The report folder: report.md, report.json, can.<format>, curve_<id>.png."""
        from linmot_st.bus.trace import write_trace

        from .plots import plot_curve, read_back_from_trace

        folder = Path(folder)
        folder.mkdir(parents=True, exist_ok=True)
        f = self.figures or self.compute()
        files: dict = {"plots": []}
        trace_name = f"can.{trace_format.lstrip('.')}"
        write_trace(self.run.trace, folder / trace_name)
        files["trace"] = trace_name
        for c in self.pvl.curves:
            backs = []
            for ax in self.run.axes:
                t_verify = next((p.t0_ns for p in ax.phases if p.phase == "verify"), None)
                drive = self.run.drives.get(ax.node_id)
                back, source = None, ""
                if t_verify is not None:
                    back, source = read_back_from_trace(self.run.trace, ax.node_id, c.curve_id, t_verify), "bus"
                if not back and drive is not None and c.curve_id in drive.curves.ram:
                    back, source = drive.curves.ram[c.curve_id].setpoints, "drive RAM"
                backs.append((ax.node_id, back, source))
            name = f"curve_{c.curve_id}.png"
            plot_curve(folder / name, c, backs)
            files["plots"].append(name)
        files["json"] = "report.json"
        f["files"] = files
        (folder / "report.json").write_text(json.dumps(f, indent=2, default=_json_default) + "\n")
        (folder / "report.md").write_text(self.markdown())
        return files


def _json_default(o):
    if isinstance(o, float):
        return round(o, 6)
    return str(o)


def _r(x, digits: int = 2) -> str:
    return "-" if x is None else f"{x:.{digits}f}"


def _bus_exchanges(trace, node: int, t0: int | None, t1: int | None) -> int:
    """Answers of `node` (580h + node, 8 bytes) on the bus between t0 and t1."""
    if t0 is None:
        return 0
    resp = 0x580 + node
    return sum(1 for e in trace if e.frame.can_id == resp and e.status != "error" and t0 <= e.start_ns
               and (t1 is None or e.start_ns < t1))
