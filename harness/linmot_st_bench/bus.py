"""Benchmarks of the simulated bus and the co-simulation, in one process. Run: `python -m linmot_st_bench.bus`.

1. The bus alone: expedited SDO exchanges per wall-clock second between a client that keeps one request
   outstanding (`RequestLoop`) and a trivial echo node answering a fixed 43h frame. (The emulated drive's
   figure, the issue's target, is measured by `python -m linmot_st_bench.emulator` with the same client.)
2. `frame_length_bits` on distinct frames (the uncached path).
3. Co-simulation scans per wall-clock second of a compiled ST program (built with the first available
   backend) that echoes each received frame, against a node that answers each echo at once: one
   frame in and one frame out per scan, and with no traffic at all.
"""

from __future__ import annotations

import time

from linmot_st.bus.frame import Frame
from linmot_st.bus.sim import SimBus


class RequestLoop:
    """A sans-I/O client that keeps one request outstanding: it sends `requests[0]`, and each time a frame on
    `reply_id` arrives, the next request (cycling through the list) until `total` answers came.

    `answers` counts them, `unexpected` counts answers whose first byte is not in `expect` (None: any),
    `kept` holds the answers' data if `keep` is set, `start_ns` / `end_ns` bound the run in virtual time.
    """

    def __init__(self, requests: list[Frame], reply_id: int, total: int, *, expect: tuple[int, ...] | None = None,
                 keep: bool = False) -> None:
        if not requests or total < 1:
            raise ValueError("RequestLoop needs at least one request and total >= 1")
        self.requests = requests
        self.reply_id = reply_id
        self.total = total
        self.expect = None if expect is None else frozenset(expect)
        self.keep = keep
        self.answers = 0
        self.unexpected = 0
        self.kept: list[bytes] = []
        self.start_ns: int | None = None
        self.end_ns: int | None = None
        self._go: int | None = None

    def start_at(self, t_ns: int) -> RequestLoop:
        self._go = t_ns
        return self

    def on_frame(self, frame: Frame, t_ns: int):
        if frame.can_id != self.reply_id or self.end_ns is not None:
            return ()
        if self.expect is not None and (not frame.data or frame.data[0] not in self.expect):
            self.unexpected += 1
        if self.keep:
            self.kept.append(frame.data)
        self.answers += 1
        if self.answers >= self.total:
            self.end_ns = t_ns
            return ()
        return [(t_ns, self.requests[self.answers % len(self.requests)])]

    def on_timer(self, t_ns: int):
        self._go, self.start_ns = None, t_ns
        return [(t_ns, self.requests[0])]

    def next_timer_ns(self):
        return self._go


def run_loop(server, client: RequestLoop, *, bitrate: int = 500_000, settle_ns: int = 0,
             limit_ns: int | None = None) -> float:
    """Put `server` and `client` on a fresh SimBus, let the server settle (boot) for `settle_ns`, run the
    loop; returns the wall-clock seconds the loop took. RuntimeError when it did not finish."""
    bus = SimBus(bitrate)
    bus.attach(server, "server")
    bus.run_until(settle_ns)
    bus.attach(client.start_at(bus.now), "client")
    t0 = time.perf_counter()
    bus.run_until(bus.now + (limit_ns if limit_ns is not None else client.total * 5_000_000))
    wall = time.perf_counter() - t0
    if client.end_ns is None or client.unexpected:
        raise RuntimeError(f"exchange loop broke: {client.answers}/{client.total} answers, "
                           f"{client.unexpected} unexpected")
    return wall


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


def measure_echo_exchanges(total: int = 20_000, bitrate: int = 500_000) -> float:
    """Exchanges per wall-clock second of the bus alone (echo node)."""
    request = Frame(0x601, bytes([0x40, 0x18, 0x10, 0x01, 0, 0, 0, 0]))
    client = RequestLoop([request], 0x581, total, expect=(0x43,))
    return total / run_loop(EchoSdoServer(1), client, bitrate=bitrate)


def measure_bit_length(n: int = 200_000) -> float:
    """frame_length_bits() calls per second on distinct 8-byte frames (the uncached path)."""
    from linmot_st.bus.bits import frame_length_bits

    frames = [Frame(0x601, i.to_bytes(8, "little")) for i in range(1000)]
    t0 = time.perf_counter()
    for _ in range(n // 1000):
        for f in frames:
            frame_length_bits(f)
    return n / (time.perf_counter() - t0)


# the echo PLC program (each received frame sent back with Id + 1); tests/cosim/test_cosim_plc.py uses it too
ECHO_ST = """{#include "st_lib/types/can.st"}
PROGRAM Echo
  VAR_EXTERNAL
    CAN0 : T_CanMailbox;
  END_VAR
  VAR
    i : INT;
    Seen : UDINT;
  END_VAR
  i := 0;
  WHILE i < CAN0.RxCount DO   (* not FOR: MatIEC of 2024 runs FOR i := 1 TO 1 zero times (spec/matiec.md) *)
    i := i + 1;
    (* an echo is the confirmation of a frame this program sent (TxEcho): not counted, not sent back *)
    IF NOT CAN0.Rx[i].Echo THEN
      Seen := Seen + 1;
      IF CAN0.TxCount < 32 THEN
        CAN0.TxCount := CAN0.TxCount + 1;
        CAN0.Tx[CAN0.TxCount] := CAN0.Rx[i];
        CAN0.Tx[CAN0.TxCount].Id := CAN0.Rx[i].Id + 1;
      ELSE
        CAN0.TxLost := CAN0.TxLost + 1;
      END_IF;
    END_IF;
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
    from linmot_st.bus.nodes import ScriptedNode
    from linmot_st.cosim import CoSim
    from linmot_st.plc import Plc

    st_lib = Path(__file__).resolve().parents[2] / "st_lib"
    backend = "builtin" if toolchain.builtin_available() else "matiec" if toolchain.matiec_available() else None
    if backend is None or not (st_lib / "types" / "can.st").is_file():
        return [dict(name="co-simulation: skipped (no ST backend or no st_lib)", value=0, unit="", target=None)]
    rows = []
    with tempfile.TemporaryDirectory(prefix="linmot-st-cosim-bench-") as tmp:
        (Path(tmp) / "st_lib").symlink_to(st_lib)     # makes tmp the include root
        src = Path(tmp) / "echo.st"
        src.write_text(ECHO_ST)
        res = toolchain.build(str(src), backend=backend)
        for label, traffic, fast in (("1 frame in + 1 out per scan", True, True),
                                     ("no traffic, every scan from Python", False, False),
                                     ("no traffic, idle scans in C", False, True)):
            plc = Plc(res)
            bus = SimBus(500_000)
            node = ScriptedNode([(0, Frame(0x181, bytes(8)))] if traffic else [],
                                replies=lambda f, t: [(t, Frame(0x181, f.data))])
            bus.attach(node, "node")
            sim = CoSim(plc, bus, mailbox="CONFIG0.RES0.CAN0", fast_idle=fast)
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
    return [
        dict(name="simulated bus alone (echo node, 500 kbit/s): expedited SDO exchanges per wall-clock second",
             value=round(measure_echo_exchanges()), unit="exchanges/s", target=None),
        dict(name="frame bit length with exact stuffing (uncached)", value=round(measure_bit_length()),
             unit="frames/s", target=None),
        *measure_cosim(),
    ]


if __name__ == "__main__":
    for row in run():
        print(f"{row['name']}: {row['value']:,} {row['unit']} (target {row['target']})")
