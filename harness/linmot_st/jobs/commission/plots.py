"""Curve plots for the report: each curve as written (the PVL's setpoints) and as read back from each
drive, one PNG per curve, with the differences below (matplotlib, Agg backend: no display needed).

"Read back" is what the PLC's VERIFY phase received on the bus (the 62h upload answers in the trace);
without a verify pass it is the emulated drive's RAM, and the plot says which. A curve the PLC never sent to
a drive (no add request 50h in the trace, e.g. after a compatibility mismatch) is "not written" there.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path

POSITION_UNIT_MM = 1e-4          # setpoints in 0.1 um
TIME_UNIT_MS = 1e-2              # x-length of a position/time curve in 10 us


def read_back_from_trace(trace, node: int, curve_id: int, t0_ns: int = 0) -> list[int]:
    """Setpoints of a curve as the drive answered the 62h uploads of `node` after t0 (last read wins)."""
    index = 0x2000 + curve_id
    points: list[int] = []
    resp = 0x580 + node
    for e in trace:
        if e.start_ns < t0_ns or e.status == "error" or e.frame.can_id != resp:
            continue
        d = e.frame.data
        if len(d) == 8 and d[0] & 0xE0 == 0x40 and d[3] == 0x60 and d[1] | d[2] << 8 == index:
            points = []                          # a new 60h (get curve) starts the read again
        elif len(d) == 8 and d[0] & 0xE0 == 0x40 and d[3] == 0x62 and d[1] | d[2] << 8 == index:
            points.append(struct.unpack_from("<i", d, 4)[0])
    return points


def was_written(trace, node: int, curve_id: int) -> bool:
    """The PLC sent the add-curve request (50h) of this curve to `node`."""
    req, index = 0x600 + node, 0x2000 + curve_id
    return any(e.frame.can_id == req and e.status != "error" and len(e.frame.data) == 8
               and e.frame.data[0] & 0xE0 == 0x20 and e.frame.data[3] == 0x50
               and e.frame.data[1] | e.frame.data[2] << 8 == index for e in trace)


@dataclass
class ReadBack:
    """One drive's copy of one curve, as the report and the plot show it."""
    node: int
    written: bool                    # the PLC sent the curve to this drive
    setpoints: list[int] | None      # as read back (None: not read back)
    source: str                      # "bus" (the PLC's VERIFY), "drive RAM", ""
    differ: int = 0                  # setpoints read back that differ from the PVL
    verdict: str = ""


def compare(curve, node: int, written: bool, back: list[int] | None, source: str) -> ReadBack:
    """The verdict on one drive's copy of `curve` (a linmot_st.pvl Curve)."""
    n = len(curve.setpoints)
    rb = ReadBack(node, written, back or None, source if back else "")
    if not back:
        rb.verdict = "not read back" if written else "not written"
        return rb
    m = min(len(back), n)
    rb.differ = sum(1 for i in range(m) if back[i] != curve.setpoints[i])
    if len(back) == n:
        rb.verdict = "read back = written" if not rb.differ else f"{rb.differ} setpoint(s) differ"
    elif len(back) < n:
        rb.verdict = (f"{len(back)} of {n} setpoints read back (the read stopped), "
                      + (f"{rb.differ} differ" if rb.differ else "equal so far"))
    else:
        rb.verdict = f"{len(back)} setpoints read back, PVL {n}" + (f", {rb.differ} differ" if rb.differ else "")
    if not written:
        rb.verdict += " (not written by this run)"
    return rb


def curve_read_backs(run, curve, nodes=None) -> list[ReadBack]:
    """Each axis' copy of `curve` in a run (a runner.RunResult): the 62h answers of its VERIFY phase on the
    bus, else (no verify pass, or the pass did not reach the curve) the emulated drive's RAM. `nodes`: only
    these axes' (those commissioned with the curve's dataset)."""
    out = []
    for ax in run.axes:
        if nodes is not None and ax.node_id not in nodes:
            continue
        t_verify = next((p.t0_ns for p in ax.phases if p.phase == "verify"), None)
        drive = run.drives.get(ax.node_id)
        back, source = None, ""
        if t_verify is not None:
            back, source = read_back_from_trace(run.trace, ax.node_id, curve.curve_id, t_verify), "bus"
        if not back and drive is not None and curve.curve_id in drive.curves.ram:
            back, source = drive.curves.ram[curve.curve_id].setpoints, "drive RAM"
        out.append(compare(curve, ax.node_id, was_written(run.trace, ax.node_id, curve.curve_id), back, source))
    return out


def plot_curve(path: Path, curve, read_backs: list[ReadBack]) -> Path:
    """One PNG per curve: the curve as written (the PVL's setpoints), as read back from each drive, and the
    differences below; the title says each drive's verdict."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    info = curve.info
    n = len(curve.setpoints)
    timed = info.object_type == 0x0003
    step = info.x_length / (n - 1) if n > 1 else 0
    scale_x = TIME_UNIT_MS if timed else 1.0
    xs = [i * step * scale_x for i in range(n)]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True,
                                      gridspec_kw={"height_ratios": [3, 1]})
    fig.subplots_adjust(left=0.14, right=0.97, top=0.9, bottom=0.1, hspace=0.08)
    written = any(rb.written for rb in read_backs)
    top.plot(xs, [v * POSITION_UNIT_MM for v in curve.setpoints], color="tab:blue", linewidth=3,
             label=f"as written ({n} setpoints, PVL)" if written else f"PVL ({n} setpoints, to be written)")
    verdicts = []
    styles = ["--", ":", "-.", (0, (3, 1, 1, 1))]
    colors = ["tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown", "tab:pink", "tab:olive", "tab:cyan"]
    for k, rb in enumerate(read_backs):
        node, back, source = rb.node, rb.setpoints, rb.source
        verdicts.append(f"node {node}: {rb.verdict}")
        if not back:
            continue
        m = min(len(back), n)
        top.plot(xs[:m], [v * POSITION_UNIT_MM for v in back[:m]], linewidth=1.3, linestyle=styles[k % 4],
                 color=colors[k % 8],
                 marker="." if n <= 80 else None, label=f"node {node} as read back ({len(back)} setpoints, {source})")
        diff = [back[i] - curve.setpoints[i] for i in range(m)]
        bottom.plot(xs[:m], diff, linewidth=1, color=colors[k % 8], label=f"node {node}")
    bottom.axhline(0, color="grey", linewidth=0.6)
    bottom.set_ylabel("read - written\n(0.1 um)", fontsize=9)
    top.set_ylabel("position (mm)")
    bottom.set_xlabel("time (ms)" if timed else "encoder position (increments)")
    x_len = f"{info.x_length * TIME_UNIT_MS:g} ms" if timed else f"{info.x_length} increments"
    top.set_title(f"curve {info.curve_id} '{info.name}' ({info.kind}, {x_len})\n" + "; ".join(verdicts), fontsize=10)
    top.grid(True, alpha=0.3)
    bottom.grid(True, alpha=0.3)
    top.legend(loc="best", fontsize=8)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
