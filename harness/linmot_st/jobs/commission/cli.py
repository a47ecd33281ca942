"""`linmot-st commission FILE.pvl`: the PLC commissions emulated drives from a PVL file, then a report.

Steps: read the PVL file, generate its dataset (`pvl to-st`), build plc_project with it, switch on the
emulated drives (simulated bus by default; NodeServer threads on python-can buses), step the PLC until
every axis is done or failed (progress on stderr), verify each emulated drive's memory against the PVL
file, print the report (stdout) and write the report folder. Exit status: 0 when every axis was
commissioned and the verification passed, 1 otherwise (also when the report folder cannot be written after
the run), 2 for bad arguments (checked before the build: the bus spec, options that cannot work together, a
report folder or trace file that cannot be written), 130 when Ctrl-C stopped the run (the report of what
was done is printed and written first).
"""

from __future__ import annotations

import argparse
import sys
from dataclasses import dataclass

from ...cliargs import (
    UsageError,
    can_bitrate,
    check_output_file,
    check_output_folder,
    error,
    int_range,
    positive_seconds,
)


def _node_ids(text: str) -> list[int]:
    try:
        return [int(x, 0) for x in text.replace(" ", "").split(",") if x]
    except ValueError:
        raise argparse.ArgumentTypeError(f"node IDs {text!r}: a comma-separated list such as 1,2,5") from None


def _node_pvl(text: str) -> tuple[int, str]:
    node, sep, path = text.partition("=")
    try:
        n = int(node, 0)
    except ValueError:
        n = 0
    if not sep or not path or not 1 <= n <= 127:
        raise argparse.ArgumentTypeError(f"{text!r}: NODE=FILE.pvl with a node ID 1..127, e.g. 3=press.pvl")
    return n, path


def _node_model(text: str) -> tuple[int, str]:
    from linmot_st.emulator.models import model_named
    node, sep, name = text.partition("=")
    try:
        n = int(node)
        if not sep or not 1 <= n <= 127:
            raise ValueError
        return n, model_named(name).name
    except ValueError as exc:
        why = f": {exc}" if str(exc) else ""
        raise argparse.ArgumentTypeError(f"{text!r}: NODE=MODEL with a node ID 1..127, e.g. 2=B1100{why}") from None


def _task_interval(text: str) -> int:
    from .project import parse_task_interval
    try:
        return parse_task_interval(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def _duration(ns: int) -> str:
    return f"{ns // 1_000_000}ms" if ns % 1_000_000 == 0 else f"{ns // 1_000}us"


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "commission", help="commission emulated E1100 drives from a PVL file with the PLC, and report",
        description=__doc__.splitlines()[0], formatter_class=argparse.RawDescriptionHelpFormatter,
        epilog="docs/commissioning.md describes the phases, the report and every figure.")
    add_run_arguments(p, timings_default="default: real on the simulated bus, fast on real-time buses")
    p.add_argument("--live-ram", action=argparse.BooleanOptionalAction, default=False,
                   help="write RAM+ROM, ROM only where the drive refuses RAM (non-live parameters) (default off)")
    p.add_argument("--flash", action=argparse.BooleanOptionalAction, default=True,
                   help="save curves and command table to flash (default on). --no-flash needs --no-reset when "
                        "the PVL has curves or command-table entries: a reset would reload the old ones from flash")
    p.add_argument("--reset", action=argparse.BooleanOptionalAction, default=True,
                   help="reset the drives at the end, so that RAM = ROM and the verify reads what survives "
                        "a restart (default on)")
    p.add_argument("--verify", action=argparse.BooleanOptionalAction, default=True,
                   help="the PLC reads everything back (default on)")
    p.add_argument("--no-emulate", dest="emulate", action="store_false",
                   help="real drives on a real bus: no emulated drives, no memory verification")
    p.add_argument("--task-interval", type=_task_interval, default=None, metavar="DURATION",
                   help="the PLC task's interval, built into the program, 50us..10ms (default 1ms; 250us keeps "
                        "the bus busy for few drives at 1 Mbit/s: docs/commissioning.md, \"Task interval\")")
    p.add_argument("--force", action="store_true",
                   help="write everything; by default the PLC reads what each drive holds and writes only what "
                        "differs (no flash save, no reset when nothing does)")
    p.add_argument("--drive-memory", metavar="DIR",
                   help="the emulated drives' memory: loaded from DIR/node<N>.json where it exists, written "
                        "there after the run (a second run finds the drives as the first left them)")
    p.set_defaults(func=run_command)


