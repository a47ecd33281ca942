"""Input scripts for the drive's I/O (`linmot-st emulate --input FILE` / `--signal LINE`): one signal per
line, times in seconds from the drive's power-on, '#' starts a comment.

    0.5   X4.6 1                      # the trigger input rises at 0.5 s
    0.6   X4.6 0
    1.0   X4.4 2.5                    # 2.5 V on the analog input
    pulse X4.6 2.0 0.1 0.02 5         # pin, start, period, width (s), count
    ramp  3.0 4.0 0.0 10.0 100        # X4.4: start, end (s), from, to (V), steps
"""

from __future__ import annotations

from .io import ANALOG

S = 1_000_000_000


class ScriptError(ValueError):
    pass


def _ns(text: str) -> int:
    return round(float(text) * S)


def apply_line(io, line: str, t0_ns: int = 0) -> bool:
    """Schedule one script line on `io` (a DriveIO); False for a blank or comment line."""
    words = line.split("#", 1)[0].split()
    if not words:
        return False
    try:
        if words[0] == "pulse" and len(words) == 6:
            _, pin, start, period, width, count = words
            io.pulse_train(pin, t0_ns + _ns(start), _ns(period), _ns(width), int(count))
        elif words[0] == "ramp" and len(words) == 6:
            _, start, end, v0, v1, steps = words
            io.analog_ramp(t0_ns + _ns(start), t0_ns + _ns(end), float(v0), float(v1), int(steps))
        elif len(words) == 3:
            t, pin, value = words
            if pin == ANALOG:
                io.set_analog(float(value), t0_ns + _ns(t))
            else:
                io.set_input(pin, int(value), t0_ns + _ns(t))
        else:
            raise ScriptError("expected 'T PIN VALUE', 'pulse PIN START PERIOD WIDTH COUNT' or "
                              "'ramp START END V0 V1 STEPS'")
    except (KeyError, ValueError) as exc:
        raise ScriptError(f"{line.strip()!r}: {exc}") from None
    return True


def apply_script(io, text: str, t0_ns: int = 0) -> int:
    """Schedule every line of a script; returns the number of signal lines."""
    n = 0
    for no, line in enumerate(text.splitlines(), 1):
        try:
            n += apply_line(io, line, t0_ns)
        except ScriptError as exc:
            raise ScriptError(f"line {no}: {exc}") from None
    return n
