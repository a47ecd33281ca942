"""Toolchain and PLC runtime figures: build times (cold, cached), scans per second, Python cost per step.

Run: `python -m linmot_st_bench.toolchain` (or `make bench` for every area). Each available backend is
measured. Cold builds use a fresh cache folder, so they include iec2c/the builtin compiler and gcc.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]

TRIVIAL = """
PROGRAM Main
  VAR
    X : INT;
    Y : INT;
  END_VAR
  Y := X + 1;
END_PROGRAM

CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK T1(INTERVAL := T#1ms, PRIORITY := 0);
    PROGRAM Inst0 WITH T1 : Main;
  END_RESOURCE
END_CONFIGURATION
"""

TARGET_SCANS_PER_S = 1_000_000
TARGET_STEP_IO_US = 5.0
TARGET_PROJECT_COLD_S = 5.0
TARGET_CACHED_S = 0.2


def _backends() -> list[str]:
    from linmot_st.toolchain import builtin_available, matiec_available
    return [b for b, ok in (("matiec", matiec_available()), ("builtin", builtin_available())) if ok]


def _build_times(path: Path, backend: str, cache: Path, repeats: int = 5) -> tuple[float, float]:
    from linmot_st.toolchain import build
    t0 = time.perf_counter()
    res = build(path, backend=backend, cache_dir=cache)
    cold = time.perf_counter() - t0
    assert not res.cached
    cached = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        res = build(path, backend=backend, cache_dir=cache)
        cached.append(time.perf_counter() - t0)
        assert res.cached
    return cold, statistics.median(cached)


def _fresh_process_build(path: Path, backend: str, cache: Path) -> float:
    """Wall time of `python -c "build(...)"` on a cached build: interpreter start and imports included."""
    import subprocess
    import sys
    code = f"from linmot_st.toolchain import build; assert build({str(path)!r}, backend={backend!r}, " \
           f"cache_dir={str(cache)!r}).cached"
    best = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", code], check=True)
        best = min(best, time.perf_counter() - t0)
    return best


def _scans_per_s(plc, n: int = 2_000_000) -> float:
    plc.step(1000)   # warm up
    t0 = time.perf_counter()
    plc.step(n)
    return n / (time.perf_counter() - t0)


def _step_io_us(plc, n: int = 100_000) -> float:
    """step(1) + one input write + one output read through bound accessors, per iteration."""
    x, y = plc.var("INST0.X"), plc.var("INST0.Y")
    step = plc.step
    best = float("inf")
    for _ in range(3):
        t0 = time.perf_counter()
        for i in range(n):
            x.value = i & 0x3FFF
            step(1)
            y.value                    # noqa: B018  (the read is what is measured)
        best = min(best, (time.perf_counter() - t0) / n * 1e6)
    if y.value != ((n - 1) & 0x3FFF) + 1:
        raise RuntimeError("benchmark program did not compute Y := X + 1")
    return best


def run() -> list[dict]:
    from linmot_st.plc import Plc
    from linmot_st.toolchain import build
    rows: list[dict] = []
    backends = _backends()
    if not backends:
        return [dict(name="toolchain: no backend available", value=0, unit="", target=None)]
    with tempfile.TemporaryDirectory(prefix="linmot-st-bench-") as tmp:
        tmp = Path(tmp)
        src = tmp / "trivial.st"
        src.write_text(TRIVIAL)
        for backend in backends:
            cold, cached = _build_times(src, backend, tmp / f"cache-{backend}")
            rows.append(dict(name=f"build trivial program, cold ({backend})", value=round(cold, 3), unit="s",
                             target=None))
            rows.append(dict(name=f"build trivial program, cached ({backend})", value=round(cached, 4), unit="s",
                             target=f"<= {TARGET_CACHED_S}"))
            plc = Plc(build(src, backend=backend, cache_dir=tmp / f"cache-{backend}"))
            rows.append(dict(name=f"scans per second, step(n), trivial program ({backend})",
                             value=round(_scans_per_s(plc)), unit="scans/s", target=f">= {TARGET_SCANS_PER_S}"))
            rows.append(dict(name=f"Python cost of step(1) + 1 input write + 1 output read ({backend})",
                             value=round(_step_io_us(plc), 2), unit="us", target=f"<= {TARGET_STEP_IO_US}"))

        project = REPO / "plc_project" / "plc.st"
        library = REPO / "st_lib" / "linmot.st"
        testbench = REPO / "tests" / "st_lib" / "testbench.st"
        targets = []
        if project.is_file():
            targets.append((project, "st_lib + plc_project", True))
        elif library.is_file():
            targets.append((library, "st_lib alone (no plc_project yet)", False))
        if testbench.is_file():
            targets.append((testbench, "st_lib + tests/st_lib/testbench.st", False))
        for path, label, targeted in targets:
            for backend in backends:
                try:
                    cold, cached = _build_times(path, backend, tmp / f"{path.stem}-{backend}")
                except Exception as exc:   # the project may not compile yet: say so, don't fail the bench
                    first = str(exc).splitlines()[0] if str(exc) else type(exc).__name__
                    rows.append(dict(name=f"build {label} ({backend}): failed: {first}", value=0, unit="",
                                     target=None))
                    continue
                rows.append(dict(name=f"build {label}, cold ({backend})", value=round(cold, 3), unit="s",
                                 target=f"<= {TARGET_PROJECT_COLD_S}" if targeted else None))
                rows.append(dict(name=f"build {label}, cached ({backend})", value=round(cached, 4), unit="s",
                                 target=f"<= {TARGET_CACHED_S}"))
                rows.append(dict(name=f"build {label}, cached, in a fresh Python process ({backend})",
                                 value=round(_fresh_process_build(path, backend, tmp / f"{path.stem}-{backend}"), 3),
                                 unit="s", target=None))
    from linmot_st_bench import toolchain_bigbuild as bigbuild
    for backend in backends:
        try:   # the 100k-statement program on the builtin backend only: iec2c alone takes minutes on it
            rows += bigbuild.rows(backend, program=backend == "builtin" or len(backends) == 1)
        except Exception as exc:   # report, don't break the other figures
            rows.append(dict(name=f"big builds ({backend}): failed: {str(exc).splitlines()[0]}", value=0, unit="",
                             target=None))
    return rows


if __name__ == "__main__":
    for row in run():
        print(f"{row['name']}: {row['value']} {row['unit']} (target {row['target']})")