def command_line(args: argparse.Namespace) -> str:
    """The command as a user would type it: the file and every option that differs from its default."""
    import shlex
    parts = ["linmot-st", "commission", args.file]
    for name, flag in (("axes", "--axes"), ("bus", "--bus"), ("bitrate", "--bitrate"), ("backend", "--backend"),
                       ("trace", "--trace"), ("trace_format", "--trace-format"), ("report", "--report"),
                       ("drive_timings", "--drive-timings"), ("timeout", "--timeout")):
        value = getattr(args, name)
        if value is not None and value != DEFAULTS.get(name):
            parts += [flag, f"{value:g}" if isinstance(value, float) else str(value)]
    if args.node_ids:
        parts += ["--node-ids", ",".join(map(str, args.node_ids))]
    for node, path in getattr(args, "pvl", None) or ():
        parts += ["--pvl", f"{node}={path}"]
    for node, model in getattr(args, "drive", None) or ():
        parts += ["--drive", f"{node}={model}"]
    if args.curve_memory is not None:
        parts += ["--curve-memory", str(args.curve_memory)]
    if getattr(args, "task_interval", None) is not None:
        parts += ["--task-interval", _duration(args.task_interval)]
    for name, default in (("live_ram", False), ("flash", True), ("reset", True), ("verify", True),
                          ("preflight", True)):
        if getattr(args, name) != default:
            parts.append(f"--{'' if getattr(args, name) else 'no-'}{name.replace('_', '-')}")
    if not args.emulate:
        parts.append("--no-emulate")
    if getattr(args, "force", False):
        parts.append("--force")
    if getattr(args, "drive_memory", None):
        parts += ["--drive-memory", args.drive_memory]
    if args.quiet:
        parts.append("-q")
    return " ".join(shlex.quote(x) for x in parts)


DEFAULTS = {"bus": "sim", "bitrate": 500_000, "backend": "auto", "trace_format": "log"}


@dataclass
class Prepared:
    """What a run needs once the arguments are checked and the project is built (commission, motion)."""
    pvl: object
    opts: object
    dataset: object
    project: object
    datasets: object                   # datasets.Datasets: each node's
    build: object
    build_s: float
    rel: str


def add_run_arguments(p, *, timings_default: str) -> None:
    """The arguments `commission` and `motion` share."""
    p.add_argument("file", metavar="FILE.pvl", help="the PVL file (LinMot-Talk export)")
    p.add_argument("--axes", type=int_range(1, 32), default=None, metavar="N",
                   help="number of drives, 1..32 on the one bus (default 1, or as many as --node-ids)")
    p.add_argument("--node-ids", type=_node_ids, default=None, metavar="IDS",
                   help="their CANopen node IDs, comma-separated (default 1..N)")
    p.add_argument("--pvl", type=_node_pvl, action="append", default=[], metavar="NODE=FILE",
                   help="the dataset of this node (repeat for others); the nodes without one get FILE.pvl")
    p.add_argument("--drive", type=_node_model, action="append", default=[], metavar="NODE=MODEL",
                   help="the emulated drive of this node (E1100, B1100; repeat for others); default: the series "
                        "its PVL file is for")
    p.add_argument("--bus", default="sim", metavar="BUS",
                   help="sim (default: simulated bus, virtual time), virtual[:CHANNEL] (python-can, real time), "
                        "socketcan:CHANNEL, or INTERFACE:CHANNEL")
    p.add_argument("--bitrate", type=can_bitrate, default=500_000, metavar="B",
                   help="bit/s, a CANopen rate (default 500000)")
    p.add_argument("--backend", choices=("auto", "matiec", "builtin"), default="auto",
                   help="ST compiler (default auto: MatIEC where installed)")
    p.add_argument("--trace", metavar="FILE", help="also write the CAN trace here (.log, .asc or .blf)")
    p.add_argument("--trace-format", choices=("log", "asc", "blf"), default="log",
                   help="format of the trace in the report folder (default log: candump)")
    p.add_argument("--report", metavar="DIR", help="write the report folder (report.md, report.json, trace, plots)")
    p.add_argument("--drive-timings", choices=("real", "fast"), default=None,
                   help=f"emulated drive durations (boot 4 s, MC start 3 s, ...) or short ones ({timings_default})")
    p.add_argument("--timeout", type=positive_seconds, default=None, metavar="S",
                   help="give up after S seconds of PLC time (default: from the dataset size)")
    p.add_argument("--preflight", action=argparse.BooleanOptionalAction, default=True,
                   help="before the first write, the PLC asks each drive whether it has every UPID, may write it "
                        "and takes its value, and whether the curves fit (default on)")
    p.add_argument("--curve-memory", type=int_range(0), default=None, metavar="BYTES",
                   help="the drives' curve memory for the pre-flight (70 + 4 x setpoints per curve); default: "
                        "the emulated drives' (256 KiB), 0 (not checked) with --no-emulate")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress lines")


