"""`python -m linmot_st_vcan [--timeout S] COMMAND...`: run a command in a User-Mode Linux guest with vcan0 and
vcan1 up (the test environment of the socketcan tests), with this checkout and venv; its output is printed,
the exit status is the command's (125 when no guest can be had here, 124 at the timeout).

    python -m linmot_st_vcan -- sh -c 'linmot-st emulate --interface socketcan --channel vcan0 --fast &
                                       sleep 5; linmot-st commission examples/two_axes.pvl --bus socketcan:vcan0 --no-emulate'
"""

from __future__ import annotations

import argparse
import sys


def main(argv: list[str] | None = None) -> int:
    from . import Machine, Unavailable

    parser = argparse.ArgumentParser(prog="python -m linmot_st_vcan", description=__doc__.splitlines()[0])
    parser.add_argument("--timeout", type=float, default=600, metavar="S", help="stop the guest after S seconds")
    parser.add_argument("command", nargs=argparse.REMAINDER, help="the command and its arguments")
    args = parser.parse_args(argv)
    command = args.command[1:] if args.command[:1] == ["--"] else args.command
    if not command:
        parser.error("no command given")
    try:
        run = Machine().run(command, timeout_s=args.timeout)
    except Unavailable as exc:
        print(f"error: no SocketCAN guest here: {exc}", file=sys.stderr)
        return 125
    sys.stdout.write(run.output)
    if run.timed_out:
        print(f"error: stopped by the timeout after {args.timeout:g} s; kernel log: {run.work_dir / 'kernel.log'}",
              file=sys.stderr)
        return 124
    return run.returncode if run.returncode is not None else 125


if __name__ == "__main__":
    sys.exit(main())
