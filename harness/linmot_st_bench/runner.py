"""`make bench` / `linmot-st bench`: run every area's module of linmot_st_bench and print its figures.

Each area's module (`linmot_st_bench.<area>`, AREAS) exposes `run() -> list[dict(name=, value=, unit=, target=)]`; `target` is None or a
string such as ">= 1000000" or "<= 5". Figures are printed against their targets, never asserted: a
miss is reported, and the exit status stays 0 unless a benchmark itself breaks.
"""

from __future__ import annotations

import importlib
import re
import sys
import time
import traceback

_TARGET = re.compile(r"^\s*(<=|>=|<|>|==)\s*([-+0-9.eE_]+)\s*$")


# the areas, in name order: the parts of linmot_st they measure (the other modules here are their helpers)
AREAS = ("bus", "commission", "emulator", "motion", "stcov", "toolchain", "vcan")


def bench_modules() -> list[str]:
    """`linmot_st_bench.<area>` for every area, in name order."""
    return [f"linmot_st_bench.{area}" for area in AREAS]


def verdict(value, target) -> str:
    if target is None:
        return ""
    m = _TARGET.match(str(target))
    if not m:
        return ""
    if not isinstance(value, (int, float)):
        return "MISS"                  # no figure where one was due (the measured run failed)
    op, limit = m[1], float(m[2].replace("_", ""))
    ok = {"<=": value <= limit, ">=": value >= limit, "<": value < limit, ">": value > limit,
          "==": value == limit}[op]
    return "ok" if ok else "MISS"


def _fmt(value) -> str:
    if isinstance(value, float):
        return f"{value:,.4g}" if abs(value) < 1000 else f"{value:,.0f}"
    if isinstance(value, int):
        return f"{value:,}"
    return str(value)


def run_all(only: list[str] | None = None, out=sys.stdout) -> int:
    broken = 0
    rows: list[tuple[str, dict]] = []
    for module in bench_modules():
        area = module.split(".")[1]
        if only and area not in only:
            continue
        t0 = time.perf_counter()
        print(f"running {module} ...", file=sys.stderr, flush=True)
        try:
            results = importlib.import_module(module).run()
        except Exception:
            broken += 1
            print(f"{module} failed:\n{traceback.format_exc()}", file=sys.stderr)
            continue
        print(f"  {module}: {time.perf_counter() - t0:.1f} s", file=sys.stderr)
        rows += [(area, r) for r in results]
    if not rows:
        print("no benchmarks ran", file=out)
        return 1 if broken else 0
    width = max(len(r["name"]) for _, r in rows)
    uw = max(4, *(len(str(r.get("unit", ""))) for _, r in rows))
    print(f"{'area':<11} {'figure':<{width}} {'value':>14} {'unit':<{uw}} {'target':<14} ", file=out)
    for area, r in rows:
        target = r.get("target")
        print(f"{area:<11} {r['name']:<{width}} {_fmt(r['value']):>14} {r.get('unit', ''):<{uw}} "
              f"{str(target) if target is not None else '-':<14} {verdict(r['value'], target)}", file=out)
    return 1 if broken else 0


def areas() -> list[str]:
    return [m.split(".")[1] for m in bench_modules()]


def _checked_areas(names: list[str]) -> list[str] | None:
    from linmot_st.cliargs import UsageError
    unknown = [a for a in names if a not in areas()]
    if unknown:
        raise UsageError(f"no benchmark named {', '.join(unknown)} (there are: {', '.join(areas())})")
    return names or None


def register(subparsers) -> None:
    p = subparsers.add_parser("bench", help="run the benchmarks and print figures against their targets")
    p.add_argument("areas", nargs="*", metavar="AREA", help="only these areas (e.g. toolchain bus)")
    p.set_defaults(func=lambda args: run_all(_checked_areas(args.areas)))


def main(argv: list[str] | None = None) -> int:
    import argparse
    parser = argparse.ArgumentParser(prog="python -m linmot_st_bench", description=__doc__.splitlines()[0])
    parser.add_argument("areas", nargs="*", metavar="AREA")
    args = parser.parse_args(argv)
    from linmot_st.cliargs import UsageError
    try:
        return run_all(_checked_areas(args.areas))
    except UsageError as exc:
        parser.error(str(exc))


if __name__ == "__main__":
    sys.exit(main())
