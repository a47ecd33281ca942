"""Curve plots for the report: each curve as written (the PVL's setpoints) and as read back from each
drive, one PNG per curve, with the differences below (matplotlib, Agg backend: no display needed).

"Read back" is what the PLC's VERIFY phase received on the bus (the 62h upload answers in the trace);
without a verify pass it is the emulated drive's RAM, and the plot says which.
"""

from __future__ import annotations

import struct
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


def plot_curve(path: Path, curve, read_backs: list[tuple[int, list[int] | None, str]]) -> Path:
    """One PNG per curve: the curve as written, as read back from each drive (node, setpoints, source), and
    the differences below."""
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
    top.plot(xs, [v * POSITION_UNIT_MM for v in curve.setpoints], color="tab:blue", linewidth=3,
             label=f"as written ({n} setpoints, PVL)")
    verdicts = []
    styles = ["--", ":", "-.", (0, (3, 1, 1, 1))]
    colors = ["tab:orange", "tab:green", "tab:red", "tab:purple", "tab:brown", "tab:pink", "tab:olive", "tab:cyan"]
    for k, (node, back, source) in enumerate(read_backs):
        if not back:
            verdicts.append(f"node {node}: not read back")
            continue
        m = min(len(back), n)
        top.plot(xs[:m], [v * POSITION_UNIT_MM for v in back[:m]], linewidth=1.3, linestyle=styles[k % 4],
                 color=colors[k % 8],
                 marker="." if n <= 80 else None, label=f"node {node} as read back ({len(back)} setpoints, {source})")
        diff = [back[i] - curve.setpoints[i] for i in range(m)]
        bottom.plot(xs[:m], diff, linewidth=1, color=colors[k % 8], label=f"node {node}")
        bad = sum(1 for d in diff if d) + abs(len(back) - n)
        verdicts.append(f"node {node}: " + ("read back = written" if not bad else f"{bad} setpoint(s) differ"))
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
