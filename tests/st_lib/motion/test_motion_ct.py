"""A command-table sequence written with the ST library's CT service (FB_LmCtWrite, on the PLC) and started with
200xh over RxPDO2/3: the emulated drive runs the linked entries in order, with their waits."""

from __future__ import annotations

import struct

from linmot_st.bus.frame import Frame
from linmot_st.emulator import DriveTimings, build_entry, load_profile
from linmot_st.protocol import commands as C
from stbench import Bench

MS = 1_000_000
MM = 10_000


def pars(cid: int, **fields) -> bytes:
    return C.encode(cid, 0, **fields)[2:]


SEQUENCE = {
    # entry: (header, parameters, link)
    1: (C.VAI_GO_TO_POS << 4, pars(C.VAI_GO_TO_POS, target=50 * MM, vmax=500_000, acc=500_000, dec=500_000), 2),
    2: (C.WAIT_IN_TARGET_POSITION << 4, b"", 3),
    3: (C.WAIT_TIME << 4, pars(C.WAIT_TIME, time=1000), 4),                   # 100 ms
    4: (C.PREDEF_VAI_GO_TO_POS << 4, pars(C.PREDEF_VAI_GO_TO_POS, target=10 * MM), 5),
    5: (C.WAIT_MOTION_FINISHED << 4, b"", 0xFFFF),
}


def test_sequence_written_by_the_library_runs_with_its_waits():
    profile = load_profile().with_defaults({0x1194: 2, 0x14BE: 250_000, 0x14BF: 500_000, 0x14C0: 500_000})
    b = Bench(nodes=1, timings=DriveTimings.fast(), drive_kwargs={"profile": profile})
    for entry, (header, params, link) in SEQUENCE.items():
        r = b.fb("CTWR").run(ENTRY=entry, BLOCK=list(build_entry(header, params, link=link, name=f"step{entry}")))
        assert r.done, r
    d = b.drive
    assert sorted(d.ct.ram) == [1, 2, 3, 4, 5]

    tester = b.bus.endpoint("tester")

    def send(can_id: int, data: bytes, scans: int = 1) -> None:
        tester.send(Frame(can_id, data), b.bus.now)
        b.step(scans)

    send(0x201, struct.pack("<H", 0x003E), 2)
    send(0x201, struct.pack("<H", 0x003F), 30)
    assert d.mc.state == 8
    send(0x201, struct.pack("<H", 0x083F), 5)
    assert d.mc.state_var == 0x090F
    send(0x201, struct.pack("<H", 0x003F), 2)
    start = C.encode(C.START_COMMAND_TABLE, 1, entry=1).ljust(10, b"\0")
    t0 = b.bus.now
    tester.send(Frame(0x301, start[:8]), t0)
    send(0x401, start[:2] + start[8:10])
    assert d.mc.ct_runner.running and d.mc.motion_active             # INFERRED: Motion Active while the table runs
    b.sim.run_until(lambda: not d.mc.ct_runner.running, max_scans=5000)
    assert d.mc.ct_runner.executed == [1, 2, 3, 4, 5]

    samples = d.mc.trajectory.between(t0)
    reached = next(s.t_ns for s in samples if s.status_word & 0x0400 and abs(s.actual - 50 * MM) < 1000)
    left = next(s.t_ns for s in samples if s.t_ns > reached and s.demand < 50 * MM - 1)
    # 50 mm at 0.5 m/s, 5 m/s^2: 0.2 s; in target, then 100 ms of waiting, then the predefined VAI back to 10 mm
    assert 0.2e9 <= reached - t0 <= 0.25e9
    assert 100 * MS <= left - reached <= 100 * MS + 2 * MS
    assert d.mc.dem_p == 10 * MM and not d.mc.motion_active
    # the PLC saw the count echo of the 200xh command once the sequence ended
    assert d.mc.state_var & 0x0F == 1
