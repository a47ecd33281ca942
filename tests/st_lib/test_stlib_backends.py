"""The library compiles with both backends (MatIEC's iec2c and the builtin compiler), and the two builds
put the same frames on the bus at the same times for the same scenario (differential run)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from linmot_st.emulator import build_entry
from stbench import VECTORS, Bench, available_backends, bench_build

SEED = json.loads((VECTORS / "curve_info.json").read_text())["curves"][0]


@pytest.mark.parametrize("backend", ["matiec", "builtin"])
def test_library_compiles(backend):
    if backend not in available_backends():
        pytest.skip(f"backend {backend} not available here (MatIEC's iec2c not found)" if backend == "matiec"
                    else "builtin compiler not importable")
    res = bench_build(backend)
    assert res.backend == backend and Path(res.library).exists()


def scenario(backend: str) -> list[tuple]:
    b = Bench(nodes=2, backend=backend)
    b.set_setpoints(SEED["setpoints"])
    assert b.fb("CA").run(CURVEID=23, INFO=list(bytes.fromhex(SEED["info_block"])), DATASIZE=40, TWOBYTE=True).done
    assert b.fb("CG").run(CURVEID=23).done
    assert b.fb("CTWR").run(ENTRY=3, BLOCK=list(build_entry(0x0103, bytes(range(32)), name="diff"))).done
    assert b.fb("CTRD").run(ENTRY=3)["NAME"] == "diff"
    assert b.fb("SWR").run(UPID=0x03E8, COUNT=8, TEXT="Differential").done
    assert b.fb("SRD").run(UPID=0x03E8, COUNT=8)["TEXT"] == "Differential"
    assert b.fb("LC").run(LAYER=3, SOURCE={"TREEID": 8194, "MAINVERSION": 3, "SUBVERSION": 1})["COMPATIBLE"]
    b.fb("CA2").start(CURVEID=23, INFO=list(bytes.fromhex(SEED["info_block"])), DATASIZE=40)
    b.fb("RD").start(UPID=0x1005)
    b.step(40)
    assert b.fb("CA2")["DONE"] and b.fb("RD")["DONE"]
    assert b.fb("RST").run().done
    return [(e.start_ns, e.sender, e.frame.can_id, bytes(e.frame.data)) for e in b.bus.trace]


def test_both_backends_put_the_same_frames_on_the_bus():
    backends = available_backends()
    if len(backends) < 2:
        pytest.skip(f"needs both backends, found {backends or 'none'}")
    traces = {be: scenario(be) for be in backends}
    assert traces["matiec"] == traces["builtin"]
    assert len(traces["matiec"]) > 200
