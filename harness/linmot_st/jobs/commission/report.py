"""The commissioning report: figures per axis and phase, bus load, the ratio to the bus-time lower bound,
the verification, the failure in words; printed as text, written as Markdown and JSON with the CAN trace
and the curve plots.

Bus-time lower bound (docs/commissioning.md, after shared/spec/can-bus-limits.md): the time SDO exchanges
need on the bus alone, every frame sent back to back with no stuff bits and no device turnaround:
exchanges x 2 frames x 111 bits (an 8-byte data frame without stuff bits, 3-bit interframe space included,
`linmot_st.bus.bits.unstuffed_bus_bits(8)`) / bit rate. Per axis and phase it counts the exchanges that axis
made. All axes share one bus, so the run-level figures ("all axes") count the exchanges of all axes, and
their bound counts the NECESSARY exchanges (`necessary_exchanges`: what a successful run cannot do without;
flash polls beyond one per store and LiveRam's ROM-only retries are not necessary); the bound of the actual
exchanges stands beside it.
"""

from __future__ import annotations

import json
import textwrap
from dataclasses import dataclass, field
from pathlib import Path

from linmot_st.bus.bits import bus_bits, unstuffed_bus_bits
from linmot_st.bus.stats import bus_stats
from linmot_st.bus.trace import write_trace
from linmot_st.protocol.errors import describe
from linmot_st.pvl import LAYERS
from linmot_st.pvl.dataset import Dataset, expected_exchanges

from .plots import ReadBack, curve_read_backs, plot_curve
from .runner import RunResult
from .verify import Verification

SDO_FRAME_BITS = unstuffed_bus_bits(8)      # 111: an SDO request or answer without stuff bits, IFS included
PHASE_TITLES = {"wait": "waiting for the drive", "start": "start (dataset header)", "check": "compatibility check",
                "compare": "compare (read drive)",
                "preflight": "pre-flight check", "params": "parameters", "curves": "curves", "ct": "command table",
                "flash": "flash save", "reset": "reset + boot", "verify": "verify (read back)"}
NMT_STATES = {0x00: "none (no heartbeat)", 0x04: "04h stopped", 0x05: "05h operational", 0x7F: "7Fh pre-operational"}
TRANSFER_PHASES = ("check", "compare", "preflight", "params", "curves", "ct", "verify")
WAIT_PHASES = ("wait", "start", "flash", "reset")      # their time is the drive's own work, not the bus


def lower_bound_ns(exchanges: int, bit_ns: int) -> int:
    return exchanges * 2 * SDO_FRAME_BITS * bit_ns


def necessary_exchanges(ds: Dataset, opts, transfer_only: bool = False) -> int:
    """The SDO exchanges one axis cannot do without in a successful run with these options: every write and
    read of the dataset (`expected_exchanges`), and, for the whole run, the flash services with one poll per
    store (the FB must poll at least once to learn the save ended) and the reset request."""
    preflight = getattr(opts, "preflight", True)
    live_ram = getattr(opts, "live_ram", False)
    if transfer_only:
        return expected_exchanges(ds, verify=opts.verify, flash=False, preflight=preflight, live_ram=live_ram)
    n = expected_exchanges(ds, verify=opts.verify, flash=opts.flash, preflight=preflight, live_ram=live_ram)
    if opts.flash and (ds.curves or ds.entries):
        n += (1 if ds.curves else 0) + (1 if ds.entries else 0)
    return n + (1 if opts.reset else 0)


def _merge(intervals: list[tuple[int, int]]) -> list[tuple[int, int]]:
    out: list[list[int]] = []
    for a, b in sorted(intervals):
        if out and a <= out[-1][1]:
            out[-1][1] = max(out[-1][1], b)
        elif b > a:
            out.append([a, b])
    return [(a, b) for a, b in out]


def _n(k: int, word: str, plural: str | None = None) -> str:
    return f"{k} {word if k == 1 else (plural or word + 's')}"


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
class DatasetGroup:
    """One dataset file of a run and the axes commissioned with it."""
    name: str
    pvl: object
    dataset: Dataset
    nodes: list[int]
    read_backs: dict[int, list[ReadBack]] = field(default_factory=dict)     # curve ID -> per axis


