"""The process-data budget of a CAN bus: how many bits per second N moving E1100 axes need from their PDOs, and
the TxPDO2 inhibit time (event mode) or SYNC period (SYNC mode) that keeps that below a share of the bit rate.

The Python twin of st_lib/motion/budget.st (FB_LmPdoBudget, which a PLC program calls before motion): the same
integer arithmetic, cross-checked by the shared vectors tests/vectors/pdo_budget.json (written from this module
by `python -m linmot_st.jobs.motion.budget --write`; tests/st_lib/motion/test_motion_budget.py runs both against them).

What is counted, per axis and second (docs/bus.md, "The process-data budget"), every frame at its worst-case
length with stuff bits (linmot_st.bus.bits.max_bus_bits: 135 bits for 8 bytes, the bound CAN load tools use):
  - TxPDO2 (280h + node, 8 bytes): on change, and a moving drive changes it every MC cycle
    (docs/emulator.md 13), so once per max(inhibit time, MC cycle); in SYNC mode once per SYNC;
  - TxPDO1 (180h + node, 8 bytes): once per event timer, plus two changes of its state var per motion
    command (accepted, done); in SYNC mode once per SYNC;
  - RxPDO2 (300h + node, 8 bytes) and RxPDO3 (400h + node, Rx3Bytes): one each per motion command;
  - RxPDO1 (200h + node, 2 bytes): the control word, once per RefreshTime;
  - SYNC (080h, no data), once per period, in SYNC mode.
Rates are kept in millihertz (integers), so that ST (UDINT) and Python compute the same figures.
"""

from __future__ import annotations

import json
from bisect import bisect_left
from dataclasses import asdict, dataclass, replace
from operator import attrgetter
from pathlib import Path

from linmot_st.bus.bits import max_bus_bits
from linmot_st.bus.stats import bus_stats, busy_per_window

EVENT, SYNC = "event", "sync"
_start = attrgetter("start_ns")           # a trace entry's start: the key the trace is sorted by
VECTORS = Path(__file__).resolve().parents[4] / "tests" / "vectors" / "pdo_budget.json"


@dataclass(frozen=True)
class BudgetInputs:
    axes: int
    bitrate: int                        # bit/s, a multiple of 1000 (every CiA 301 bit rate is)
    share_permille: int = 700           # the planned load may use this share of the bus
    mode: str = EVENT                   # EVENT: TxPDOs on change (type 254); SYNC: every SYNC (type 1)
    tx1_event_ms: int = 50              # TxPDO1 event timer (1800h sub 5), 0 = off
    commands_per_s: int = 10            # motion commands per axis and second the program issues at most
    refresh_ms: int = 100               # FB_LmPdo's RefreshTime: the control word at least this often
    rx3_bytes: int = 4                  # RxPDO3's length (2041h)
    mc_cycle_us: int = 1000             # the drive's MC cycle: TxPDO2 changes at most once per cycle
    max_interval_100us: int = 200       # the longest inhibit time / SYNC period allowed (20 ms)


@dataclass(frozen=True)
class Budget:
    fits: bool
    interval_100us: int                 # TxPDO2 inhibit time (EVENT) or SYNC period (SYNC), 100 us
    bits_per_s: int                     # planned bus bits per second (worst-case stuffing)
    load_permille: int                  # bits_per_s / bitrate, rounded up
    frames_needed: int                  # frames per second, rounded up
    frames_available: int               # frames per second of the plan's mean length that fit in the share

    def describe(self, inp: BudgetInputs) -> str:
        what = "TxPDO2 inhibit time" if inp.mode == EVENT else "SYNC period"
        return (f"{inp.axes} axes at {inp.bitrate // 1000} kbit/s: {self.frames_needed:,} frames/s needed, "
                f"{self.frames_available:,} available at {inp.share_permille / 10:g} % of the bus "
                f"({what} {self.interval_100us / 10:g} ms; planned load {self.load_permille / 10:g} %, "
                f"{self.bits_per_s:,} bit/s)")