def prepare_run(args: argparse.Namespace, *, flash: bool = True, reset: bool = True, verify: bool = True,
                live_ram: bool = False, emulate: bool = True, timings: str | None = None,
                force: bool = False) -> Prepared | int:
    """Read the PVL file, check the arguments (exit status 2 before anything is built), prepare and build the
    project (1 when that fails)."""
    import time
    from pathlib import Path

    from linmot_st.pvl.cli import load_or_report
    from linmot_st.pvl.dataset import DatasetError
    from linmot_st.toolchain import CompileError

    from .datasets import Datasets
    from .project import TASK_INTERVAL_NS, build_project, prepare
    from .runner import RunOptions, check_bus_spec

    err = sys.stderr
    # the output paths first: nothing is read, built or run for a command whose results cannot be kept
    if args.trace:
        check_output_file(args.trace, f"--trace {args.trace}", (".log", ".asc", ".blf"))
    if args.report:
        check_output_folder(args.report, f"--report {args.report}")
    if getattr(args, "drive_memory", None):
        if not emulate:
            raise UsageError("--drive-memory is the emulated drives' memory: not with --no-emulate")
        check_output_folder(args.drive_memory, f"--drive-memory {args.drive_memory}")
    pvl = load_or_report(args.file, err)
    if pvl is None:
        return 1
    axes = args.axes if args.axes is not None else (len(args.node_ids) if args.node_ids else 1)
    if args.node_ids and len(args.node_ids) != axes:
        raise UsageError(f"--axes {axes} but {len(args.node_ids)} node IDs")
    opts = RunOptions(axes=axes, node_ids=args.node_ids, bus=args.bus, bitrate=args.bitrate,
                      live_ram=live_ram, flash=flash, reset=reset, verify=verify,
                      preflight=args.preflight, curve_memory=args.curve_memory,
                      timings=timings, timeout_s=args.timeout, emulate=emulate, force=force,
                      drive_models=dict(getattr(args, "drive", None) or ()))
    try:
        opts.nodes()
        check_bus_spec(opts.bus)
        if not opts.emulate and opts.simulated:
            raise ValueError("--no-emulate needs a real bus (--bus socketcan:CHANNEL)")
        if opts.reset and not opts.flash and (pvl.curves or pvl.command_table):
            raise ValueError("--no-flash with the reset (on by default): the reset would reload the old curves and "
                             "command table from flash, so the FB refuses it (ResetNeedsFlash). Add --no-reset "
                             "(RAM then holds the new curves and entries until the next power cycle), or keep the "
                             "flash save")
    except ValueError as e:
        raise UsageError(str(e)) from None
    per_node = {}
    nodes = opts.nodes()
    for node, model in getattr(args, "drive", None) or ():
        if node not in nodes:
            raise UsageError(f"--drive {node}={model}: node {node} is not commissioned (node IDs {nodes})")
    for node, path in getattr(args, "pvl", None) or ():
        if node not in nodes:
            raise UsageError(f"--pvl {node}={path}: node {node} is not commissioned (node IDs {nodes})")
        if node in per_node:
            raise UsageError(f"--pvl {node}=...: node {node} given twice")
        other = load_or_report(path, err)
        if other is None:
            return 1
        per_node[node] = (other, Path(path).name)
    try:
        datasets = Datasets.build(pvl, Path(args.file).name, per_node)
        dataset = datasets.default.dataset
        project = prepare(pvl, Path(args.file).name, text=datasets.st_text(),
                          task_interval_ns=getattr(args, "task_interval", None) or TASK_INTERVAL_NS)
    except (DatasetError, FileNotFoundError) as e:
        error(args, str(e))
        return 1
    t0 = time.perf_counter()
    try:
        res = build_project(project, args.backend)
    except CompileError as e:
        print(e, file=err)
        return 1
    return Prepared(pvl, opts, dataset, project, datasets, res, time.perf_counter() - t0, _rel(project.entry))


