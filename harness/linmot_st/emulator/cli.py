"""`linmot-st emulate`: serve an emulated LinMot drive (the E1100 by default) on a python-can bus in real time until
interrupted."""

from __future__ import annotations

import argparse


def register(subparsers) -> None:
    from ..cliargs import can_bitrate, int_range, non_negative_seconds

    p = subparsers.add_parser(
        "emulate", help="serve an emulated LinMot E1100 (CANopen) on a python-can bus",
        description="Serve an emulated LinMot E1100 CANopen drive on any python-can bus in real time, "
                    "e.g. --interface socketcan --channel vcan0, until Ctrl-C or SIGTERM.")
    p.add_argument("--interface", required=True, help="python-can interface (socketcan, virtual, pcan, ...)")
    p.add_argument("--channel", required=True, help="python-can channel (vcan0, can0, a virtual channel name)")
    p.add_argument("--node-id", type=int_range(1, 127), default=None,
                   help="CANopen node ID 1..127 (default: the model's, 1 for the E1100, 63 for the B1100)")
    p.add_argument("--bitrate", type=can_bitrate, default=500_000,
                   help="bit rate in bit/s (default 500000, the E1100 default; SocketCAN: set with `ip link`)")
    p.add_argument("--drive", default="E1100", metavar="MODEL",
                   help="the drive model (emulator/models.py; default E1100)")
    p.add_argument("--profile", help="drive profile JSON (default: the model's own, for the E1100 the seeds' "
                                     "example drive)")
    p.add_argument("--fast", action="store_true", help="short boot/MC/flash durations (for demos and tests)")
    p.add_argument("--duration", type=non_negative_seconds,
                   help="stop after this many seconds (default: until interrupted)")
    p.add_argument("--master-encoder", metavar="SIGNAL",
                   help="turn the drive's master encoder input ([MC] 7.3; counted once 172Ah selects a source): "
                        "speed:EDGES_PER_S, profile:T=EDGES_PER_S,... (T in s) or recorded:FILE (CSV s,edges)")
    p.add_argument("--dump-memory", metavar="FILE",
                   help="when stopped, write the drive's memory (parameters ROM and RAM, curves and command table "
                        "in RAM and flash) to FILE as JSON (emulator/linmot/memory.py), to check what a PLC wrote")
    p.add_argument("--input", metavar="FILE",
                   help="an input script: signals on the drive's I/O (X4.6 trigger, X4.4 analog, ...), one per line, "
                        "times in s from power-on (emulator/linmot/io_script.py; docs/emulator.md 'The drive's I/O')")
    p.add_argument("--signal", action="append", default=[], metavar="LINE",
                   help="one input-script line, e.g. 'pulse X4.6 2.0 0.1 0.02 5' or '1.5 X4.6 1' (repeatable)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    """Exit status 0 when stopped (duration, Ctrl-C, SIGTERM), 2 for bad arguments, 1 when the bus
    cannot be opened or the drive fails while serving. On stopping it says what it served."""
    from ..cliargs import check_output_file, error

    def _error(message: str, rc: int) -> int:
        error(args, message)
        return rc

    import signal
    import threading
    import time

    import can

    from ..bus import open_bus, parse_bus_spec
    from .linmot.drive import DriveTimings
    from .linmot.master_encoder import parse_signal
    from .linmot.profile import ProfileError, load_profile
    from .models import make_drive, model_named

    spec = f"{args.interface}:{args.channel}"
    try:
        model = model_named(args.drive)
    except ValueError as exc:
        return _error(f"--drive {args.drive}: {exc}", 2)
    try:
        parse_bus_spec(spec, where=f"--interface {args.interface} --channel {args.channel}")
        if args.dump_memory:
            check_output_file(args.dump_memory, f"--dump-memory {args.dump_memory}")
        profile = load_profile(args.profile) if args.profile else None
        signal_ = parse_signal(args.master_encoder) if args.master_encoder else None
    except ProfileError as exc:
        return _error(f"--profile {exc}", 2)
    except OSError as exc:
        return _error(f"--profile {args.profile}: {exc.strerror or exc}", 2)
    except ValueError as exc:
        return _error(str(exc), 2)
    if args.node_id is None:
        args.node_id = model.default_node_id
    drive = make_drive(model, args.node_id, profile=profile, timings=DriveTimings.fast() if args.fast else None)
    if signal_ is not None:
        drive.mc.encoder.drive_with(signal_, 0)
    from .linmot.io_script import ScriptError, apply_line, apply_script
    try:
        if args.input:
            with open(args.input) as f:
                apply_script(drive.io, f.read())
        for line in args.signal:
            apply_line(drive.io, line)
    except OSError as exc:
        return _error(f"--input {args.input}: {exc.strerror or exc}", 2)
    except ScriptError as exc:
        return _error(f"input script: {exc}", 2)
    try:
        bus = open_bus(spec, bitrate=args.bitrate)
    except (can.CanError, OSError, ValueError, ImportError) as exc:
        return _error(f"cannot open {args.interface} channel {args.channel}: {exc}", 1)

    stop = threading.Event()
    old_handler = None
    rc = 0
    t0 = time.monotonic()
    served = None
    try:                                            # from here on Ctrl-C, wherever it comes, ends in the report
        if threading.current_thread() is threading.main_thread():   # signal handlers: main thread only
            old_handler = signal.signal(signal.SIGTERM, lambda signum, frame: stop.set())
        drive.attach(bus)
        served = drive._server
        print(f"{model.name} node {args.node_id} on {args.interface}:{args.channel} "
              f"(boot-up after {drive.timings.boot_ns / 1e9:g} s); Ctrl-C stops", flush=True)
        deadline = None if args.duration is None else time.monotonic() + args.duration
        while not stop.is_set() and (deadline is None or time.monotonic() < deadline):
            stop.wait(0.05 if deadline is None else max(0.0, min(0.05, deadline - time.monotonic())))
    except KeyboardInterrupt:
        pass
    finally:
        try:
            drive.detach()
        except RuntimeError as exc:                 # the drive raised while serving
            rc = _error(str(exc), 1)
        bus.shutdown()
        if args.dump_memory:
            from .linmot.memory import write
            try:
                write(drive, args.dump_memory)
            except OSError as exc:
                rc = _error(f"--dump-memory {args.dump_memory}: {exc.strerror or exc}", 1)
        if old_handler is not None:
            signal.signal(signal.SIGTERM, old_handler)
    done = (f" after {time.monotonic() - t0:.1f} s: {served.frames_received} frames received, "
            f"{served.frames_sent} sent" if served is not None else "")
    print(f"{model.name} node {args.node_id} stopped in NMT state {drive.nmt_state}{done}", flush=True)
    return rc
