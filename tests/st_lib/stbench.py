"""Test helpers for the ST library: the testbench PLC (tests/st_lib/testbench.st) on a simulated bus
with emulated E1100 drives, and a handle per FB instance that drives its PLCopen inputs. Both are the
pytest plugin's (linmot_st.plctest.rig: Rig, FbHandle), bound to the testbench.

    b = Bench(nodes=1)                 # drives 1..n booted, channels enabled and ready
    r = b.fb("RD").run(UPID=0x1194)    # Execute, step until Done/Error, Execute off
    r.done, r.error, r.error_id, r.scans, r["VALUE"]

One build serves every test (cached by content); each Bench loads its own PLC instance. Bench(task_ms=3)
uses a variant of the testbench with another task interval (one more build, under build/st_lib_variants). The suite runs on
MatIEC when iec2c is found, else on the builtin compiler; STLIB_BACKEND=builtin|matiec forces one.
"""

from __future__ import annotations

import os
import struct
from pathlib import Path
from typing import Any

import pytest

from linmot_st.plctest.rig import FbHandle, FbResult, Rig

REPO = Path(__file__).resolve().parents[2]
TESTBENCH = REPO / "tests" / "st_lib" / "testbench.st"
VECTORS = REPO / "tests" / "vectors"
MAILBOX = "CONFIG0.RES0.CAN0"
PROG = "BENCH"
CODECS = "CODECS"

_builds: dict[str, Any] = {}


def available_backends() -> list[str]:
    from linmot_st import toolchain
    out = []
    if toolchain.matiec_available():
        out.append("matiec")
    if toolchain.builtin_available():
        out.append("builtin")
    return out


TASK_LINE = "TASK Main(INTERVAL := T#1ms, PRIORITY := 0);"
VARIANTS = REPO / "build" / "st_lib_variants"     # inside the repository: st_lib/ is its include root


def testbench_with_task(task_ms: int, source: Path = TESTBENCH) -> Path:
    """A testbench with another task interval: its CONFIGURATION rewritten into a file under build/."""
    text = source.read_text(encoding="latin-1")
    assert text.count(TASK_LINE) == 1, "the testbench's task line changed: update TASK_LINE"
    VARIANTS.mkdir(parents=True, exist_ok=True)
    path = VARIANTS / f"{source.stem}_task{task_ms}ms.st"
    tmp = path.with_suffix(f".{os.getpid()}.tmp")
    tmp.write_text(text.replace(TASK_LINE, TASK_LINE.replace("T#1ms", f"T#{task_ms}ms")), encoding="latin-1")
    os.replace(tmp, path)                          # atomic: parallel test workers may write it at once
    return path


def bench_build(backend: str = "auto", task_ms: int = 1, source: Path = TESTBENCH):
    """A testbench (the library's, or another one such as the motion testbench), built once per backend (and
    task interval) per session (skips the test when it cannot be built)."""
    from linmot_st import toolchain
    if backend == "auto":
        backend = os.environ.get("STLIB_BACKEND", "auto")      # run the suite on one backend: matiec | builtin
    if backend == "auto":
        backends = available_backends()
        if not backends:
            pytest.skip("no ST backend: MatIEC's iec2c not found and the builtin compiler is not importable")
        backend = backends[0]
    key = f"{source.name}/{backend}" if task_ms == 1 else f"{source.name}/{backend}/{task_ms}ms"
    if key not in _builds:
        path = source if task_ms == 1 else testbench_with_task(task_ms, source)
        _builds[key] = toolchain.build(str(path), backend=backend)
    return _builds[key]


Result = FbResult                   # the PLCopen outcome of an FB run (linmot_st.plctest.rig)


class Fb(FbHandle):
    """One FB instance of the testbench program: the plugin's FB handle, named within BENCH."""

    def __init__(self, bench: Bench, name: str):
        super().__init__(bench, f"{bench.prog}.{name}")
        self.bench = bench
        self.name = name.upper()

    def flags(self) -> tuple[bool, bool, bool]:
        return self["DONE"], self["BUSY"], self["ERROR"]

    def run(self, max_scans: int = 20_000, release: bool = True, **inputs: Any) -> Result:
        """Execute with these inputs, step until Done, Error or CommandAborted, then (release) drop
        Execute and step once. `scans` counts the scans from the Execute scan to the finishing one."""
        return super().run(scans=max_scans, release=release, **inputs)

    def _aborted(self) -> bool:
        return bool(self._member("COMMANDABORTED"))


class Bench(Rig):
    """The testbench PLC with `nodes` emulated E1100 drives (node IDs 1..nodes) on one simulated bus: the
    plugin's rig, with the channels of nodes 1..n enabled and ready. A subclass names another testbench
    (source) and its program (prog)."""

    source = TESTBENCH
    prog = PROG

    def __init__(self, nodes: int = 1, *, bitrate: int = 500_000, timings: Any = None, backend: str = "auto",
                 enable: bool = True, drive_kwargs: dict | None = None, task_ms: int = 1,
                 echo: bool | None = None):
        from linmot_st.emulator import DriveTimings, E1100Drive

        timings = timings or DriveTimings.fast()
        super().__init__(bench_build(backend, task_ms, self.source), nodes=range(1, nodes + 1), bitrate=bitrate,
                         mailbox=MAILBOX,
                         drive_factory=lambda n: E1100Drive(n, timings=timings, **(drive_kwargs or {})),
                         echo=echo)
        if enable:
            for n in range(1, nodes + 1):
                self.plc[f"{self.prog}.CH{n}.NODEID"] = n
                self.plc[f"{self.prog}.CH{n}.ENABLE"] = True
            self.sim.run_until(lambda: all(self.plc[f"{self.prog}.AX{n}.BOOTCOUNT"] >= 1
                                           for n in range(1, nodes + 1)), max_scans=20_000)
            self.step(2)

    def fb(self, name: str) -> Fb:
        return Fb(self, name)

    def __getitem__(self, path: str) -> Any:
        return self.plc[f"{self.prog}.{path}"]

    def __setitem__(self, path: str, value: Any) -> None:
        self.plc[f"{self.prog}.{path}"] = value

    def set_setpoints(self, values: list[int], var: str = "SP") -> None:
        self[var] = list(values) + [0] * (1000 - len(values))

    def sdo_trace(self, node: int = 1, since_ns: int = 0) -> list:
        """(request, answer) trace entries of one node's SDO traffic after since_ns, in bus order."""
        ids = (0x600 + node, 0x580 + node)
        return [e for e in self.bus.trace if e.frame.can_id in ids and e.start_ns >= since_ns and e.status != "error"]


def exchanges(trace: list, node: int = 1) -> int:
    """Complete request/answer pairs of a node in a trace slice."""
    return sum(1 for e in trace if e.frame.can_id == 0x580 + node)


def u32_words_to_bytes(words: list[str]) -> bytes:
    return b"".join(struct.pack("<I", int(w, 16)) for w in words)
