"""Argument checks shared by the `linmot-st` commands, and their one error style.

Every command checks its arguments before doing any work. A bad argument is a `UsageError`; `cli.main`
prints it as `linmot-st CMD: error: MESSAGE` (the form argparse uses for its own checks) and exits 2.
Output paths are checked by creating (and removing) a probe file where the output will go, which is the
only test that holds for /proc, /sys or a read-only mount whatever the permission bits say; no check
creates a folder.
"""

from __future__ import annotations

import argparse
import os
import sys
import tempfile
from pathlib import Path

# CiA 301's bit rates (the CAN bit timing table of CANopen devices); the E1100 takes these
CAN_BITRATES = (10_000, 20_000, 50_000, 125_000, 250_000, 500_000, 800_000, 1_000_000)


class UsageError(ValueError):
    """A bad argument: printed as `linmot-st CMD: error: ...`, exit status 2."""


def error(args: argparse.Namespace, message: str) -> None:
    """Print a command's error message in the common style (the exit status is the caller's)."""
    print(f"{getattr(args, '_prog', 'linmot-st')}: error: {message}", file=sys.stderr, flush=True)


def _probe(folder: Path, what: str) -> None:
    try:
        fd, name = tempfile.mkstemp(prefix=".linmot-st-probe-", dir=folder)
    except OSError as exc:
        raise UsageError(f"{what}: cannot write in {folder} ({exc.strerror or exc})") from None
    os.close(fd)
    os.unlink(name)


def check_output_file(path: str, what: str, extensions: tuple[str, ...] = ()) -> None:
    """`path` can be written as a file: not a folder, in a folder that exists and takes files."""
    p = Path(path).expanduser()
    if extensions and p.suffix.lower() not in extensions:
        raise UsageError(f"{what}: the extension says the format: {', '.join(extensions)}")
    if p.is_dir():
        raise UsageError(f"{what}: is a folder; give a file name")
    folder = p.parent if str(p.parent) else Path(".")
    if not folder.is_dir():
        raise UsageError(f"{what}: {folder} is not a folder" if folder.exists()
                         else f"{what}: folder {folder} does not exist")
    _probe(folder, what)


def check_output_folder(path: str, what: str) -> None:
    """`path` can hold output files: an existing folder that takes files, or a new one whose parent
    exists and takes folders (it is created when the output is written, not here)."""
    p = Path(path).expanduser()
    if p.exists():
        if not p.is_dir():
            raise UsageError(f"{what}: is not a folder")
        _probe(p, what)
        return
    parent = p.parent if str(p.parent) else Path(".")
    if not parent.is_dir():
        raise UsageError(f"{what}: folder {parent} does not exist (only {p.name} itself is created)")
    _probe(parent, what)


def existing_file(what: str):
    """An argparse type: a file that exists."""
    def check(text: str) -> str:
        if not Path(text).expanduser().is_file():
            raise argparse.ArgumentTypeError(f"{text}: no such file")
        return text
    check.__name__ = what
    return check


def _seconds(text: str, allow_zero: bool) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: not a number of seconds") from None
    if value != value or value == float("inf") or value < 0 or (value == 0 and not allow_zero):
        raise argparse.ArgumentTypeError(f"{text}: must be a number of seconds "
                                         + (">= 0" if allow_zero else "> 0"))
    return value


def positive_seconds(text: str) -> float:
    """An argparse type: a time in seconds, > 0."""
    return _seconds(text, allow_zero=False)


def non_negative_seconds(text: str) -> float:
    """An argparse type: a time in seconds, >= 0 (0 = off)."""
    return _seconds(text, allow_zero=True)


def can_bitrate(text: str) -> int:
    """An argparse type: one of the CANopen bit rates."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: not a bit rate") from None
    if value not in CAN_BITRATES:
        raise argparse.ArgumentTypeError(f"{value}: not a CAN bit rate (one of "
                                         f"{', '.join(str(b) for b in CAN_BITRATES)} bit/s)")
    return value


def int_range(lo: int, hi: int | None = None):
    """An argparse type: an integer in lo..hi (hi None: no upper limit)."""
    def check(text: str) -> int:
        try:
            value = int(text, 0)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r}: not an integer") from None
        if value < lo or (hi is not None and value > hi):
            raise argparse.ArgumentTypeError(f"{value}: must be {lo}..{hi}" if hi is not None
                                             else f"{value}: must be >= {lo}")
        return value
    check.__name__ = "integer"
    return check
