"""Issue 22: a command-table program written by the PLC (FB_LmCtWriteFields, st_lib/services/ct.st, over SDO)
with a counter (Set / Add CT Var1, 240xh / 241xh) and an IF (IF Var1 < value, 250xh) that loops N times, started
by FB_LmStartCommandTable (200xh): the trajectory shows N strokes ([MC] 4.3.124..127, 166..211, [MC] 6)."""

from __future__ import annotations

from linmot_st.protocol import commands as C
from motionbench import MM, MotionBench

END = 0xFFFF
VAD = dict(vmax=250_000, acc=500_000, dec=500_000)        # 0.25 m/s, 5 m/s^2
OUT_MM, BACK_MM = 30, 10


def program(strokes: int) -> dict[int, tuple[int, dict, int]]:
    """entry -> (command ID, fields, link): out and back `strokes` times, counted in Var 1."""
    return {
        1: (C.SET_CT_VAR1, dict(value=0), 2),
        2: (C.VAI_GO_TO_POS, dict(target=OUT_MM * MM, **VAD), 3),
        3: (C.WAIT_MOTION_FINISHED, {}, 4),
        4: (C.VAI_GO_TO_POS, dict(target=BACK_MM * MM, **VAD), 5),
        5: (C.WAIT_MOTION_FINISHED, {}, 6),
        6: (C.ADD_CT_VAR1, dict(value=1), 7),
        7: (C.IF_VAR1_LESS, dict(value=strokes, if_true=2, if_false=8), END),
        8: (C.WAIT_MOTION_FINISHED, {}, END),
    }


def write(b: MotionBench, prog: dict) -> None:
    for entry, (cid, fields, link) in prog.items():
        pars = C.encode(cid, 0, **fields)[2:]
        r = b.fb("CTW").run(ENTRY=entry, LINK=link, HEADER=cid << 4, PARS=list(pars) + [0] * (32 - len(pars)),
                            NAME=f"E{entry}")
        assert r.done, r


def strokes_out(b: MotionBench, t0: int) -> int:
    """How often the demand reached the outer end coming from the inner one."""
    n, out = 0, False
    for s in b.drive.mc.trajectory.between(t0):
        if not out and s.demand >= OUT_MM * MM - 1:
            n, out = n + 1, True
        elif out and s.demand <= BACK_MM * MM + 1:
            out = False
    return n


def test_the_plc_writes_a_counted_loop_and_the_drive_runs_it_n_times():
    b = MotionBench(nodes=1).ready()
    assert not set(range(1, 9)) & set(b.drive.ct.ram)          # the entries come from the PLC's SDO writes
    write(b, program(3))
    assert set(range(1, 9)) <= set(b.drive.ct.ram)
    t0 = b.plc.time_ns
    r = b.fb("CT").run(ENTRY=1)
    assert r.done, r
    b.sim.run_until(lambda: 8 in b.drive.mc.ct_runner.executed and not b.drive.mc.motion_active, max_scans=20_000)
    assert strokes_out(b, t0) == 3
    assert b.drive.mc.ct_runner.executed.count(7) == 3            # the IF ran once per stroke
    assert b.drive.mc.dem_p == BACK_MM * MM                      # the demand ends on the inner end
    b.step(200)
    assert abs(b.drive.mc.axis.position - BACK_MM * MM) < 100    # the actual settled there (10 um)


def test_the_count_comes_from_the_program():
    """The same program with N = 2: two strokes (the loop is the program's, not a fixed count)."""
    b = MotionBench(nodes=1).ready()
    write(b, program(2))
    t0 = b.plc.time_ns
    assert b.fb("CT").run(ENTRY=1).done
    b.sim.run_until(lambda: 8 in b.drive.mc.ct_runner.executed and not b.drive.mc.motion_active, max_scans=20_000)
    assert strokes_out(b, t0) == 2
