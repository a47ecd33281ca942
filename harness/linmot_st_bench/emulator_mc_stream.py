"""The cost of a streaming drive: simulated seconds per wall-clock second (`make bench`, through
linmot_st_bench.emulator; `python -m linmot_st_bench.emulator_mc_stream`).

One emulated E1100 on a 1 Mbit/s SimBus with a master node that plays an NC master: it starts, enables and
homes the drive, then sends a PV stream (031xh, [MC] 4.3.39) of a 20 mm cosine stroke at 1 Hz, one setpoint per
2 ms SYNC (RxPDO2 + RxPDO3 before each SYNC). The drive's TxPDO1/TxPDO2 go on every SYNC (transmission type 1,
as [MC] 5.4 requires for streaming on CANopen), so it takes the setpoints on SYNC. The figure is simulated
seconds of streaming per wall second, best of the runs, with the same per CPU second of this process and the
load average beside it.
"""

from __future__ import annotations

import math
import os
import time

from linmot_st.bus import Frame, SimBus
from linmot_st.emulator.linmot.drive import DriveTimings, E1100Drive
from linmot_st.emulator.linmot.profile import load_profile
from linmot_st.emulator.models import make_drive
from linmot_st.protocol import commands as C

from .emulator_mc import ScriptedMaster

MS = 1_000_000
S = 1_000_000_000
PERIOD_NS = 2 * MS
LEAD_NS = 300_000                   # the setpoint's RxPDOs go this long before the SYNC
SYNC = Frame(0x080, b"")
STROKE = 200_000                    # 20 mm


class StreamMaster(ScriptedMaster):
    """The start (emulator_mc.ScriptedMaster), then one PV setpoint and a SYNC per period."""

    def __init__(self, node_id: int, start_ns: int):
        super().__init__([node_id], start_ns)
        self.node = node_id
        self.stream_from = (self.homed_at + 10 * MS) // PERIOD_NS * PERIOD_NS + PERIOD_NS
        self.next_sync = start_ns          # SYNC from the start: the drive takes its RxPDOs on SYNC
        self.next_point = self.stream_from - LEAD_NS
        self.k = 0
        self.count = 0

    def next_own_ns(self) -> int:
        return self.next_sync if self.next_sync < self.next_point else self.next_point

    def on_timer(self, t_ns):
        out = self.scripted(t_ns)
        if self.next_point <= t_ns:
            tau = self.k * PERIOD_NS / S
            w = 2 * math.pi
            p = round(STROKE * (1 - math.cos(w * tau)) / 2)
            v = round(STROKE * w * math.sin(w * tau) / 2 / 10)          # 1 um/s
            self.count = self.count % 15 + 1
            raw = C.encode(C.PV_STREAM, self.count, position=p, velocity=v)
            out += [(t_ns, Frame(0x300 + self.node, raw[:8])), (t_ns, Frame(0x400 + self.node, raw[:2] + raw[8:10]))]
            self.k += 1
            self.next_point += PERIOD_NS
        if self.next_sync <= t_ns:
            out.append((t_ns, SYNC))
            self.next_sync += PERIOD_NS
        return out


def _setup() -> tuple[SimBus, StreamMaster, E1100Drive]:
    profile = load_profile().with_defaults({0x1194: 2, 0x146F: 2_800_000, 0x146E: -100_000})
    bus = SimBus(1_000_000)
    d = make_drive("E1100", 1, profile=profile, timings=DriveTimings.fast())
    for index in (0x1800, 0x1801):     # TxPDO1/TxPDO2 on every SYNC from power-on (a master writes it in Pre-Op)
        d.comm.objects[index].subs[2].default = 1
    d.comm.reset()
    bus.attach(d, "drive1")
    d.power_on(0)
    master = StreamMaster(1, 100 * MS)
    bus.attach(master, "master")
    return bus, master, d


def simulated_per_wall(seconds: float = 5.0) -> tuple[float, dict]:
    bus, master, drive = _setup()
    bus.run_until(master.stream_from)
    if not (drive.mc.state == 8 and drive.mc.homed and drive.pdo.rx_on_sync):
        raise RuntimeError("the drive did not reach Operation Enabled, homed, RxPDOs on SYNC")
    t_end = master.stream_from + int(seconds * S)
    c0, t0 = time.process_time(), time.perf_counter()
    bus.run_until(t_end)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    mc = drive.mc
    if mc.error_code or mc.gen.kind != "stream":
        raise RuntimeError(f"the stream broke: error {mc.error_code:04X}h")
    return seconds / wall, {"per_cpu": seconds / max(cpu, 1e-9), "setpoints": master.k}


def run(runs: int = 3) -> list[dict]:
    best, best_cpu = 0.0, 0.0
    for _ in range(runs):
        x, info = simulated_per_wall()
        best, best_cpu = max(best, x), max(best_cpu, info["per_cpu"])
    what = "streaming drive (PV stream, 2 ms SYNC)"
    return [dict(name=f"{what}, simulated s per wall s", value=round(best, 1), unit="x", target=None),
            dict(name=f"{what}, simulated s per CPU s of this process (best run)", value=round(best_cpu, 1),
                 unit="x", target=None),
            dict(name=f"{what}, 1-minute load average right after ({os.cpu_count()} CPUs)",
                 value=round(os.getloadavg()[0], 2), unit="", target=None)]


if __name__ == "__main__":
    for r in run():
        print(f"{r['name']:<72} {r['value']:>10,} {r['unit']:<9}")
