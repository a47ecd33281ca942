"""Figures of the emulated drive (`make bench` prints them; `python -m linmot_st.emulator.bench`).

- the drive alone (sans-I/O, no bus): expedited parameter reads per wall-clock second;
- on the simulated bus at 500 kbit/s with a client that sends the next request when the answer arrives:
  expedited manufacturer-object exchanges per wall-clock second (issue 3 target: >= 50,000);
- virtual time of a 1,000-setpoint curve download with the 4-byte services (1 + 18 + 1,000 exchanges),
  back to back with no PLC, at 500 kbit/s and 1 Mbit/s (spec/can-bus-limits.md: 226..275 ms at 1 Mbit/s
  with zero turnaround, plus the turnaround per exchange).
"""

from __future__ import annotations

import struct
import time

from ..bus import Frame, SimBus
from .curves import Curve
from .drive import E1100Drive

S = 1_000_000_000


class _SequenceClient:
    """Sends the requests one by one, each as soon as the previous answer has arrived."""

    def __init__(self, requests: list[bytes], node_id: int = 1):
        self.requests = [Frame(0x600 + node_id, r) for r in requests]
        self.reply_id = 0x580 + node_id
        self.answers: list[bytes] = []
        self.start: int | None = None
        self.end: int | None = None

    def on_frame(self, frame, t_ns):
        if frame.can_id != self.reply_id:
            return ()
        self.answers.append(frame.data)
        if len(self.answers) < len(self.requests):
            return [(t_ns, self.requests[len(self.answers)])]
        self.end = t_ns
        return ()

    def on_timer(self, t_ns):
        self.start, self._go = t_ns, None
        return [(t_ns, self.requests[0])]

    def next_timer_ns(self):
        return getattr(self, "_go", None)


def _run_on_bus(requests: list[bytes], bitrate: int) -> tuple[_SequenceClient, SimBus, float]:
    drive = E1100Drive(1)
    drive.power_on(0)
    bus = SimBus(bitrate)
    bus.attach(drive, "drive")
    bus.run_until(drive.timings.boot_ns + 10_000_000)
    client = _SequenceClient(requests)
    client._go = bus.now
    bus.attach(client, "client")
    t0 = time.perf_counter()
    bus.run_until(bus.now + 100 * S)
    wall = time.perf_counter() - t0
    if client.end is None:
        raise RuntimeError(f"exchange loop broke after {len(client.answers)} of {len(requests)} answers")
    return client, bus, wall


def _curve_requests(n: int) -> list[bytes]:
    curve = Curve.build(1, [k * 100 for k in range(n)])
    reqs = [struct.pack("<BHBHH", 0x23, 0x2001, 0x50, 70, 4 * n)]
    info = curve.info + b"\0\0"
    reqs += [struct.pack("<BHB", 0x23, 0x2001, 0x54) + info[k:k + 4] for k in range(0, 72, 4)]
    reqs += [struct.pack("<BHB", 0x23, 0x2001, 0x53) + curve.data[k:k + 4] for k in range(0, 4 * n, 4)]
    return reqs


def measure_direct(total: int = 50_000) -> float:
    drive = E1100Drive(1)
    drive.power_on(0)
    drive.on_timer(drive.next_timer_ns())
    frame = Frame(0x601, struct.pack("<BHBI", 0x40, 0x33A2, 1, 0))
    t, on_frame = drive.now_ns, drive.on_frame
    t0 = time.perf_counter()
    for _ in range(total):
        t += 1_000_000
        on_frame(frame, t)
    return total / (time.perf_counter() - t0)


def measure_bus_exchanges(total: int = 20_000) -> float:
    reqs = [struct.pack("<BHBI", 0x40, 0x33A2, 1, 0), struct.pack("<BHBI", 0x23, 0x33A2, 1, 100)] * (total // 2)
    client, _, wall = _run_on_bus(reqs, 500_000)
    if any(a[0] not in (0x43, 0x60) for a in client.answers):
        raise RuntimeError("unexpected answer in the exchange loop")
    return total / wall


def measure_curve_download(n: int = 1000, bitrate: int = 500_000) -> float:
    client, _, _ = _run_on_bus(_curve_requests(n), bitrate)
    if client.answers[-1][6] != 0 or any(a[6] not in (0, 4) for a in client.answers):
        raise RuntimeError("curve download did not finish with 00h")
    return (client.end - client.start) / 1e6


def run() -> list[dict]:
    return [
        dict(name="emulator alone: expedited parameter reads (on_frame, no bus)", value=round(measure_direct()),
             unit="exchanges/s", target=None),
        dict(name="emulator on the simulated bus (500 kbit/s): expedited parameter read/write exchanges",
             value=round(measure_bus_exchanges()), unit="exchanges/s", target=">= 50000"),
        dict(name="1000-setpoint curve download, 4-byte services, back to back, 500 kbit/s (virtual time)",
             value=round(measure_curve_download(1000, 500_000), 1), unit="ms", target=None),
        dict(name="1000-setpoint curve download, 4-byte services, back to back, 1 Mbit/s (virtual time)",
             value=round(measure_curve_download(1000, 1_000_000), 1), unit="ms", target=None),
    ]


if __name__ == "__main__":
    for row in run():
        print(f"{row['name']}: {row['value']:,} {row['unit']} (target {row['target']})")
