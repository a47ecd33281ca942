"""The motion job's report: per axis and step the time, the PLC scans and the frames; each check with its
figures; what was not run and why; written as text (stdout), Markdown, JSON, and a PNG per axis (demand and
actual position over time with each curve as written overlaid where it ran, and the following error)."""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

from linmot_st.protocol.errors import describe

from .check import MotionCheck, stream_position
from .job import MotionResult
from .plan import MM

NODE_IDS = (0x180, 0x200, 0x280, 0x300, 0x380, 0x400, 0x580, 0x600, 0x700)


def _frames(trace, node: int, t0: int, t1: int) -> int:
    ids = {base + node for base in NODE_IDS} | {0x080, 0x000}
    return sum(1 for e in trace if e.frame.can_id in ids and t0 <= e.start_ns < t1 and e.status != "error")


class MotionReport:
    def __init__(self, motion: MotionResult, check: MotionCheck, trace, drives: dict):
        self.m, self.c, self.trace, self.drives = motion, check, trace, drives
        self.offsets = motion.clock_offsets

    @property
    def passed(self) -> bool:
        return self.m.finished and self.c.passed

    def rows(self) -> list[dict]:
        checks = {(s.axis, s.index): s for s in self.c.steps}
        out = []
        for ax in self.m.axes:
            for r in ax.steps:
                chk = checks.get((ax.axis, r.index))
                out.append(dict(axis=ax.axis, node=ax.node_id, step=r.index, kind=r.kind, label=r.label,
                                start_ms=round(r.t0_ns / 1e6, 1), time_ms=round(r.duration_ns / 1e6, 1),
                                scans=r.scans, frames=_frames(self.trace, ax.node_id, r.t0_ns, r.t1_ns),
                                ok=bool(chk and chk.ok), check=chk.what if chk else "",
                                stroke=self._where(r.index),
                                error=describe(r.error_id) if r.error_id else ""))
        return out

    def _where(self, index: int) -> str:
        span, stroke = self.m.plan.steps[index - 1].span_mm, self.m.plan.stroke
        return stroke.where(*span) if span is not None and stroke is not None else ""

    def figures(self) -> dict:
        stroke = self.m.plan.stroke
        return {"passed": self.passed, "axes": len(self.m.axes), "steps": len(self.m.plan.steps),
                "stroke": stroke.describe() if stroke else "",
                "stroke_mm": [stroke.negative_mm, stroke.positive_mm] if stroke else None,
                "plc_time_ms": round((self.m.t1_ns - self.m.t0_ns) / 1e6, 1), "scans": self.m.scans,
                "wall_s": round(self.m.wall_s, 3), "timed_out": self.m.timed_out,
                "not_run": self.m.plan.not_run, "rows": self.rows(),
                "checks": [asdict(s) for s in self.c.steps]}

    def text(self) -> str:
        f = self.figures()
        lines = [f"motion job: {'PASSED' if f['passed'] else 'FAILED'}: {f['axes']} axis/axes, {f['steps']} steps "
                 f"each, {f['plc_time_ms'] / 1000:.2f} s of PLC time in {f['scans']} scans, "
                 f"{f['wall_s']:.1f} s wall" + (" (timed out)" if f["timed_out"] else "")]
        if f["stroke"]:
            lines.append(f"  {f['stroke']}")
        for ax in self.m.axes:
            lines.append(f"  axis {ax.axis} (node {ax.node_id}):"
                         + (f" FAILED at step {ax.fail_step}: {describe(ax.error_id)}"
                            + (f", drive error {ax.drive_error:04X}h" if ax.drive_error else "") if ax.error else ""))
            lines.append(f"    {'#':>2}  {'step':<58} {'time ms':>9} {'scans':>6} {'frames':>6}  "
                         f"{'in the stroke':<38}  result")
            for r in (r for r in f["rows"] if r["axis"] == ax.axis):
                lines.append(f"    {r['step']:>2}  {r['label'][:58]:<58} {r['time_ms']:>9.1f} {r['scans']:>6} "
                             f"{r['frames']:>6}  {r['stroke']:<38}  "
                             f"{'ok' if r['ok'] else 'FAILED'}: {r['check'] or r['error']}")
        for item in f["not_run"]:
            lines.append(f"  not run: {item}")
        return "\n".join(lines) + "\n"

    def markdown(self) -> str:
        f = self.figures()
        md = [f"# Motion job: {'PASSED' if f['passed'] else 'FAILED'}", "",
              f"{f['axes']} axis/axes, {f['steps']} steps each, {f['plc_time_ms'] / 1000:.2f} s of PLC time in "
              f"{f['scans']} scans ({f['wall_s']:.1f} s wall).", ""] + ([f"The axis: {f['stroke']}.", ""]
                                                                         if f["stroke"] else [])
        for ax in self.m.axes:
            md += [f"## Axis {ax.axis} (node {ax.node_id})", "", f"![axis {ax.axis}](motion-axis{ax.axis}.png)", "",
                   "| # | step | start ms | time ms | scans | frames | in the stroke | result |",
                   "|---|---|---|---|---|---|---|---|"]
            for r in (r for r in f["rows"] if r["axis"] == ax.axis):
                md.append(f"| {r['step']} | {r['label']} | {r['start_ms']} | {r['time_ms']} | {r['scans']} | "
                          f"{r['frames']} | {r['stroke']} | {'ok' if r['ok'] else 'FAILED'}: "
                          f"{r['check'] or r['error']} |")
            md.append("")
        if f["not_run"]:
            md += ["## Not run", ""] + [f"- {x}" for x in f["not_run"]] + [""]
        return "\n".join(md)

    def plot(self, path: Path, ax) -> Path:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt

        drive = self.drives[ax.node_id]
        off = self.offsets.get(ax.node_id, 0)          # drive time - PLC time
        t0 = self.m.t0_ns
        samples = drive.mc.trajectory.between(t0 + off, self.m.t1_ns + off)
        t = [(s.t_ns - off - t0) / 1e9 for s in samples]
        fig, (top, mid, bottom) = plt.subplots(3, 1, figsize=(11, 9), sharex=True, height_ratios=(3, 1.5, 1))
        top.plot(t, [s.demand / MM for s in samples], label="demand", linewidth=1.0)
        top.plot(t, [s.actual / MM for s in samples], label="actual", linewidth=1.0, alpha=0.8)
        labelled = False
        for chk in self.c.steps:
            if chk.axis == ax.axis and chk.kind == "curve" and chk.t_exec_ns is not None:
                run = self.m.plan.steps[chk.index - 1].curve
                n = 200
                xs = [chk.t_exec_ns + run.duration_ns * k // n for k in range(n + 1)]
                top.plot([(x - t0) / 1e9 for x in xs], [run.position(x - chk.t_exec_ns) / MM for x in xs], "k--",
                         linewidth=0.8, label=None if labelled else "curve as written (PVL)")
                labelled = True
            if chk.axis == ax.axis and chk.kind == "stream" and chk.t_exec_ns is not None:
                step = self.m.plan.steps[chk.index - 1]
                n = 200
                xs = [chk.t_exec_ns + step.hold_ms * 1_000_000 * k // n for k in range(n + 1)]
                top.plot([(x - t0) / 1e9 for x in xs], [stream_position(step, x - chk.t_exec_ns) / MM for x in xs],
                         ":", color="k", linewidth=0.9, label="the PLC's sine, 1.5 SYNC periods late")
            if chk.axis == ax.axis and chk.kind == "ctloop":
                # the PLC's command-table loop: its two ends over the step, the strokes it counted
                r = next(r for r in ax.steps if r.index == chk.index)
                step = self.m.plan.steps[chk.index - 1]
                xs = [(r.t0_ns - t0) / 1e9, (r.t1_ns - t0) / 1e9]
                for k, y in enumerate((step.position_mm, step.back_mm)):
                    top.plot(xs, [y, y], "-.", color="tab:olive", linewidth=0.8,
                             label=None if k else f"the PLC's command-table loop: {step.count} x between these")
        for r in ax.steps:
            top.axvline((r.t0_ns - t0) / 1e9, color="0.85", linewidth=0.6)
        # the input edges the job raised (trigger X4.6, capture X4.5) and the position the PLC read on X4.5
        edges = [r for r in ax.steps if r.edge_ns]
        for k, r in enumerate(edges):
            x = (r.edge_ns - off - t0) / 1e9
            top.axvline(x, color="tab:purple", linestyle=":", linewidth=1.0,
                        label=None if k else "the job: input edge (X4.6, X4.5) or conveyor start")
            if r.probed_mm is not None:
                top.plot([x], [r.probed_mm], "o", color="tab:purple", markersize=5,
                         label="position captured (MC_TouchProbe)")
        mid.plot(t, [s.demand_velocity / MM for s in samples], color="tab:green", linewidth=0.8)
        mid.set_ylabel("demand velocity (mm/s)")
        top.set_ylabel("position (mm)")
        top.set_title(f"axis {ax.axis} (node {ax.node_id}): the motion job")
        top.legend(loc="best")
        bottom.plot(t, [(s.demand - s.actual) / MM for s in samples], color="tab:red", linewidth=0.8)
        bottom.set_ylabel("following error (mm)")
        bottom.set_xlabel("time since the motion program started (s)")
        fig.tight_layout()
        fig.savefig(path, dpi=90)
        plt.close(fig)
        return path

    def write(self, folder: Path) -> list[Path]:
        folder.mkdir(parents=True, exist_ok=True)
        files = [folder / "motion.md", folder / "motion.json"]
        files[0].write_text(self.markdown())
        files[1].write_text(json.dumps(self.figures(), indent=2))
        for ax in self.m.axes:
            if ax.node_id in self.drives:
                files.append(self.plot(folder / f"motion-axis{ax.axis}.png", ax))
        return files


class MotionProgress:
    """One stderr line per finished step and axis."""

    def __init__(self, out):
        self.out = out

    def step_done(self, ax, rec) -> None:
        print(f"  axis {ax.axis}: step {rec.index} {rec.label}: {rec.duration_ns / 1e6:.0f} ms, {rec.scans} scans",
              file=self.out, flush=True)
