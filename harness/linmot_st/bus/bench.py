"""Benchmark of the simulated bus: expedited SDO exchanges per wall-clock second, in one process.

A client node sends an expedited upload request (40h, object 1018h sub 1: the vendor ID), waits
for the answer, sends the next one; the server is the emulated E1100 drive when
`linmot_st.emulator.E1100Drive` exists, else a trivial echo node that answers every request with a
fixed 43h frame (then the figure measures the bus alone, and its name says so). Nothing but the
two nodes runs: no PLC. Run: `python -m linmot_st.bus.bench`.
"""

from __future__ import annotations

import time

from .frame import Frame
from .sim import SimBus

TARGET_EXCHANGES_PER_S = 50_000


class SdoReadLoop:
    """A sans-I/O client that keeps one expedited SDO upload outstanding until `total` answers came."""

    def __init__(self, node_id: int, index: int, subindex: int, total: int) -> None:
        self.request = Frame(0x600 + node_id, bytes([0x40, index & 0xFF, index >> 8, subindex, 0, 0, 0, 0]))
        self.reply_id = 0x580 + node_id
        self.total = total
        self.answers = 0
        self.unexpected = 0
        self._start: int | None = 0

    def on_frame(self, frame: Frame, t_ns: int):
        if frame.can_id != self.reply_id:
            return ()
        if frame.data[:1] != b"\x43":
            self.unexpected += 1
        self.answers += 1
        return [(t_ns, self.request)] if self.answers < self.total else ()

    def on_timer(self, t_ns: int):
        self._start = None
        return [(t_ns, self.request)]

    def next_timer_ns(self):
        return self._start


class EchoSdoServer:
    """Answers every SDO request to its node with a fixed expedited upload response (no object dictionary)."""

    def __init__(self, node_id: int = 1) -> None:
        self.request_id = 0x600 + node_id
        self.reply = Frame(0x580 + node_id, bytes([0x43, 0x18, 0x10, 0x01, 0x56, 0x01, 0, 0]))

    def on_frame(self, frame: Frame, t_ns: int):
        return [(t_ns, self.reply)] if frame.can_id == self.request_id else ()

    def on_timer(self, t_ns: int):
        return ()

    def next_timer_ns(self):
        return None


def _server():
    """The real drive when the emulator exists, else the echo node; and a label saying which."""
    try:
        from linmot_st.emulator import E1100Drive
    except ImportError:
        return EchoSdoServer(1), "echo node (E1100Drive not available)"
    drive = E1100Drive(node_id=1)
    return drive, "E1100Drive"


def measure_exchanges(total: int = 20_000, bitrate: int = 500_000) -> dict:
    server, label = _server()
    bus = SimBus(bitrate)
    if hasattr(server, "power_on"):
        server.power_on(0)
    bus.attach(server, "drive")
    # let a drive boot (boot-up message, NMT state) before the clock starts
    bus.run_until(5_000_000_000 if hasattr(server, "power_on") else 0)
    client = SdoReadLoop(1, 0x1018, 1, total)
    client._start = bus.now
    bus.attach(client, "client")
    t0 = time.perf_counter()
    bus.run_until(bus.now + total * 10_000_000)   # far beyond the last answer; the loop ends when idle
    wall = time.perf_counter() - t0
    if client.answers != total or client.unexpected:
        raise RuntimeError(f"benchmark loop broke: {client.answers}/{total} answers, "
                           f"{client.unexpected} not 43h")
    return {"label": label, "exchanges": total, "wall_s": wall, "rate": total / wall}


def measure_bit_length(n: int = 200_000) -> float:
    """frame_length_bits() calls per second on distinct 8-byte frames (the uncached path)."""
    from .bits import frame_length_bits

    frames = [Frame(0x601, i.to_bytes(8, "little")) for i in range(1000)]
    t0 = time.perf_counter()
    for _ in range(n // 1000):
        for f in frames:
            frame_length_bits(f)
    return n / (time.perf_counter() - t0)


def run() -> list[dict]:
    ex = measure_exchanges()
    return [
        dict(name=f"simulated bus: expedited SDO exchanges per wall-clock second, {ex['label']}",
             value=round(ex["rate"]), unit="exchanges/s", target=f">= {TARGET_EXCHANGES_PER_S}"),
        dict(name="frame bit length with exact stuffing (uncached)", value=round(measure_bit_length()),
             unit="frames/s", target=None),
    ]


if __name__ == "__main__":
    for row in run():
        print(f"{row['name']}: {row['value']:,} {row['unit']} (target {row['target']})")