def _dataset_counts(ds: Dataset) -> dict:
    return dict(layers=len(ds.layers), parameters=len(ds.params), curves=len(ds.curves),
                setpoints=sum(len(c[2]) for c in ds.curves), entries=len(ds.entries), words=ds.words)


@dataclass
class Report:
    ctx: Context
    run: RunResult
    dataset: Dataset
    verification: Verification
    pvl: object
    figures: dict = field(default_factory=dict)
    groups: list = field(default_factory=list)    # DatasetGroup per dataset file (one without per-node datasets)

    # ------------------------------------------------------------------ figures
    def compute(self) -> dict:
        r, bit = self.run, self.run.bit_ns
        sets = r.datasets
        own = None if sets is None or sets.single else {ax.node_id for ax in r.axes if sets.of(ax.node_id) is sets.default}
        self.groups = self._dataset_groups(own)

        def dataset_of(node: int) -> Dataset:
            return self.dataset if own is None or node in own else sets.of(node).dataset
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
                dataset=(self.ctx.pvl_path if own is None or ax.node_id in own else sets.of(ax.node_id).name),
                result="done" if ax.done else ("error" if ax.error else "not finished"),
                error_id=ax.error_id, error=describe(ax.error_id, ax.abort_code) if ax.error else "",
                abort_code=ax.abort_code, failure=self.failure_text(ax) if ax.error else "",
                fail=dict(phase=ax.fail_phase, kind=ax.fail_kind, item=ax.fail_item, step=ax.fail_step,
                          expected=ax.fail_expected, actual=ax.fail_actual, delay_ms=ax.fail_delay_ns / 1e6,
                          mc_stopped=ax.mc_stopped) if ax.error else None,
                drive_layer=dict(zip(("tree_id", "main_version", "sub_version"), ax.drive_layer)),
                up_ms=ax.up_ns / 1e6 if ax.up_ns is not None else None,
                start_ms=ax.started_ns / 1e6 if ax.started_ns is not None else None,
                end_ms=ax.ended_ns / 1e6 if ax.ended_ns is not None else None,
                time_ms=((ax.ended_ns or 0) - (ax.started_ns or 0)) / 1e6 if ax.ended_ns else None,
                exchanges=ax.exchanges, exchanges_on_bus=on_bus, live_written=ax.live_written,
                items=dict(written=ax.written, skipped=ax.skipped, verified=ax.verified),
                wear=r.wear(ax.node_id),
                transfer=dict(time_ms=t_ns / 1e6, exchanges=t_ex, lower_bound_ms=lower_bound_ns(t_ex, bit) / 1e6,
                              ratio=t_ns / lower_bound_ns(t_ex, bit) if t_ex else None),
                phases=phases))
        span = r.t_end_ns - r.t_start_ns
        total_ex = sum(a.exchanges for a in r.axes)
        # re-commissioning: what a run needs depends on what the drives held, so only the full write has a
        # necessary count
        complete = r.commissioned and r.options.force
        # all axes on the one bus: the bound counts the necessary exchanges of every axis (a failed run has
        # no necessary count: its bound counts what it did)
        need = sum(necessary_exchanges(dataset_of(a.node_id), r.options) for a in r.axes) if complete else None
        lb_actual = lower_bound_ns(total_ex, bit)
        lb = lower_bound_ns(need, bit) if need is not None else None
        windows = _merge([(p.t0_ns, p.t1_ns) for ax in r.axes for p in ax.phases if p.phase in TRANSFER_PHASES])
        tr_ns = sum(b - a for a, b in windows)
        tr_busy = sum(self._busy_ns(a, b) for a, b in windows)
        tr_ex = sum(a["transfer"]["exchanges"] for a in axes)
        tr_need = (sum(necessary_exchanges(dataset_of(a.node_id), r.options, transfer_only=True) for a in r.axes)
                   if complete else None)
        tr_lb_actual = lower_bound_ns(tr_ex, bit)
        tr_lb = lower_bound_ns(tr_need, bit) if tr_need is not None else None
        tr_stuffed = stuffed_bound_ns(r, TRANSFER_PHASES, tr_need)
        st = r.stats
        self.figures = dict(
            command=self.ctx.command, pvl=self.ctx.pvl_path, backend=self.ctx.backend,
            build=dict(seconds=round(self.ctx.build_s, 3), cached=self.ctx.build_cached, project=self.ctx.project),
            dataset=_dataset_counts(self.dataset),
            datasets=[dict(name=g.name, nodes=g.nodes, **_dataset_counts(g.dataset)) for g in self.groups],
            options=dict(axes=len(r.axes), node_ids=r.node_ids, bus=r.options.bus, bitrate=r.options.bitrate,
                         live_ram=r.options.live_ram, flash=r.options.flash, reset=r.options.reset,
                         verify=r.options.verify, preflight=r.options.preflight, force=r.options.force,
                         drive_timings=r.options.timing_kind() if r.options.emulate else None,
                         task_ms=r.tick_ns / 1e6),
            axes=axes,
            run=dict(start_ms=r.t_start_ns / 1e6, end_ms=r.t_end_ns / 1e6, time_ms=span / 1e6,
                     exchanges=total_ex, necessary_exchanges=need,
                     items={k: sum(a["items"][k] for a in axes) for k in ("written", "skipped", "verified")}, scans=r.scans, wall_s=round(r.wall_s, 3),
                     commissioned=r.commissioned, timed_out=r.timed_out, interrupted=r.interrupted, plc_fault=r.fault,
                     overruns=r.overruns, max_lateness_ms=r.max_lateness_ns / 1e6, skipped_ticks=r.skipped_ticks),
            bus=dict(frames=st.frames if st else 0, frames_in_trace=sum(1 for e in r.trace if e.status != "error"),
                     errors=st.errors if st else 0,
                     load=st.load if st else 0.0, busy_ms=(st.busy_ns / 1e6) if st else 0.0,
                     stuffing_ratio=st.stuffing_ratio if st else 0.0, frame_bits=SDO_FRAME_BITS,
                     lower_bound_ms=lb / 1e6 if lb is not None else None, ratio=(span / lb) if lb else None,
                     lower_bound_actual_ms=lb_actual / 1e6, ratio_actual=(span / lb_actual) if lb_actual else None,
                     scan_bound_ms=max((a.exchanges for a in r.axes), default=0) * r.tick_ns / 1e6),
            transfer=dict(time_ms=tr_ns / 1e6, exchanges=tr_ex, necessary_exchanges=tr_need,
                          busy_ms=tr_busy / 1e6, load=tr_busy / tr_ns if tr_ns else 0.0,
                          lower_bound_ms=tr_lb / 1e6 if tr_lb is not None else None,
                          ratio=tr_ns / tr_lb if tr_lb else None,
                          lower_bound_actual_ms=tr_lb_actual / 1e6,
                          ratio_actual=tr_ns / tr_lb_actual if tr_lb_actual else None,
                          lower_bound_stuffed_ms=tr_stuffed / 1e6 if tr_stuffed else None,
                          ratio_stuffed=tr_ns / tr_stuffed if tr_stuffed else None),
            curves=[dict(curve=c.curve_id, name=c.name, setpoints=len(c.setpoints), dataset=g.name,
                         nodes=[dict(node=rb.node, written=rb.written,
                                     read_back=len(rb.setpoints) if rb.setpoints else None, source=rb.source,
                                     differ=rb.differ, verdict=rb.verdict) for rb in g.read_backs[c.curve_id]])
                    for g in self.groups for c in g.pvl.curves],
            verification=dict(ok=self.verification.ok, skipped=self.verification.skipped,
                              by_plc=self.verification.by_plc,
                              checks=[dict(node=c.node, what=c.what, checked=c.checked, equal=c.equal,
                                           required=c.required, ok=c.ok, differences=c.differences, note=c.note)
                                      for c in self.verification.checks]),
            result=dict(commissioned=r.commissioned, verified=self.verification.ok,
                        passed=r.commissioned and self.verification.ok),
        )
        return self.figures

    def _dataset_groups(self, own: set[int] | None) -> list[DatasetGroup]:
        """The first file's group (its nodes: `own`, None = every axis), then one per other dataset file."""
        r, sets = self.run, self.run.datasets
        nodes = [ax.node_id for ax in r.axes]
        first = [n for n in nodes if own is None or n in own]
        groups = [DatasetGroup(self.ctx.pvl_path, self.pvl, self.dataset, first)]
        for src in (sets.sources[1:] if own is not None else ()):
            mine = [n for n in nodes if sets.of(n) is src]
            groups.append(DatasetGroup(src.name, src.pvl, src.dataset, mine))
        groups = [g for g in groups if g.nodes] or groups[:1]        # --pvl for every node: not the first file
        for g in groups:
            g.read_backs = {c.curve_id: curve_read_backs(r, c, set(g.nodes)) for c in g.pvl.curves}
        return groups

    def _busy_ns(self, t0: int, t1: int) -> int:
        return bus_stats(self.run.trace, self.run.bit_ns, t0, t1).busy_ns

    # ------------------------------------------------------------------ words
    def _group_of(self, node: int) -> DatasetGroup:
        """The dataset file this axis was commissioned with (its captions and curve names)."""
        return next((g for g in self.groups if node in g.nodes), None) or DatasetGroup(
            self.ctx.pvl_path, self.pvl, self.dataset, [])

    def failure_text(self, ax) -> str:
        where = self.item_text(ax)
        what = describe(ax.error_id, ax.abort_code)
        extra = ""
        if ax.fail_kind == "layer" and ax.error_id in (0x0501, 0x0502, 0x0503):
            src = next((layer for layer in self._group_of(ax.node_id).dataset.layers if layer[0] == ax.fail_item), None)
            tid, main, sub = ax.drive_layer
            if src:
                extra = (f"; the drive has tree ID {tid}, version {main}.{sub}, the dataset tree ID {src[1]}, "
                         f"version {src[2]}.{src[3]}; nothing was written")
        elif ax.error_id == 0x0603:
            extra = f"; read {ax.fail_actual:08X}h, expected {ax.fail_expected:08X}h"
        elif ax.error_id in (0x0606, 0x0607):
            limit = "maximum" if ax.error_id == 0x0606 else "minimum"
            extra = f" (the dataset's value {ax.fail_actual:08X}h, the drive's {limit} {ax.fail_expected:08X}h)"
        elif ax.error_id == 0x0608:
            extra = f" (the curves need {ax.fail_actual} bytes, CurveMemory is {ax.fail_expected})"
        elif ax.error_id == 0x030B:
            extra = f"; its last NMT state {NMT_STATES.get(ax.fail_actual, f'{ax.fail_actual:02X}h')}"
        if ax.fail_phase == "flash":
            if ax.mc_stopped:
                extra += "; the MC was left stopped (the drive refused to start it again)"
            else:
                extra += (f"; reported {ax.fail_delay_ns / 1e6:.1f} ms after the failure, once the MC ran again"
                          if ax.fail_delay_ns else "")
        phase = PHASE_TITLES.get(ax.fail_phase, ax.fail_phase)
        return f"failed in phase {phase}" + (f", {where}" if where else "") + f": ErrorID {what}{extra}"

    def item_text(self, ax) -> str:
        """FailItem in words, as FailKind says what it is (the PLC's FB_LmCommission output)."""
        kind, item, step, verifying = ax.fail_kind, ax.fail_item, ax.fail_step, ax.fail_phase == "verify"
        if kind == "layer":
            return f"layer {item} ({LAYERS[item].name})" if item in LAYERS else f"layer {item}"
        if kind == "param":
            caption = next((p.caption for o in self._group_of(ax.node_id).pvl.parameter_objects for p in o.parameters
                            if p.upid == item), "")
            return f"UPID {item:04X}h {caption}".rstrip()
        if kind == "curve":
            c = self._group_of(ax.node_id).pvl.curve(item)
            name = f" '{c.name}'" if c else ""
            if step == 0:
                part = "get request (60h)" if verifying else self._first_request(ax, {
                    0x41: "delete all curves (41h) before it", 0x50: "add request (50h)"})
            elif step <= 18:
                part = f"info word {step}"
            else:
                part = f"setpoint {step - 19}"
            return f"curve {item}{name}, {part}"
        if kind == "entry":
            if step == 0:
                part = "get request (85h)" if verifying else self._first_request(ax, {
                    0x81: "delete all entries (81h) before it", 0x83: "prepare request (83h)"})
            else:
                part = f"2-byte step {step}"
            return f"command-table entry {item}, {part}"
        if kind == "service":
            names = {0x35: "stop MC (35h)", 0x40: "save curves (40h)", 0x42: "poll flash (42h)",
                     0x80: "save / poll command table (80h)", 0x36: "start MC (36h)", 0x0B: "reset (0Bh)"}
            return names.get(item, f"service {item:02X}h")
        if kind == "dataset":
            return f"dataset word {step}"
        return ""

    def _first_request(self, ax, names: dict[int, str]) -> str:
        """Which of the requests with FailStep 0 failed: the last one the PLC sent to the node."""
        req = 0x600 + ax.node_id
        last = next((e.frame for e in reversed(self.run.trace) if e.frame.can_id == req and e.status != "error"
                     and len(e.frame.data) == 8), None)
        return names.get(last.data[3], " / ".join(names.values())) if last else " / ".join(names.values())

    # ------------------------------------------------------------------ text
    def text(self) -> str:
        f = self.figures or self.compute()
        o, run, bus, tr = f["options"], f["run"], f["bus"], f["transfer"]
        kbit = f"{o['bitrate'] / 1000:g} kbit/s"
        bus_name = ("simulated bus" if o["bus"] == "sim" else o["bus"]) + f" {kbit}"
        lines = [
            self.ctx.command,
            f"  {_n(o['axes'], 'axis', 'axes')} (node ID{'s' if o['axes'] > 1 else ''} "
            f"{', '.join(map(str, o['node_ids']))}), {bus_name}, PLC task {o['task_ms']:g} ms, backend {f['backend']} "
            f"({self.ctx.project}, build {'cached' if f['build']['cached'] else f'{self.ctx.build_s:.1f} s'})",
            *(f"  dataset{'' if len(f['datasets']) == 1 else ' ' + g['name'] + ' (nodes ' + ', '.join(map(str, g['nodes'])) + ')'}: "
              f"{_n(g['layers'], 'layer')}, {_n(g['parameters'], 'parameter')}, {_n(g['curves'], 'curve')} "
              f"({_n(g['setpoints'], 'setpoint')}), {_n(g['entries'], 'command-table entry', 'command-table entries')}"
              f" = {_n(g['words'], 'word')}" for g in f["datasets"]),
            "  options: " + ", ".join(f"{k} {'on' if o[k] else 'off'}" for k in ("live_ram", "flash", "reset", "verify", "preflight", "force"))
            + (f", drive timings {o['drive_timings']}" if o["drive_timings"] else ""),
            "",
        ]
        mixed = len(f["datasets"]) > 1
        for a in f["axes"]:
            head = f"node {a['node']}: " + (f"[{a['dataset']}] " if mixed else "")
            if a["result"] == "done":
                head += f"commissioned in {a['time_ms']:.1f} ms, {_n(a['exchanges'], 'exchange')}"
            elif a["result"] == "error":
                head += a["failure"].upper()[:1] + a["failure"][1:]
            else:
                head += "did not finish" + ("" if a["start_ms"] is not None else " (never started: no boot-up heard)")
            if a["up_ms"] is not None and a["start_ms"] is not None:
                head += f" (drive up at {a['up_ms']:.1f} ms, started {a['start_ms']:.1f} ms)"
            lines.append(head)
            it, w = a["items"], a["wear"]
            lines.append(f"  items: {it['written']} written, {it['skipped']} skipped (the drive held them), "
                         f"{it['verified']} verified"
                         + (f"; drive: {w['flash_curves'] + w['flash_ct']} flash save(s) (curves {w['flash_curves']}, "
                            f"command table {w['flash_ct']}), {w['rom_writes']} ROM write(s)" if w else ""))
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
        complete = run["necessary_exchanges"] is not None
        lines.append(f"{'all axes, one bus':<24}{'exchanges':>10}{'necessary':>11}{'time ms':>11}{'bus LB ms':>11}"
                     f"{'x LB':>8}{'bus load':>10}")
        for title, g, time_ms, load in (("transfer phases", tr, tr["time_ms"], tr["load"]),
                                        ("whole run", {**bus, "exchanges": run["exchanges"],
                                                       "necessary_exchanges": run["necessary_exchanges"]},
                                         run["time_ms"], bus["load"])):
            lb = g["lower_bound_ms"] if complete else g["lower_bound_actual_ms"]
            ratio = g["ratio"] if complete else g["ratio_actual"]
            need = g["necessary_exchanges"]
            lines.append(f"  {title:<22}{g['exchanges']:>10}{'-' if need is None else need:>11}{time_ms:>11.1f}"
                         f"{lb:>11.2f}{_r(ratio):>8}{100 * load:>8.1f} %")
        if tr.get("ratio_stuffed"):
            lines.append(f"  transfer phases, stuffed bound (the necessary frames' exact bits, stuff bits included, "
                         f"back to back): {tr['lower_bound_stuffed_ms']:.2f} ms = {_r(tr['ratio_stuffed'])} x")
        if complete:
            lines.append(f"  (bound of the actual exchanges, flash polls included: transfer phases "
                         f"{tr['lower_bound_actual_ms']:.2f} ms = {_r(tr['ratio_actual'])} x, whole run "
                         f"{bus['lower_bound_actual_ms']:.2f} ms = {_r(bus['ratio_actual'])} x)")
        elif not o["force"] and run["commissioned"]:
            lines.append("  (re-commissioning: what a run needs depends on what the drives held; the bounds count "
                         "the exchanges it made)")
        else:
            lines.append("  (the run did not complete: the bounds count the exchanges it made)")
        it = run["items"]
        lines.append(f"items, all axes: {it['written']} written, {it['skipped']} skipped, {it['verified']} verified")
        lines += [
            "",
            f"run: {run['time_ms']:.1f} ms of PLC time from the first start ({run['start_ms']:.1f} ms) to the last "
            f"end ({run['end_ms']:.1f} ms), {_n(run['exchanges'], 'exchange')}, {_n(run['scans'], 'scan')} in "
            f"{run['wall_s']:.2f} s wall"
            + (f", {run['overruns']} late scans (max {run['max_lateness_ms']:.1f} ms, {run['skipped_ticks']} ticks "
               "skipped)" if o["bus"] != "sim" else "")
            + (" - TIMED OUT" if run["timed_out"] else "")
            + (" - INTERRUPTED (Ctrl-C)" if run.get("interrupted") else "")
            + (f" - PLC FAULT: {run['plc_fault']}" if run["plc_fault"] else ""),
            f"bus: {_n(bus['frames'], 'frame')} in that time (the trace holds {bus['frames_in_trace']}, from "
            f"switch-on), busy {bus['busy_ms']:.1f} ms = load {100 * bus['load']:.1f} %"
            + (f", stuff bits add {100 * (bus['stuffing_ratio'] - 1):.1f} %" if bus["stuffing_ratio"] else ""),
            f"scan bound: one exchange per scan and drive, at least {bus['scan_bound_ms']:.0f} ms",
            "",
            *textwrap.wrap(
            f"bus LB: bus-time lower bound = exchanges x 2 frames x {SDO_FRAME_BITS} bits / {kbit} (8-byte frames "
            "without stuff bits, back to back, no device turnaround); x LB = time / bus LB. Per axis it counts that "
            "axis' exchanges; all axes share the bus, so 'all axes' counts every axis' necessary exchanges (no flash "
            "poll beyond one per store, no ROM-only retry). (drive): the phase waits for the drive's own work (MC "
            "stop/start, flash writes, boot), not for the bus.", width=110, subsequent_indent="  "),
        ]
        if f["curves"]:
            lines += ["", "curves read back (the PLC's VERIFY on the bus; else the emulated drive's RAM):"]
            for c in f["curves"]:
                parts = [f"node {n['node']} {n['verdict']}"
                         + (f" ({n['source']})" if n["source"] and n["source"] != "bus" else "") for n in c["nodes"]]
                lines.append(f"  {'[' + c['dataset'] + '] ' if mixed else ''}curve {c['curve']} '{c['name']}', "
                             f"{_n(c['setpoints'], 'setpoint')}: " + "; ".join(parts))
        v = self.verification
        lines += ["", "verification (the emulated drives' memory against the PVL file):" if not v.by_plc
                  else "verification:"]
        if v.by_plc:
            lines.append(f"  {v.by_plc}")
        if v.skipped:
            lines.append(f"  not done: {v.skipped}")
        for node in f["options"]["node_ids"]:
            checks = v.for_node(node)
            if not checks:
                continue
            same = next((c for c in checks if c.what == "drive unchanged"), None)
            if same is not None and same.ok:
                lines.append(f"  node {node}: {same.note}; drive unchanged ({same.checked} parameters, curves and "
                             "entries as when it was switched on): OK")
                continue
            parts = [f"{c.what} {c.equal}/{c.checked}" for c in checks]
            lines.append(f"  node {node}: " + ", ".join(parts) + (": OK" if v.node_ok(node) else ": DIFFERENT"))
            for c in checks:
                for diff in c.differences:
                    lines.append(f"    {c.what}: {diff}" + ("" if c.required else " (not required)"))
                if c.note:
                    lines.append(f"    {c.what}: {c.note}")
        res = f["result"]
        verdict = "PASSED" if res["passed"] else "INTERRUPTED" if run.get("interrupted") else "FAILED"
        why = []
        if not res["commissioned"]:
            bad = [str(a["node"]) for a in f["axes"] if a["result"] != "done"]
            if run.get("interrupted"):
                why.append("interrupted (Ctrl-C) before every axis finished")
            elif run["plc_fault"]:
                why.append("the PLC faulted")
            elif bad:
                why.append(f"commissioning failed on node{'s' if len(bad) > 1 else ''} {', '.join(bad)}")
        if not res["verified"]:
            why.append("verification " + ("not done" if v.skipped else "found differences"))
        lines += ["", f"result: {verdict}" + (f" ({'; '.join(why)})" if why else
                                            f" ({_n(len(f['axes']), 'axis', 'axes')} commissioned and verified)")]
        return "\n".join(lines) + "\n"

    def markdown(self) -> str:
        return (f"# Commissioning report: `{self.ctx.command}`\n\n```\n" + self.text() + "```\n\n"
                + self._files_md())

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
        """The report folder: report.md, report.json, can.<format>, curve_<id>.png. Curve plots and traces
        of an earlier report in the same folder are removed first (they would not belong to this run)."""
        folder = Path(folder)
        folder.mkdir(exist_ok=True)            # the folder named, not its parents
        for old in [*folder.glob("curve_*.png"), *(folder / f"can.{x}" for x in ("log", "asc", "blf"))]:
            old.unlink(missing_ok=True)
        f = self.figures or self.compute()
        files: dict = {"plots": []}
        trace_name = f"can.{trace_format.lstrip('.')}"
        write_trace(self.run.trace, folder / trace_name)
        files["trace"] = trace_name
        for k, g in enumerate(self.groups):
            for c in g.pvl.curves:
                # the first file's curves keep their plain names; another file's carry its number
                name = f"curve_{c.curve_id}.png" if k == 0 else f"curve_{c.curve_id}_dataset{k + 1}.png"
                plot_curve(folder / name, c, g.read_backs[c.curve_id])
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


