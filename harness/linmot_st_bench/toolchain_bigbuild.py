"""Big inputs built cold (issue 12): a 60-curve x 4000-setpoint PVL dataset with plc_project, and a
100k-statement ST program. Generated here, never committed; each build runs in a fresh Python process with
an empty cache, so that imports, the ST compiler and gcc are all counted, and gcc's peak memory is that
process's largest child (resource.getrusage(RUSAGE_CHILDREN)).

`python -m linmot_st_bench.toolchain_bigbuild dataset|program [N] [--backend B]` prints one build's figures as
JSON; linmot_st_bench.toolchain puts them into `make bench`.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

DATASET_CURVES, DATASET_SETPOINTS = 60, 4000
PROGRAM_STATEMENTS = 100_000
TARGET_DATASET_S = 3.0
TARGET_PROGRAM_S = 60.0
TARGET_PROGRAM_RSS_MB = 1024
TARGET_LOAD_PVL_S = 0.5


def big_pvl(curves: int = DATASET_CURVES, setpoints: int = DATASET_SETPOINTS):
    """The demo's parameters and `curves` minimum-jerk curves of `setpoints` setpoints each (a file that a PVL
    writer accepts: its name has no blank at a stringlet's end)."""
    from linmot_st.pvl import demo
    from linmot_st.pvl.model import PvlFile
    items = [demo.minimum_jerk_curve(k + 1, f"Big_{k + 1}", 1_000_000 - 991 * k, 40_000, setpoints)
             for k in range(curves)]
    return PvlFile((demo.os_parameters("Big_Dataset", "Bench"), demo.mc_parameters(), *items))


def big_program(statements: int = PROGRAM_STATEMENTS) -> str:
    """One PROGRAM of `statements` straight-line statements (assignments, IFs, array accesses, REAL
    arithmetic, MOD), as a generated program or a long hand-written sequence would be."""
    lines = ["PROGRAM Big", "  VAR", "    a : ARRAY[0..99] OF DINT;",
             "    x : DINT; y : DINT; r : REAL; b : BOOL;", "  END_VAR"]
    k = 0
    while k < statements:
        j = k % 100
        kind = k % 5
        if kind == 0:
            lines.append(f"  x := x + {k % 977} * y;")
        elif kind == 1:
            lines.append(f"  a[{j}] := a[{j * 7 % 100}] + x;")
        elif kind == 2:     # two statements
            lines.append(f"  IF x > {k} THEN y := y - 1; ELSE y := y + 2; END_IF;")
            k += 1
        elif kind == 3:
            lines.append(f"  r := r * 0.5 + DINT_TO_REAL(a[{j}]);")
        else:
            lines.append(f"  b := (x MOD {k % 13 + 2}) = 0 OR b;")
        k += 1
    lines += ["END_PROGRAM", "", "CONFIGURATION Config0", "  RESOURCE Res0 ON PLC",
              "    TASK Main(INTERVAL := T#1ms, PRIORITY := 0);", "    PROGRAM Inst0 WITH Main : Big;",
              "  END_RESOURCE", "END_CONFIGURATION", ""]
    return "\n".join(lines)


def _measure(kind: str, n: int, backend: str) -> dict:
    """In this process: build one big input cold; wall and CPU seconds, gcc's peak RSS."""
    import resource

    from linmot_st.toolchain import build

    wall0, cpu0 = time.perf_counter(), os.times()
    with tempfile.TemporaryDirectory(prefix="linmot-st-bigbuild-") as tmp:
        os.environ["LINMOT_ST_CACHE"] = str(Path(tmp) / "cache")
        if kind == "dataset":
            from linmot_st.jobs.commission.project import build_project, prepare
            res = build_project(prepare(big_pvl(n), "big.pvl"), backend)
        else:
            src = Path(tmp) / "big.st"
            src.write_text(big_program(n))
            res = build(str(src), backend=backend, cache_dir=Path(tmp) / "cache")
        assert not res.cached
        wall, cpu1 = time.perf_counter() - wall0, os.times()
        rss = resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024
        out = dict(kind=kind, n=n, backend=res.backend, wall_s=round(wall, 2),
                   cpu_s=round(sum(cpu1[:4]) - sum(cpu0[:4]), 2), gcc_rss_mb=round(rss))
        if kind == "dataset":
            out.update(_load_pvl_figures(big_pvl(n), Path(tmp) / "big.pvl"))
        return out


