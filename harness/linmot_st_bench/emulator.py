"""Figures of the emulated drive (`make bench` prints them; `python -m linmot_st_bench.emulator`).

- on the simulated bus at 500 kbit/s, with a client that sends the next request when the answer arrives
  (`linmot_st_bench.bus.RequestLoop`): expedited manufacturer-object exchanges (parameter RAM read, then
  write) per wall-clock second, the issue's target (>= 50,000). The best of several runs is reported, with
  the 1-minute load average at the time: on a shared, loaded 2-core machine one run can drop far below;
- the drive alone (sans-I/O, no bus): expedited parameter reads per wall-clock second, best of the runs;
- the cost of moving axes (motion/bench.py): simulated seconds per wall second for 1 and 16 drives;
- the cost of a cam (motion/cam_bench.py): one drive following a master encoder, simulated s per wall s;
- the cost of a stream: one drive streaming PV setpoints at 2 ms SYNC (motion/stream_bench.py);
- virtual time of a 1,000-setpoint curve download with the 4-byte services (1 + 18 + 1,000 exchanges),
  back to back with no PLC, at 500 kbit/s and 1 Mbit/s (spec/can-bus-limits.md: 226..275 ms at 1 Mbit/s
  with zero turnaround, plus the turnaround per exchange).
"""

from __future__ import annotations

import os
import struct
import time

from linmot_st.bus import Frame
from linmot_st.emulator.linmot.curves import Curve
from linmot_st.emulator.linmot.drive import E1100Drive
from linmot_st.emulator.models import make_drive
from linmot_st_bench import emulator_mc as motion_bench
from linmot_st_bench import emulator_mc_cam as cam_bench
from linmot_st_bench import emulator_mc_stream as stream_bench
from linmot_st_bench.bus import RequestLoop, run_loop

S = 1_000_000_000
RUNS = 5
TARGET_EXCHANGES_PER_S = 50_000


def _booted_drive() -> tuple[E1100Drive, int]:
    drive = make_drive("E1100", 1)
    drive.power_on(0)
    return drive, drive.timings.boot_ns + 10_000_000


def measure_bus_exchanges(total: int = 10_000) -> float:
    """One run: parameter RAM read / write exchanges (13A2h) per wall-clock second on a 500 kbit/s SimBus."""
    reqs = [Frame(0x601, struct.pack("<BHBI", 0x40, 0x33A2, 1, 0)),
            Frame(0x601, struct.pack("<BHBI", 0x23, 0x33A2, 1, 100))]
    drive, boot = _booted_drive()
    client = RequestLoop(reqs, 0x581, total, expect=(0x43, 0x60))
    return total / run_loop(drive, client, settle_ns=boot)


def measure_direct(total: int = 50_000) -> float:
    """One run: parameter reads per wall-clock second through on_frame alone (no bus)."""
    drive = make_drive("E1100", 1)
    drive.power_on(0)
    drive.on_timer(drive.next_timer_ns())
    frame = Frame(0x601, struct.pack("<BHBI", 0x40, 0x33A2, 1, 0))
    t, on_frame = drive.now_ns, drive.on_frame
    t0 = time.perf_counter()
    for _ in range(total):
        t += 1_000_000
        on_frame(frame, t)
    return total / (time.perf_counter() - t0)


def _curve_requests(n: int) -> list[Frame]:
    curve = Curve.build(1, [k * 100 for k in range(n)])
    reqs = [struct.pack("<BHBHH", 0x23, 0x2001, 0x50, 70, 4 * n)]
    info = curve.info + b"\0\0"
    reqs += [struct.pack("<BHB", 0x23, 0x2001, 0x54) + info[k:k + 4] for k in range(0, 72, 4)]
    reqs += [struct.pack("<BHB", 0x23, 0x2001, 0x53) + curve.data[k:k + 4] for k in range(0, 4 * n, 4)]
    return [Frame(0x601, r) for r in reqs]


def measure_curve_download(n: int = 1000, bitrate: int = 500_000) -> float:
    """Virtual milliseconds of a curve download, request after answer, no PLC."""
    reqs = _curve_requests(n)
    drive, boot = _booted_drive()
    client = RequestLoop(reqs, 0x581, len(reqs), expect=(0x60,), keep=True)
    run_loop(drive, client, bitrate=bitrate, settle_ns=boot, limit_ns=100 * S)
    if client.kept[-1][6] != 0 or any(a[6] not in (0, 4) for a in client.kept):
        raise RuntimeError("curve download did not finish with 00h")
    return (client.end_ns - client.start_ns) / 1e6


def best_of(runs: int, measure) -> float:
    return max(measure() for _ in range(runs))


def run() -> list[dict]:
    load_before = os.getloadavg()[0]
    exchanges = best_of(RUNS, measure_bus_exchanges)
    direct = best_of(RUNS, measure_direct)
    load = max(load_before, os.getloadavg()[0])
    return [
        dict(name=f"emulator on the simulated bus (500 kbit/s): expedited parameter read/write exchanges, "
                  f"best of {RUNS} runs", value=round(exchanges), unit="exchanges/s",
             target=f">= {TARGET_EXCHANGES_PER_S}"),
        dict(name=f"emulator alone: expedited parameter reads (on_frame, no bus), best of {RUNS} runs",
             value=round(direct), unit="exchanges/s", target=None),
        dict(name=f"1-minute load average while the two figures above were measured ({os.cpu_count()} CPUs)",
             value=round(load, 2), unit="", target=None),
        dict(name="1000-setpoint curve download, 4-byte services, back to back, 500 kbit/s (virtual time)",
             value=round(measure_curve_download(1000, 500_000), 1), unit="ms", target=None),
        dict(name="1000-setpoint curve download, 4-byte services, back to back, 1 Mbit/s (virtual time)",
             value=round(measure_curve_download(1000, 1_000_000), 1), unit="ms", target=None),
    ] + motion_bench.run() + cam_bench.run() + stream_bench.run()


if __name__ == "__main__":
    for row in run():
        print(f"{row['name']}: {row['value']:,} {row['unit']} (target {row['target']})")