def commission_report(args: argparse.Namespace, prep: Prepared, result, command: str):
    """The commissioning report of a run (printed first, written with the report folder by the caller)."""
    from .report import Context, Report
    from .verify import verify_run

    verification = verify_run(prep.pvl, result)
    ctx = Context(pvl_path=args.file, command=command, backend=prep.build.backend, build_s=prep.build_s,
                  build_cached=prep.build.cached, project=prep.rel, dataset_words=prep.dataset.words)
    report = Report(ctx, result, prep.dataset, verification, prep.pvl)
    report.compute()
    return report


def write_outputs(args: argparse.Namespace, report, result) -> int:
    """The --trace file and the report folder; 0, or 1 when one cannot be written."""
    from pathlib import Path

    status = 0
    if args.trace:
        from linmot_st.bus.trace import write_trace
        try:
            write_trace(result.trace, args.trace)
        except (OSError, ValueError) as e:
            error(args, f"--trace {args.trace}: {getattr(e, 'strerror', None) or e}")
            status = 1
    if args.report:
        try:
            files = report.write(Path(args.report), args.trace_format)
        except OSError as e:
            error(args, f"--report {args.report}: {e.strerror or e} ({e.filename or args.report})")
            return 1
        print(f"report: {args.report}/report.md, report.json, {files['trace']}, "
              f"{len(files['plots'])} curve plot(s)")
    return status


def run_command(args: argparse.Namespace) -> int:
    from .progress import Progress
    from .runner import run

    err = sys.stderr
    prep = prepare_run(args, flash=args.flash, reset=args.reset, verify=args.verify, live_ram=args.live_ram,
                       emulate=args.emulate, timings=args.drive_timings, force=args.force)
    if isinstance(prep, int):
        return prep
    if not args.quiet:
        print(f"built {prep.rel} with {prep.build.backend} "
              f"({'cached' if prep.build.cached else f'{prep.build_s:.1f} s'}); commissioning {prep.opts.axes} "
              f"drive(s) on {'the simulated bus' if prep.opts.simulated else prep.opts.bus}", file=err)
    progress = None if args.quiet else Progress(err)
    try:
        factory = (_remembering_drives(args.drive_memory, prep.opts, prep.datasets) if args.drive_memory
                   else None)
        result = run(prep.pvl, prep.opts, prep.build, datasets=prep.datasets, progress=progress,
                     drive_factory=factory)
        if args.drive_memory:
            _keep_drives(args.drive_memory, result.drives)
    except (ValueError, OSError) as e:
        error(args, str(e))
        return 2
    finally:
        if progress:
            progress.close()
    report = commission_report(args, prep, result, command_line(args))
    sys.stdout.write(report.text())             # first: whatever happens to the files, the result is shown
    sys.stdout.flush()
    status = 0 if report.figures["result"]["passed"] else 130 if result.interrupted else 1
    return write_outputs(args, report, result) or status


def _memory_file(folder: str, node: int):
    from pathlib import Path
    return Path(folder) / f"node{node}.json"


def _remembering_drives(folder: str, opts, datasets=None):
    """A drive factory: each emulated drive with the memory a previous run left in `folder` (if any)."""
    from linmot_st.emulator.linmot import memory

    from .runner import emulated_drive

    def factory(node: int):
        drive = emulated_drive(node, opts, datasets)
        path = _memory_file(folder, node)
        if path.exists():
            memory.load(drive, memory.read(path))
        return drive
    return factory


def _keep_drives(folder: str, drives: dict) -> None:
    from pathlib import Path

    from linmot_st.emulator.linmot import memory

    Path(folder).mkdir(exist_ok=True)
    for node, drive in drives.items():
        memory.write(drive, _memory_file(folder, node))


def _rel(path) -> str:
    from pathlib import Path
    try:
        return str(Path(path).resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)