def _load_pvl_figures(pvl, path: Path) -> dict:
    """What `linmot-st commission` adds before the build on such a file: load_pvl of it (best of 3, wall and
    CPU; the file written by the PVL writer)."""
    from linmot_st.pvl import load_pvl
    from linmot_st.pvl.writer import save_pvl
    save_pvl(pvl, path)
    best_wall = best_cpu = float("inf")
    for _ in range(3):
        wall0, cpu0 = time.perf_counter(), time.process_time()
        load_pvl(path)
        best_wall = min(best_wall, time.perf_counter() - wall0)
        best_cpu = min(best_cpu, time.process_time() - cpu0)
    return dict(pvl_mb=round(path.stat().st_size / 1e6, 2), load_pvl_s=round(best_wall, 3),
                load_pvl_cpu_s=round(best_cpu, 3))


def measure(kind: str, n: int | None = None, backend: str = "auto") -> dict:
    """One cold build in a fresh Python process (imports included): the figures of _measure."""
    n = n or (DATASET_CURVES if kind == "dataset" else PROGRAM_STATEMENTS)
    proc = subprocess.run([sys.executable, "-m", "linmot_st_bench.toolchain_bigbuild", kind, str(n), "--backend", backend],
                          capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"bigbuild {kind} {n} failed:\n{proc.stderr[-2000:]}")
    return json.loads(proc.stdout.splitlines()[-1])


def rows(backend: str, program: bool = True) -> list[dict]:
    """The figures of one backend: the big dataset, and (`program`) the 100k-statement program."""
    ds = measure("dataset", backend=backend)
    label = f"{DATASET_CURVES}-curve x {DATASET_SETPOINTS}-setpoint PVL with plc_project"
    out = [dict(name=f"build {label}, cold, fresh process ({ds['backend']}; CPU {ds['cpu_s']} s)",
                value=ds["wall_s"], unit="s", target=f"<= {TARGET_DATASET_S}"),
           dict(name=f"load_pvl of that PVL file ({ds['pvl_mb']} MB; best of 3, CPU {ds['load_pvl_cpu_s']} s)",
                value=ds["load_pvl_s"], unit="s", target=f"< {TARGET_LOAD_PVL_S}")]
    if program:
        pr = measure("program", backend=backend)
        out += [dict(name=f"build a {pr['n']:,}-statement ST program, cold, fresh process ({pr['backend']}; "
                          f"CPU {pr['cpu_s']} s)", value=pr["wall_s"], unit="s", target=f"<= {TARGET_PROGRAM_S}"),
                dict(name=f"build a {pr['n']:,}-statement ST program: gcc's peak RSS ({pr['backend']})",
                     value=pr["gcc_rss_mb"], unit="MB", target=f"<= {TARGET_PROGRAM_RSS_MB}")]
    return out


def main(argv: list[str]) -> int:
    import argparse
    p = argparse.ArgumentParser(prog="python -m linmot_st_bench.toolchain_bigbuild")
    p.add_argument("kind", choices=("dataset", "program"))
    p.add_argument("n", type=int, nargs="?", help="curves (dataset) or statements (program)")
    p.add_argument("--backend", default="auto")
    args = p.parse_args(argv)
    n = args.n or (DATASET_CURVES if args.kind == "dataset" else PROGRAM_STATEMENTS)
    print(json.dumps(_measure(args.kind, n, args.backend)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
