"""`linmot-st emulate`: serve an emulated E1100 drive on a python-can bus in real time until interrupted."""

from __future__ import annotations

import argparse


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "emulate", help="serve an emulated LinMot E1100 (CANopen) on a python-can bus",
        description="Serve an emulated LinMot E1100 CANopen drive on any python-can bus in real time, "
                    "e.g. --interface socketcan --channel vcan0, until Ctrl-C.")
    p.add_argument("--interface", required=True, help="python-can interface (socketcan, virtual, pcan, ...)")
    p.add_argument("--channel", required=True, help="python-can channel (vcan0, can0, a virtual channel name)")
    p.add_argument("--node-id", type=int, default=1, help="CANopen node ID 1..127 (default 1)")
    p.add_argument("--bitrate", type=int, default=500_000, help="bit rate in bit/s (default 500000, the E1100 default)")
    p.add_argument("--profile", help="drive profile JSON (default: the seeds' example drive)")
    p.add_argument("--fast", action="store_true", help="short boot/MC/flash durations (for demos and tests)")
    p.add_argument("--duration", type=float, help="stop after this many seconds (default: until interrupted)")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    import time

    import can

    from .drive import DriveTimings, E1100Drive
    from .profile import load_profile

    if args.interface == "udp_multicast":
        raise SystemExit("emulate: the udp_multicast interface is not supported (its traffic leaves the machine)")
    if not 1 <= args.node_id <= 127:
        raise SystemExit(f"emulate: node ID {args.node_id} is outside 1..127")
    profile = load_profile(args.profile) if args.profile else None
    drive = E1100Drive(args.node_id, profile, DriveTimings.fast() if args.fast else None)
    kwargs = {} if args.interface == "socketcan" else {"bitrate": args.bitrate}  # SocketCAN: set with `ip link`
    bus = can.Bus(interface=args.interface, channel=args.channel, **kwargs)
    print(f"E1100 node {args.node_id} on {args.interface}:{args.channel} "
          f"(boot-up after {drive.timings.boot_ns / 1e9:g} s); Ctrl-C stops", flush=True)
    drive.attach(bus)
    try:
        deadline = None if args.duration is None else time.monotonic() + args.duration
        while deadline is None or time.monotonic() < deadline:
            time.sleep(0.05 if deadline is None else max(0.0, min(0.05, deadline - time.monotonic())))
    except KeyboardInterrupt:
        pass
    finally:
        drive.detach()
        bus.shutdown()
    print(f"E1100 node {args.node_id} stopped in NMT state {drive.nmt_state}", flush=True)
    return 0
