"""Curve plots for the report: each curve as written (the PVL's setpoints) and as read back, one PNG per
curve and drive, with the difference below (matplotlib, Agg backend: no display needed).

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


def plot_curve(path: Path, curve, node: int, read_back: list[int] | None, source: str) -> Path:
    """One PNG: the curve as written and as read back (if any), and their difference."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    info = curve.info
    n = len(curve.setpoints)
    timed = info.object_type == 0x0003
    step = info.x_length / (n - 1) if n > 1 else 0
    scale_x = TIME_UNIT_MS if timed else 1.0
    xs = [i * step * scale_x for i in range(n)]
    written = [v * POSITION_UNIT_MM for v in curve.setpoints]
    fig, (top, bottom) = plt.subplots(2, 1, figsize=(8, 5.5), sharex=True,
                                      gridspec_kw={"height_ratios": [3, 1]})
    top.plot(xs, written, color="tab:blue", linewidth=2.5, label=f"as written ({n} setpoints, PVL)")
    verdict = "not read back"
    if read_back:
        m = min(len(read_back), n)
        back = [v * POSITION_UNIT_MM for v in read_back[:m]]
        top.plot(xs[:m], back, color="tab:orange", linewidth=1.2, linestyle="--", marker="." if n <= 80 else None,
                 label=f"as read back ({len(read_back)} setpoints, {source})")
        diff = [(read_back[i] - curve.setpoints[i]) for i in range(m)]
        bottom.plot(xs[:m], diff, color="tab:red", linewidth=1)
        bad = sum(1 for d in diff if d) + abs(len(read_back) - n)
        verdict = "read back = written" if not bad else f"{bad} setpoint(s) differ"
    bottom.axhline(0, color="grey", linewidth=0.6)
    bottom.set_ylabel("read - written\n(0.1 um)")
    top.set_ylabel("position (mm)")
    bottom.set_xlabel("time (ms)" if timed else "encoder position (increments)")
    x_len = f"{info.x_length * TIME_UNIT_MS:g} ms" if timed else f"{info.x_length} increments"
    top.set_title(f"node {node}, curve {info.curve_id} '{info.name}' ({info.kind}, {x_len})\n{verdict}", fontsize=10)
    top.grid(True, alpha=0.3)
    bottom.grid(True, alpha=0.3)
    top.legend(loc="best", fontsize=8)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path
