"""PLC faults: the exception, and where a fault happened when the C could only report its address."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

FAULT_KINDS = {
    1: "integer division by zero or overflow (MIN / -1)",
    2: "array index out of range",
    3: "arithmetic fault",
    4: "fatal signal",
    5: "scan watchdog: the scan ran longer than the watchdog allows",
    # operations whose value MatIEC's C leaves undefined: stopped rather than given a value of our own
    6: "SHL/SHR/ROL/ROR count that MatIEC's C leaves undefined (below 0, at or beyond the width it shifts in)",
    7: ("REAL/LREAL to integer conversion that MatIEC's C leaves undefined (inf, NaN or out of range; also "
        "inside its TIME * x, TIME / x and REAL_TO_TIME, which convert seconds and nanoseconds from double)"),
}


class PlcFault(Exception):
    """A PLC fault: the scan was abandoned and the PLC stays stopped until reset()."""

    def __init__(self, kind: int, pou: str = "", file: str = "", line: int = 0, pc: int = 0, scan: int = 0):
        self.kind = kind
        self.kind_text = FAULT_KINDS.get(kind, f"fault kind {kind}")
        self.pou = pou
        self.file = file
        self.line = line
        self.pc = pc
        self.scan = scan
        where = f" in POU {pou}" if pou else " in an unknown POU"
        if file:
            where += f" ({file}:{line})" if line else f" ({file})"
        super().__init__(f"PLC fault: {self.kind_text}{where}, scan {scan}")


def locate_with_debug_info(library: Path, pc: int, pous: set[str]) -> tuple[str, str, int] | None:
    """(POU, file, line) for a code address, from the library's DWARF line table (gcc -g, iec2c -O l).

    addr2line -i lists the inlined frames innermost first, each with its own source position; the first
    frame whose function is a POU (FB/program bodies are `<POU>_body__`) is the one that faulted.
    """
    tool = shutil.which("addr2line")
    if not tool or not pc:
        return None
    try:
        out = subprocess.run([tool, "-f", "-i", "-e", str(library), hex(pc)], capture_output=True,
                             text=True, timeout=10, check=False).stdout.splitlines()
    except (OSError, subprocess.SubprocessError):
        return None
    for func, pos in zip(out[0::2], out[1::2]):
        name = func.split(".")[0].upper()   # drop gcc clone suffixes such as .part.0
        for suffix in ("_BODY__", "_INIT__"):
            if name.endswith(suffix):
                name = name[: -len(suffix)]
        if name in pous:
            file, _, line = pos.partition(":")
            line = line.split(" ")[0]
            if file == "??":
                return name, "", 0
            return name, file, int(line) if line.isdigit() else 0
    return None
