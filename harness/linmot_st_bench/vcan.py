"""Real-time figures on a real SocketCAN stack (vcan0), for `make bench`: measured where this kernel has vcan0,
else inside a User-Mode Linux guest (linmot_st_vcan.Machine), else reported as not measured with the reason.

1. Expedited SDO exchanges per second between a python-can client (`RequestLoop`, one request outstanding)
   and `linmot-st emulate` in another process: the stack's and the emulator's bound, no PLC.
2. The commissioning of examples/two_axes.pvl by plc_project (`RealTimeCoSim`, 1 ms task) against
   `linmot-st emulate` in another process: PLC-to-drive exchanges per second of the run, and how close the
   co-simulation keeps to its task (late scans, worst lateness, ticks skipped).
3. The same PLC idle for 2000 scans: late scans and worst lateness with no traffic.

Run: `python -m linmot_st_bench.vcan` (or `make bench`); `--here` measures on this kernel's vcan0 and prints
the figures as JSON (what the guest runs).
"""

from __future__ import annotations

import json
import os
import sys
import tempfile
from pathlib import Path

EXCHANGES = 2000
IDLE_SCANS = 2000


def measure_here() -> list[dict]:
    """The figures, measured on this kernel's vcan0."""
    import can

    from linmot_st.bus import Frame, NodeServer
    from linmot_st.cosim import RealTimeCoSim
    from linmot_st.jobs.commission.runner import RunOptions, run
    from linmot_st.jobs.commission.testing import example, project_build
    from linmot_st.plc import Plc
    from linmot_st_bench.bus import RequestLoop
    from linmot_st_vcan.testing import EmulatedDrives

    build = project_build()
    rows = []
    with tempfile.TemporaryDirectory(prefix="linmot-st-vcan-bench-") as work:
        with EmulatedDrives([1], Path(work)):
            client = RequestLoop([Frame(0x601, bytes.fromhex("40 A2 33 01 00 00 00 00"))], 0x581, EXCHANGES,
                                 expect=(0x43,))
            with can.Bus(interface="socketcan", channel="vcan0") as bus:
                server = NodeServer(client.start_at(0), bus, name="RequestLoop").start()
                try:
                    import time
                    deadline = time.monotonic() + 120
                    while client.end_ns is None and time.monotonic() < deadline:
                        time.sleep(0.05)
                finally:
                    server.stop()
            if client.end_ns is None or client.unexpected:
                raise RuntimeError(f"request loop: {client.answers} answers, {client.unexpected} unexpected")
            rows.append(dict(name="vcan0: expedited SDO exchanges, python-can client <-> `linmot-st emulate` "
                                  "(two processes, no PLC)",
                             value=round(client.answers / ((client.end_ns - client.start_ns) / 1e9)),
                             unit="exchanges/s", target=None))
        with EmulatedDrives([1], Path(work) / "commission"):
            res = run(example(), RunOptions(bus="socketcan:vcan0", emulate=False, timings="fast"), build)
        if not res.commissioned:
            raise RuntimeError("the commissioning over vcan0 failed")
        exchanges = sum(a.exchanges for a in res.axes)
        span_s = (res.t_end_ns - res.t_start_ns) / 1e9
        rows += [
            dict(name="vcan0 commissioning (1 drive, 1 ms task): PLC <-> emulated drive exchanges per second",
                 value=round(exchanges / span_s), unit="exchanges/s", target=None),
            dict(name="vcan0 commissioning: late scans (started a tick or more late)",
                 value=round(100 * res.overruns / max(res.scans, 1), 1), unit="% of scans", target=None),
            dict(name="vcan0 commissioning: worst lateness of a scan", value=round(res.max_lateness_ns / 1e6, 2),
                 unit="ms", target=None),
            dict(name="vcan0 commissioning: task activations skipped (PLC clock kept on the wall clock)",
                 value=round(100 * res.skipped_ticks / max(res.scans + res.skipped_ticks, 1), 1),
                 unit="% of ticks", target=None),
        ]
    plc = Plc(build)
    with can.Bus(interface="socketcan", channel="vcan0") as bus:
        sim = RealTimeCoSim(plc, bus, mailbox="CONFIG0.RES0.CAN0")
        sim.step(IDLE_SCANS)
    rows += [
        dict(name=f"vcan0 idle PLC ({IDLE_SCANS} scans, 1 ms task, no traffic): late scans",
             value=round(100 * sim.overruns / sim.scans, 1), unit="% of scans", target=None),
        dict(name="vcan0 idle PLC: worst lateness of a scan", value=round(sim.max_lateness_ns / 1e6, 2),
             unit="ms", target=None),
    ]
    return rows


def run() -> list[dict]:
    from linmot_st_vcan import Machine, Unavailable, native

    load = os.getloadavg()[0]
    if native():
        where = "this kernel's vcan0"
        rows = measure_here()
    else:
        where = "User-Mode Linux guest (one CPU; a system call costs ~40 us there)"
        try:
            machine = Machine()
            with tempfile.TemporaryDirectory(prefix="linmot-st-vcan-bench-") as work:
                out = Path(work) / "figures.json"
                guest = machine.run([sys.executable, "-m", "linmot_st_bench.vcan", "--here", str(out)],
                                    timeout_s=600, work_dir=Path(work) / "guest", writable=(work,))
                if not guest.ok or not out.exists():
                    raise RuntimeError("the measurement in the guest failed\n" + guest.describe())
                rows = json.loads(out.read_text())
        except Unavailable as exc:
            return [dict(name="vcan figures", value=f"not measured: {exc}", unit="", target=None)]
    load = max(load, os.getloadavg()[0])
    return rows + [dict(name=f"vcan figures measured on: {where}; 1-minute load average ({os.cpu_count()} CPUs)",
                        value=round(load, 2), unit="", target=None)]


def main(argv: list[str]) -> int:
    if argv[:1] == ["--here"]:
        rows = measure_here()
        if len(argv) > 1:
            Path(argv[1]).write_text(json.dumps(rows))
        else:
            print(json.dumps(rows, indent=1))
        return 0
    for row in run():
        print(f"{row['name']}: {row['value']} {row['unit']}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
