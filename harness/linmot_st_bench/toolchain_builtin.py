"""Figures of the builtin compiler: time to compile ST to C (parse, check, generate) and gcc's time on the C.

    python -m linmot_st_bench.toolchain_builtin

Inputs: the ST library's testbench (tests/st_lib/testbench.st, which includes all of st_lib) when the
repository is at hand, and a generated 3,000-line program of function blocks instantiated by a
configuration (so that gcc compiles all of it). Each figure is the best of 3 runs.
"""

from __future__ import annotations

import subprocess
import tempfile
import time
from pathlib import Path

from linmot_st.toolchain.cc import BASE_FLAGS, BUILTIN_FLAGS

REPO = Path(__file__).resolve().parents[2]
TESTBENCH = REPO / "tests" / "st_lib" / "testbench.st"
TARGET_COLD_S = 5.0
CFLAGS = [*BASE_FLAGS, *BUILTIN_FLAGS]   # as the build gives them


def synthetic(lines: int = 3000) -> str:
    """A program of `lines` lines: FBs with loops, CASE, arithmetic, arrays, and one program using each."""
    head = ["TYPE t_syn_a8 : ARRAY[1..8] OF INT; END_TYPE"]
    fbs, body = [], []
    k = 0
    while len(head) + sum(len(f) for f in fbs) < lines - 40:
        fb = [f"FUNCTION_BLOCK fb_syn{k}",
              "  VAR_INPUT x : INT; en2 : BOOL; END_VAR",
              "  VAR_OUTPUT y : INT; done : BOOL; END_VAR",
              "  VAR i, j, st : INT; arr : t_syn_a8; t : TON; END_VAR"]
        for m in range(6):
            fb += [f"  IF en2 AND x > {m} THEN",
                   f"    y := y + x * {m + 1} - 3;",
                   "    FOR i := 1 TO 8 DO arr[i] := arr[i] + i; END_FOR;",
                   f"  ELSIF x < -{m} THEN",
                   "    CASE st OF",
                   "      0: st := 1; j := j + 1;",
                   "      1, 2: st := 3;",
                   "      5..7: st := 0;",
                   "    ELSE st := 0;",
                   "    END_CASE;",
                   "  END_IF;"]
        fb += ["  t(IN := en2, PT := T#20ms);", "  done := t.Q OR y > 100;", "END_FUNCTION_BLOCK"]
        fbs.append(fb)
        body.append(f"  f{k}(x := n, en2 := n MOD 2 = 0);")
        k += 1
    decl = "  VAR n : INT; " + " ".join(f"f{i} : fb_syn{i};" for i in range(k)) + " END_VAR"
    prog = ["PROGRAM p_syn", decl, "  n := n + 1;", *body, "END_PROGRAM",
            "CONFIGURATION c_syn", "  RESOURCE r ON PLC", "    TASK t(INTERVAL := T#10ms, PRIORITY := 0);",
            "    PROGRAM i WITH t : p_syn;", "  END_RESOURCE", "END_CONFIGURATION"]
    return "\n".join(head + [ln for f in fbs for ln in f] + prog) + "\n"


def _best(fn, repeats: int = 3) -> float:
    best = float("inf")
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def _measure(entry: Path, root: Path, label: str) -> list[dict]:
    from linmot_st.toolchain.builtin import compile_to_c
    out = Path(tempfile.mkdtemp(prefix="builtin-bench-"))
    st_lines = 0
    res = compile_to_c(entry, root, out)
    for p in res.sources:
        st_lines += len(p.read_text(errors="replace").splitlines())
    front = _best(lambda: compile_to_c(entry, root, out))
    c_lines = sum(len(c.read_text().splitlines()) for c in res.c_files)
    # every unit, one after the other (the build runs them in parallel): gcc's CPU time
    gcc = _best(lambda: [subprocess.run(["gcc", *CFLAGS, "-c", str(c), "-o", str(out / f"{c.stem}.o")], check=True)
                         for c in res.c_files])
    return [
        dict(name=f"{label}: ST lines read", value=st_lines, unit="lines", target=None),
        dict(name=f"{label}: ST -> C (parse, check, generate)", value=round(front, 3), unit="s", target=None),
        dict(name=f"{label}: C lines generated", value=c_lines, unit="lines", target=None),
        dict(name=f"{label}: gcc {' '.join(CFLAGS[:2])} of the C", value=round(gcc, 3), unit="s", target=None),
        dict(name=f"{label}: ST -> object code, total", value=round(front + gcc, 3), unit="s",
             target=f"<= {TARGET_COLD_S}"),
    ]


def run() -> list[dict]:
    figures = []
    if TESTBENCH.is_file():
        figures += _measure(TESTBENCH, REPO, "st_lib testbench")
    folder = Path(tempfile.mkdtemp(prefix="builtin-bench-src-"))
    entry = folder / "synthetic.st"
    entry.write_text(synthetic())
    figures += _measure(entry, folder, "synthetic 3000 lines")
    return figures


if __name__ == "__main__":
    for f in run():
        target = f" (target {f['target']})" if f["target"] else ""
        print(f"{f['name']:<55} {f['value']:>10} {f['unit']}{target}")
