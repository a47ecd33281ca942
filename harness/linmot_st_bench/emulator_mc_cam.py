"""The cost of a cam motion: one emulated E1100 following a master encoder with an encoder cam (modulo mode, one
cam per revolution of an 8000-count encoder turning at 2 revolutions/s), on a 1 Mbit/s SimBus with a SYNC every
4 ms and TxPDO2 on every SYNC, as the motion bench (bench.py). The figure is simulated seconds per wall second,
best of the runs (`make bench`; `python -m linmot_st_bench.emulator_mc_cam`).
"""

from __future__ import annotations

import time

from linmot_st.emulator.linmot.curves import Curve
from linmot_st.emulator.linmot.master_encoder import ConstantSpeed
from linmot_st.protocol import commands as C
from linmot_st.protocol import upids as U
from linmot_st_bench.emulator_mc import S, _setup

SETPOINTS = [0, 100_000, 400_000, 500_000, 400_000, 100_000, 0]    # 0 -> 50 mm -> 0 over one revolution


def simulated_per_wall(seconds: float = 5.0) -> tuple[float, float]:
    """One run: simulated seconds per wall second and per CPU second of this process."""
    bus, master, (drive,) = _setup(1)
    master.next_move = 1 << 62                                      # no VAI moves: the cam moves the axis
    bus.run_until(master.moves_from)
    mc = drive.mc
    if not (mc.state == 8 and mc.homed):
        raise RuntimeError("the drive did not reach Operation Enabled, homed")
    for upid, value in ((U.P_MASTER_ENCODER_SOURCE, 1), (U.P_CAM_MODE, 1)):
        drive.params[upid].ram = value
    drive.curves.ram[1] = Curve.build(1, SETPOINTS, x_length=8000, object_type=0x0103, x_dim=0x001B)
    t = master.moves_from
    for n, (cid, fields) in enumerate(((C.cam_command(1, C.CAM_DEFINE_FROM_ACT_POS), dict(curve_id=1, start_count=0)),
                                      (C.cam_command(1, C.CAM_Y_ENABLE), {}), (C.ENCODER_CAM_ENABLE, {}))):
        raw = C.encode(cid, n + 1, **fields)
        mc.command_image(int.from_bytes(raw[:2], "little"), raw[2:], t)
    mc.encoder.drive_with(ConstantSpeed(16_000, t0_ns=t), t)
    t_end = t + int(seconds * S)
    t0, c0 = time.perf_counter(), time.process_time()
    bus.run_until(t_end)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    top = max(s.demand for s in mc.trajectory.between(t, t_end))
    if mc.error_code or top < mc.trajectory.between(t, t)[0].demand + 400_000:
        raise RuntimeError(f"the cam did not run (error {mc.error_code:04X}h)")
    return seconds / wall, seconds / max(cpu, 1e-9)


def run(runs: int = 3) -> list[dict]:
    figures = [simulated_per_wall() for _ in range(runs)]
    return [dict(name="cam following a master encoder: 1 drive, simulated s per wall s", value=round(
                 max(w for w, _ in figures), 1), unit="x", target=None),
            dict(name="cam following a master encoder: 1 drive, simulated s per CPU s of this process",
                 value=round(max(c for _, c in figures), 1), unit="x", target=None)]


if __name__ == "__main__":
    for r in run():
        print(f"{r['name']:<72} {r['value']:>10,} {r['unit']}")