def frame_bits(dlc: int) -> int:
    return max_bus_bits(dlc)


def load_at(inp: BudgetInputs, interval_100us: int) -> tuple[int, int]:
    """(bits per second, frames per second x 1000) of the whole bus with this inhibit time / SYNC period."""
    b8 = frame_bits(8)
    period_us = max(interval_100us * 100, inp.mc_cycle_us)
    cmd_mhz = 1000 * inp.commands_per_s
    cw_mhz = 1_000_000 // inp.refresh_ms if inp.refresh_ms > 0 else 0
    if inp.mode == SYNC:
        tx1_mhz = tx2_mhz = sync_mhz = 1_000_000_000 // period_us
    else:
        tx2_mhz = 1_000_000_000 // period_us
        tx1_mhz = (1_000_000 // inp.tx1_event_ms if inp.tx1_event_ms > 0 else 0) + 2 * cmd_mhz
        sync_mhz = 0
    axis_mbits = ((tx1_mhz + tx2_mhz + cmd_mhz) * b8 + cmd_mhz * frame_bits(inp.rx3_bytes)
                  + cw_mhz * frame_bits(2))
    axis_bits = (axis_mbits + 999) // 1000
    bits = inp.axes * axis_bits + (sync_mhz * frame_bits(0) + 999) // 1000
    frames_mhz = inp.axes * (tx1_mhz + tx2_mhz + 2 * cmd_mhz + cw_mhz) + sync_mhz
    return bits, frames_mhz


def plan_budget(inp: BudgetInputs) -> Budget:
    """The shortest inhibit time (EVENT, from 0) or SYNC period (SYNC, from the MC cycle), in 100 us steps up to
    max_interval_100us, whose planned load stays within the share; fits is False when even the longest does not."""
    if inp.axes < 1 or inp.bitrate < 1000 or inp.bitrate % 1000:
        raise ValueError(f"budget: axes >= 1 and a bit rate that is a multiple of 1000 (got {inp.axes}, "
                         f"{inp.bitrate})")
    kbit = inp.bitrate // 1000
    allowed = inp.share_permille * kbit
    interval = 0 if inp.mode == EVENT else (inp.mc_cycle_us + 99) // 100
    while True:
        bits, frames_mhz = load_at(inp, interval)
        fits = bits <= allowed
        if fits or interval >= inp.max_interval_100us:
            break
        interval += 1
    frames = (frames_mhz + 999) // 1000
    mean_bits = bits // frames if frames else frame_bits(8)       # floor: a plan that fits never shows fewer
    return Budget(fits, interval, bits, (bits + kbit - 1) // kbit, frames, allowed // mean_bits)


def job_inputs(axes: int, bitrate: int, share_percent: float = 70.0) -> BudgetInputs:
    """The motion job's (plc_project/motion.st): event mode, TxPDO1 event timer 50 ms, FB_LmPdo's defaults."""
    return BudgetInputs(axes=axes, bitrate=bitrate, share_permille=round(share_percent * 10))


class BudgetRefused(ValueError):
    """The planned process data do not fit the bus's share: the figures say by how much."""


def job_budget(axes: int, bitrate: int, share_percent: float = 70.0) -> tuple[BudgetInputs, Budget]:
    """The job's budget; BudgetRefused (with the figures) when even the longest inhibit time does not fit."""
    inp = job_inputs(axes, bitrate, share_percent)
    b = plan_budget(inp)
    if not b.fits:
        raise BudgetRefused(f"the process data do not fit the bus: {b.describe(inp)}; fewer axes, a higher bit "
                            f"rate or a larger --bus-share")
    return inp, b


# ------------------------------------------------------------------ the steps' admission (the FB steps' bursts)
# What one axis puts on the bus in a step of the motion job beyond what an idle axis sends, in its busiest 100 ms
# (plc_project/motion.st; measured per axis and step on the demo, docs/motion.md "Bus admission"):
#   commands: motion commands (RxPDO2 + RxPDO3, and two TxPDO1 state-var changes each) in those 100 ms: one for a
#     move, curve, command table (the PLC's loop runs in the drive: one command starts it); the trigger's two
#     (02Axh, 008xh), the cam's three; FB_LmJog and FB_LmMoveVelocity write the predefined VA interpolator's
#     parameters first (st_lib/motion/jog.st, velocity.st: four 002xh writes);
#   sdo: SDO exchanges (request and answer, 8 bytes each) in those 100 ms: MC_MoveVelocity reads the demand
#     velocity 1BAEh at its edge and until InVelocity (measured: 8 in the velocity step), MC_TouchProbe's reads
#     (8); the CTWRITE step writes 8 entries of 64 bytes in 2-byte SDO writes, one exchange per scan (measured:
#     101 in its busiest 100 ms);
#   moving: the axis moves (TxPDO2 at its inhibit time, the MC cycle at the least);
#   stream: PDOs on a 2 ms SYNC (the STREAM step: the setpoint's RxPDO2 + RxPDO3 each SYNC, TxPDO1 and TxPDO2
#     every STREAM_SYNC_EVERY-th SYNC, the SYNC frame itself): stream_bits(). A stream is admitted alone
#     (step_load: the whole capacity): the drive needs its SYNC and each setpoint within the 2 ms period, and the
#     PLC sends its frames through one transmit queue, so a burst of other axes' commands queued ahead of them
#     (four axes starting a move in one scan: 2 ms of frames at 500 kbit/s) delays the SYNC by a period and ends
#     the stream in 0083h (measured: 16 and 20 axes at 500 kbit/s with the streams admitted by their rate).
STREAM_SYNC_PERIOD_US = 2000
STREAM_SYNC_EVERY = 5
STEP_TRAFFIC = {                     # kind: (commands, sdo exchanges, moving) in the busiest 100 ms
    # not "stop": a stop ends a motion (the velocity move runs until it) and is never held back
    "home": (1, 0, True), "move": (1, 0, True), "curve": (1, 0, True), "ct": (1, 0, True),
    "trigger": (2, 0, True), "cam": (3, 0, True), "jog": (4, 0, True), "velocity": (4, 8, True),
    "probe": (0, 8, False), "stream": (0, 0, False), "ctwrite": (0, 100, False), "ctloop": (1, 0, True),
}


def idle_axis_bits(inp: BudgetInputs) -> int:
    """Bits per second of an axis that stands: TxPDO1 once per event timer, the control word once per refresh."""
    tx1 = 1_000_000 // inp.tx1_event_ms if inp.tx1_event_ms > 0 else 0
    cw = 1_000_000 // inp.refresh_ms if inp.refresh_ms > 0 else 0
    return (tx1 * frame_bits(8) + cw * frame_bits(2) + 999) // 1000


def step_load(kind: str, inp: BudgetInputs, interval_100us: int) -> int:
    """Bits per second an axis in a step of this kind adds to an idle axis' (0: a step the admission lets pass:
    setup, power, off, whose traffic precedes the process data or is a single frame)."""
    if kind not in STEP_TRAFFIC:
        return 0
    moving = STEP_TRAFFIC[kind][2]
    b8 = frame_bits(8)
    bits = step_burst(kind, inp)
    if moving:
        bits += 1_000_000 // max(interval_100us * 100, inp.mc_cycle_us) * b8
    if kind == "stream":
        return max(admission_capacity(inp), stream_bits(inp))
    return bits


def step_burst(kind: str, inp: BudgetInputs) -> int:
    """The part of step_load that is the step's commands and SDO exchanges (per 100 ms, as bits per second): what
    a step shorter than 100 ms leaves on the bus after its end, which FB_PlcMotion keeps planned until 100 ms
    after the step's admission (a moving step's TxPDO2 ends with its motion)."""
    if kind not in STEP_TRAFFIC:
        return 0
    commands, sdo, _ = STEP_TRAFFIC[kind]
    b8 = frame_bits(8)
    # a command: RxPDO2, RxPDO3 and its two TxPDO1 state-var changes (accepted, done); an SDO exchange: 2 frames
    return 10 * (commands * (3 * b8 + frame_bits(inp.rx3_bytes)) + 2 * sdo * b8)     # per 100 ms -> per s


def stream_bits(inp: BudgetInputs) -> int:
    """Bits per second of one axis streaming on the 2 ms SYNC (with the SYNC frames)."""
    syncs = 1_000_000 // STREAM_SYNC_PERIOD_US
    return (syncs * (frame_bits(8) + frame_bits(inp.rx3_bytes) + frame_bits(0))
            + syncs // STREAM_SYNC_EVERY * 2 * frame_bits(8))


def admission_capacity(inp: BudgetInputs) -> int:
    """Bits per second the steps may add on top of every axis standing: the share of the bit rate less the idle
    axes' process data. plc_project's FB_PlcMotion starts a step once the steps running on the other axes leave
    room for its step_load (in the order the axes asked; a step alone always runs)."""
    return max(0, inp.share_permille * (inp.bitrate // 1000) - inp.axes * idle_axis_bits(inp))


def measured_load(trace, bit_ns: int, t0_ns: int, t1_ns: int, window_ns: int = 100_000_000) -> tuple[float, float]:
    """What the bus carried in [t0, t1) (the motion job's phase): the mean load and the highest load of any
    window of window_ns (a planned load is a rate; a short burst is what overloads a bus)."""
    if t1_ns <= t0_ns:
        return 0.0, 0.0
    lo = bisect_left(trace, t0_ns - window_ns, key=_start)
    part = trace[lo:bisect_left(trace, t1_ns, lo=lo, key=_start)]
    mean = bus_stats(part, bit_ns, t0_ns, t1_ns).load
    peak = 0.0
    for t, end, busy in busy_per_window(part, bit_ns, t0_ns, t1_ns, window_ns):
        if end - t >= window_ns // 2:             # a last stub of a window says little
            peak = max(peak, busy / (end - t))    # BusStats.load of the window
    return mean, peak


# ------------------------------------------------------------------ the shared vectors
def _vector_inputs() -> list[BudgetInputs]:
    base = BudgetInputs(axes=2, bitrate=500_000)
    out = [base]
    for axes in (1, 4, 12, 16, 17, 24, 32):
        for bitrate in (250_000, 500_000, 1_000_000):
            out.append(replace(base, axes=axes, bitrate=bitrate))
    out += [replace(base, axes=32, bitrate=1_000_000, mode=SYNC), replace(base, axes=8, bitrate=500_000, mode=SYNC),
            replace(base, axes=16, bitrate=1_000_000, share_permille=500),
            replace(base, axes=16, bitrate=1_000_000, tx1_event_ms=0, commands_per_s=0, rx3_bytes=8),
            replace(base, axes=3, bitrate=125_000, refresh_ms=0, max_interval_100us=50),
            replace(base, axes=64, bitrate=1_000_000)]
    return out


def vectors() -> dict:
    rows = [dict(inputs=asdict(i), budget=asdict(plan_budget(i))) for i in _vector_inputs()]
    return {"about": "process-data budget (linmot_st.jobs.motion.budget, st_lib/motion/budget.st); written by "
                     "python -m linmot_st.jobs.motion.budget --write",
            "frame_bits": {str(d): frame_bits(d) for d in range(9)}, "vectors": rows}


if __name__ == "__main__":
    import sys

    text = json.dumps(vectors(), indent=1) + "\n"
    if "--write" in sys.argv:
        VECTORS.write_text(text)
    else:
        sys.stdout.write(text)
