"""Benchmarks of the simulated bus and the co-simulation, in one process. Run: `python -m linmot_st.bus.bench`.

1. Expedited SDO exchanges per wall-clock second: a client node sends an expedited upload request
   (40h, RAM value of a parameter: object 2000h + UPID 13A2h, sub 1), waits for the answer, sends the
   next one; the server is the emulated E1100 drive, or, where `linmot_st.emulator` is missing, a
   trivial echo node answering a fixed 43h frame (the figure's name says which). No PLC.
2. Co-simulation scans per wall-clock second of a compiled ST program (built with the first available
   backend) that echoes each received frame, against a node that answers each echo at once: one
   frame in and one frame out per scan, and with no traffic at all.
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


BENCH_UPID = 0x13A2   # a parameter of the default E1100 profile


def _server():
    """The real drive when the emulator exists, else the echo node; a label saying which; its boot time."""
    try:
        from linmot_st.emulator import E1100Drive
    except ImportError:
        return EchoSdoServer(1), "echo node (E1100Drive not available)", 0
    drive = E1100Drive(node_id=1)
    drive.power_on(0)
    return drive, "E1100Drive, parameter RAM reads", drive.timings.boot_ns + 10_000_000


def measure_exchanges(total: int = 20_000, bitrate: int = 500_000) -> dict:
    server, label, boot_ns = _server()
    bus = SimBus(bitrate)
    bus.attach(server, "drive")
    bus.run_until(boot_ns)   # let a drive boot (boot-up message, NMT state) before the clock starts
    client = SdoReadLoop(1, 0x2000 + BENCH_UPID, 1, total)
    client._start = bus.now
    bus.attach(client, "client")
    t0 = time.perf_counter()
    bus.run_until(bus.now + total * 5_000_000)   # beyond the last answer (about 0.5 ms per exchange)
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


ECHO_ST = """{#include "st_lib/types/can.st"}
PROGRAM Echo
  VAR_EXTERNAL
    CAN0 : T_CanMailbox;
  END_VAR
  VAR
    i : INT;
  END_VAR
  i := 0;
  WHILE i < CAN0.RxCount AND CAN0.TxCount < 32 DO
    i := i + 1;
    CAN0.TxCount := CAN0.TxCount + 1;
    CAN0.Tx[CAN0.TxCount] := CAN0.Rx[i];
    CAN0.Tx[CAN0.TxCount].Id := CAN0.Rx[i].Id + 1;
  END_WHILE;
END_PROGRAM

CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    VAR_GLOBAL
      CAN0 : T_CanMailbox;
    END_VAR
    TASK Main(INTERVAL := T#1ms, PRIORITY := 0);
    PROGRAM Inst0 WITH Main : Echo;
  END_RESOURCE
END_CONFIGURATION
"""


def measure_cosim(scans: int = 20_000) -> list[dict]:
    """Scans per second of CoSim with the echo program; [] with a reason row if no backend can build it."""
    import tempfile
    from pathlib import Path

    from linmot_st import toolchain
    from linmot_st.cosim import CoSim
    from linmot_st.plc import Plc

    from .nodes import ScriptedNode

    st_lib = Path(__file__).resolve().parents[3] / "st_lib"
    backend = "builtin" if toolchain.builtin_available() else "matiec" if toolchain.matiec_available() else None
    if backend is None or not (st_lib / "types" / "can.st").is_file():
        return [dict(name="co-simulation: skipped (no ST backend or no st_lib)", value=0, unit="", target=None)]
    rows = []
    with tempfile.TemporaryDirectory(prefix="linmot-st-cosim-bench-") as tmp:
        (Path(tmp) / "st_lib").symlink_to(st_lib)     # makes tmp the include root
        src = Path(tmp) / "echo.st"
        src.write_text(ECHO_ST)
        res = toolchain.build(str(src), backend=backend)
        for label, traffic in (("1 frame in + 1 out per scan", True), ("no traffic", False)):
            plc = Plc(res)
            bus = SimBus(500_000)
            node = ScriptedNode([(0, Frame(0x181, bytes(8)))] if traffic else [],
                                replies=lambda f, t: [(t, Frame(0x181, f.data))])
            bus.attach(node, "node")
            sim = CoSim(plc, bus, mailbox="CONFIG0.RES0.CAN0")
            sim.step(100)
            t0 = time.perf_counter()
            sim.step(scans)
            wall = time.perf_counter() - t0
            if traffic and sim.frames_received < scans:
                raise RuntimeError(f"co-simulation benchmark broke: {sim.frames_received} frames in {scans} scans")
            rows.append(dict(name=f"co-simulation scans per wall-clock second, {label} ({backend})",
                             value=round(scans / wall), unit="scans/s", target=None))
    return rows


def run() -> list[dict]:
    ex = measure_exchanges()
    return [
        dict(name=f"simulated bus: expedited SDO exchanges per wall-clock second, {ex['label']}",
             value=round(ex["rate"]), unit="exchanges/s", target=f">= {TARGET_EXCHANGES_PER_S}"),
        dict(name="frame bit length with exact stuffing (uncached)", value=round(measure_bit_length()),
             unit="frames/s", target=None),
        *measure_cosim(),
    ]


if __name__ == "__main__":
    for row in run():
        print(f"{row['name']}: {row['value']:,} {row['unit']} (target {row['target']})")
