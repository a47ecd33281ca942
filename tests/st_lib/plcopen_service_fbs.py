"""The configuration (service) FBs of the one PLCopen suite (tests/st_lib/test_plcopen.py): the table of FBs
with their inputs, and how a run of them is seen and disturbed on the configuration testbench (SDO)."""

from __future__ import annotations

import json
from collections.abc import Callable
from dataclasses import dataclass, field

from linmot_st.emulator import build_entry
from plcopen_checks import requests
from stbench import VECTORS, Bench

MS = 1_000_000
SEED = json.loads((VECTORS / "curve_info.json").read_text())["curves"][0]
SEED_INFO = list(bytes.fromhex(SEED["info_block"]))
ENTRY = list(build_entry(0x0103, bytes(32), name="conf"))


def seed_setpoints(b: Bench) -> None:
    b.set_setpoints(SEED["setpoints"])


def seed_curve_on_drive(b: Bench) -> None:
    seed_setpoints(b)
    assert b.fb("CA").run(CURVEID=23, INFO=SEED_INFO, DATASIZE=40).done


def ct_entry_on_drive(b: Bench) -> None:
    assert b.fb("CTWR").run(ENTRY=5, BLOCK=ENTRY).done


@dataclass
class Spec:
    name: str
    inputs: dict
    alt: dict | None = None                  # other inputs, set while Busy: must change nothing
    bad: dict | None = None                  # invalid inputs: Error before any frame
    setup: Callable[[Bench], None] | None = None
    abort: bool = False                      # has Abort / CommandAborted
    fail: dict = field(default_factory=dict)  # extra inputs for the timeout error run
    polls: bool = False                      # polls a busy drive: the number of polls depends on timing


SPECS = [
    Spec("RD", dict(UPID=0x1005, MEM="LM_RAM"), dict(UPID=0x1018, MEM="LM_ROM"), dict(UPID=0x4000)),
    Spec("WR", dict(UPID=0x1005, VALUE=1500, MEM="LM_RAM"), dict(VALUE=1600), dict(MEM="LM_MIN")),
    Spec("SRD", dict(UPID=0x03E8, COUNT=8, MEM="LM_RAM"), dict(COUNT=2), dict(COUNT=0)),
    Spec("SWR", dict(UPID=0x03F2, COUNT=8, TEXT="conformance", MEM="LM_RAM_ROM"), dict(TEXT="other"), dict(COUNT=40)),
    Spec("DEF", dict(LAYER=3), dict(LAYER=1), dict(LAYER=9), fail=dict(TIMEOUT=20 * MS)),
    Spec("UL", dict(MODIFIED=False, STARTUPID=0x2000, ENDUPID=0x2EFF), dict(ENDUPID=0x2010),
         dict(STARTUPID=0x3000, ENDUPID=0x2000), abort=True),
    Spec("CA", dict(CURVEID=23, INFO=SEED_INFO, DATASIZE=40), dict(CURVEID=24), dict(CURVEID=0),
         setup=seed_setpoints, abort=True),
    Spec("CAF", dict(CURVEID=5, NAME="conf", OBJECTTYPE=3, XLENGTH=1000, NUMSETPOINTS=10), dict(NAME="other"),
         dict(NUMSETPOINTS=1), setup=seed_setpoints, abort=True),
    Spec("CG", dict(CURVEID=23), dict(CURVEID=24), dict(CURVEID=0), setup=seed_curve_on_drive, abort=True),
    Spec("CDA", {}),
    Spec("FS", dict(CURVES=True, COMMANDTABLE=False, POLLINTERVAL=0), dict(COMMANDTABLE=True),
         dict(CURVES=False, COMMANDTABLE=False), fail=dict(MCTIMEOUT=20 * MS), polls=True),
    Spec("CTWR", dict(ENTRY=5, BLOCK=ENTRY), dict(ENTRY=6), dict(ENTRY=256), abort=True),
    Spec("CTWRF", dict(ENTRY=5, HEADER=0x0103, NAME="conf"), dict(NAME="other"), dict(NAME="x" * 17), abort=True),
    Spec("CTRD", dict(ENTRY=5), dict(ENTRY=6), dict(ENTRY=256), setup=ct_entry_on_drive, abort=True),
    Spec("CTDEL", dict(ENTRY=5), dict(ENTRY=6), dict(ENTRY=256), setup=ct_entry_on_drive),
    Spec("CTDELALL", {}),
    Spec("CTPRES", {}),
    Spec("LC", dict(LAYER=2, CHECK=True, SOURCE={"TREEID": 4612, "MAINVERSION": 3, "SUBVERSION": 0}),
         dict(LAYER=1), dict(LAYER=0)),
    Spec("MST", {}, fail=dict(TIMEOUT=20 * MS)),
    Spec("MSA", {}, fail=dict(TIMEOUT=20 * MS)),
    Spec("RST", {}, fail=dict(BOOTTIMEOUT=40 * MS)),
    Spec("SDO", dict(INDEX=0x1018, SUBINDEX=1, WRITE=False), dict(SUBINDEX=2), dict(INDEX=0)),
    Spec("CMD", dict(SUBINDEX=0x41, E1100ONLY=True), dict(SUBINDEX=0x81), dict(WRAPPERERROR=0x0101)),
]
IDS = [s.name for s in SPECS]


def bench(spec: Spec) -> Bench:
    b = Bench(nodes=1)
    if spec.setup:
        spec.setup(b)
    return b


class ServiceFamily:
    """The service FBs' side of the suite: a run's frames are the node's SDO requests (0x601); an answer kept
    late (0x581) keeps an FB busy; lost answers (and, for MC_Reset's twin, the boot-up) end it in a timeout."""

    name = "service"
    specs = SPECS

    bench = staticmethod(bench)

    @staticmethod
    def frames(b: Bench, spec: Spec, t0: int) -> list:
        return requests(b, t0, spec.polls)

    @staticmethod
    def frames_of_a_refused_run(b: Bench, spec: Spec, t0: int) -> list:
        return requests(b, t0)

    @staticmethod
    def keep_busy(b: Bench) -> None:
        b.bus.delay(lambda f: f.can_id == 0x581, 3 * MS)

    @staticmethod
    def fails(spec: Spec) -> bool:
        return True

    @staticmethod
    def make_it_fail(b: Bench, spec: Spec) -> dict:
        b["CH1.SDOTIMEOUT"] = 20 * MS
        b.bus.drop(lambda f: f.can_id == 0x581)                    # the drive's answers never arrive
        if spec.name == "RST":
            b.bus.drop(lambda f: f.can_id == 0x701)
        return spec.fail

    @staticmethod
    def pulse_options(spec: Spec) -> dict:
        return {}
