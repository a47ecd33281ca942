"""`linmot-st motion FILE.pvl`: commission emulated drives from a PVL file, then move them with the PLC.

Steps: as `linmot-st commission` (fast drive timings unless --drive-timings real), then plc_project's motion
program on every commissioned axis: set up the PDOs, power, home, move to --position, for each time curve of
the file move to its start and run it, start a command-table entry, stop, switch off. Each step is checked
against the PVL file as written (targets, the curves' setpoints) on the emulated drive's trajectory. Prints
the commissioning report and the motion report; --report writes both (report.md, motion.md, JSON, the trace,
curve plots, a position plot per axis). Exit status: 0 when every axis was commissioned and every step met
its check, 1 otherwise, 2 for bad arguments.
"""

from __future__ import annotations

import argparse
import sys


def register(subparsers) -> None:
    from linmot_st.jobs.commission.cli import add_run_arguments

    p = subparsers.add_parser(
        "motion", help="commission emulated E1100 drives from a PVL file, then move them with the PLC, and report",
        description=__doc__.splitlines()[0], formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="docs/motion.md describes the steps, the checks and the report.")
    add_run_arguments(p, timings_default="default: fast")
    p.add_argument("--position", type=float, default=50.0, metavar="MM",
                   help="the position of the move step, mm (default 50)")
    p.add_argument("--bus-share", type=_share, default=70.0, metavar="PCT",
                   help="the share of the bus the planned process data may use, %% (default 70): the job sets "
                        "TxPDO2's inhibit time to stay within it and refuses a configuration that cannot")
    p.set_defaults(func=run_command)


def _share(text: str) -> float:
    v = float(text)
    if not 1.0 <= v <= 100.0:
        raise argparse.ArgumentTypeError(f"{text}: a share of the bus in % (1..100)")
    return v


def command_line(args: argparse.Namespace) -> str:
    from linmot_st.jobs.commission.cli import command_line as commission_line

    line = commission_line(argparse.Namespace(**{**vars(args), "live_ram": False, "flash": True, "reset": True,
                                                 "verify": True, "emulate": True}))
    line = line.replace("linmot-st commission", "linmot-st motion", 1)
    line += f" --position {args.position:g}" if args.position != 50.0 else ""
    return line + (f" --bus-share {args.bus_share:g}" if args.bus_share != 70.0 else "")


def run_command(args: argparse.Namespace) -> int:
    from pathlib import Path

    from linmot_st.cliargs import error
    from linmot_st.jobs.commission.cli import commission_report, prepare_run, write_outputs
    from linmot_st.jobs.commission.progress import Progress

    from .check import check_motion
    from .job import as_commissioned, run_job
    from .plan import plan as make_plan
    from .report import MotionProgress, MotionReport

    err = sys.stderr
    prep = prepare_run(args, timings=args.drive_timings or "fast")
    if isinstance(prep, int):
        return prep
    from .budget import BudgetRefused, job_budget
    try:                                    # before any motion: the PDOs of every axis must fit the bus
        budget_in, budget = job_budget(prep.opts.axes, prep.opts.bitrate, args.bus_share)
    except BudgetRefused as e:
        print(f"linmot-st motion: refused: {e}", file=err)
        return 1
    # per-node PVL files (--pvl NODE=FILE, e.g. a B1100 beside E1100s): the steps every axis can run
    others = [s.pvl for s in prep.datasets.sources if s.pvl is not prep.pvl] if prep.datasets else []
    # the PLC-streamed profile needs a deterministic scan: the simulated bus's virtual time, not real time
    plan = make_plan(prep.pvl, args.position, others=others, stream=prep.opts.bus == "sim")
    if plan.refusals:
        # before any motion (and before commissioning): the file's own settings exclude a step
        print(f"motion job: REFUSED before motion: {plan.stroke.describe()}")
        for why in plan.refusals:
            print(f"  {why}")
        return 1
    if not args.quiet:
        print(f"built {prep.rel} with {prep.build.backend} "
              f"({'cached' if prep.build.cached else f'{prep.build_s:.1f} s'}); commissioning, then moving "
              f"{prep.opts.axes} drive(s) on {'the simulated bus' if prep.opts.simulated else prep.opts.bus}: "
              f"{len(plan.steps)} steps", file=err)
    progress = None if args.quiet else Progress(err)
    try:
        result = run_job(prep.pvl, prep.opts, prep.build, plan, dataset=prep.dataset, datasets=prep.datasets,
                         progress=progress,
                         motion_progress=None if args.quiet else MotionProgress(err),
                         timeout_s=args.timeout or 120.0, inhibit_100us=budget.interval_100us,
                         share_percent=args.bus_share)
    except (ValueError, OSError) as e:
        error(args, str(e))
        return 2
    finally:
        if progress:
            progress.close()
    with as_commissioned(result):       # the memory check: as the commissioning left it, before the motion
        report = commission_report(args, prep, result, command_line(args))
    sys.stdout.write(report.text())
    status = 0 if report.figures["result"]["passed"] else 130 if result.interrupted else 1
    motion = None
    print(f"bus budget: {budget.describe(budget_in)}")
    if result.after is not None and result.after.bus_load is not None:
        mean, peak = result.after.bus_load
        print(f"bus after the PDO setup: load {100 * mean:.1f} % mean, {100 * peak:.1f} % in the busiest 100 ms "
              f"(budget {args.bus_share:g} %)")
    if result.after is not None and result.after.ram_changed:
        changed = sorted({u for ps in result.after.ram_changed.values() for u in ps})
        print("RAM parameters the motion steps wrote (checked above as commissioned): "
              + ", ".join(f"{u:04X}h" for u in changed))
    if result.after is not None and result.after.ct_changed:
        entries = sorted({k for es in result.after.ct_changed.values() for k in es})
        print(f"command-table entries the motion steps wrote to RAM (checked above as commissioned): "
              f"{entries[0]}..{entries[-1]}" if entries == list(range(entries[0], entries[-1] + 1))
              else ", ".join(map(str, entries)))
    if result.after is not None:
        check = check_motion(result.after, plan, result.drives)
        motion = MotionReport(result.after, check, result.trace, result.drives)
        sys.stdout.write(motion.text())
        if not motion.passed:
            status = 1
    else:
        print("motion job: not run (the commissioning did not succeed)")
        status = 1
    sys.stdout.flush()
    status = write_outputs(args, report, result) or status
    if args.report and motion is not None:
        try:
            files = motion.write(Path(args.report))
        except OSError as e:
            error(args, f"--report {args.report}: {e.strerror or e}")
            return 1
        print(f"motion report: {', '.join(str(f) for f in files)}")
    return status