def stuffed_bound_ns(run: RunResult, phases: tuple[str, ...], necessary: int | None) -> int:
    """The stuffed bus-time bound of the given phases of every axis: the exact bus bits (stuff bits and
    interframe space included, `bus_bits`) of the SDO requests and answers each axis exchanged in those
    phases, back to back. When the axes made more exchanges than `necessary` (retries), the necessary ones
    are counted at the mean length of the frames seen. 0 when no exchange was seen or the run was
    incomplete (necessary None)."""
    if not necessary:
        return 0
    windows = {ax.node_id: [(p.t0_ns, p.t1_ns) for p in ax.phases if p.phase in phases] for ax in run.axes}
    bits = frames = 0
    for e in run.trace:
        f = e.frame
        if e.status == "error" or f.dlc != 8 or f.rtr or not (0x581 <= f.can_id <= 0x67F):
            continue
        node = f.can_id & 0x7F
        if f.can_id - node not in (0x580, 0x600):
            continue
        if any(a <= e.start_ns < b for a, b in windows.get(node, ())):
            bits += bus_bits(f)
            frames += 1
    if not frames:
        return 0
    return round(bits * min(1.0, 2 * necessary / frames) * run.bit_ns)


def _bus_exchanges(trace, node: int, t0: int | None, t1: int | None) -> int:
    """Answers of `node` (580h + node, 8 bytes) on the bus between t0 and t1."""
    if t0 is None:
        return 0
    resp = 0x580 + node
    return sum(1 for e in trace if e.frame.can_id == resp and e.status != "error" and t0 <= e.start_ns
               and (t1 is None or e.start_ns < t1))
