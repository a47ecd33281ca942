"""The drive's memory as JSON: every parameter's ROM and RAM, the curves and the command table in RAM and in
flash. `linmot-st emulate --dump-memory FILE` writes it when it stops, so that what a PLC wrote into a drive
served by another process can be checked like a drive in the same process (`load` puts it into an
E1100Drive of the same profile, which `commission.verify` then compares with the PVL file).

    {"format": "linmot-st-e1100-memory-1", "node_id": 1, "nmt_state": "OPERATIONAL",
     "params": {"1194": [rom, ram], ...},                  # UPID in hex -> raw values as the drive keeps them
     "curves": {"ram": {"1": {"info": "46 00 ...", "data": "..."}}, "flash": {...}},
     "command_table": {"ram": {"5": "hex"}, "flash": {...}}}
"""

from __future__ import annotations

import json
from pathlib import Path

from .curves import Curve

FORMAT = "linmot-st-e1100-memory-1"


def dump(drive) -> dict:
    """The memory of `drive` (take drive.lock while it is served)."""
    def curves(store: dict) -> dict:
        return {str(cid): {"info": c.info.hex(" "), "data": c.data.hex()} for cid, c in sorted(store.items())}

    def entries(store: dict) -> dict:
        return {str(eid): bytes(data).hex(" ") for eid, data in sorted(store.items())}

    return {"format": FORMAT, "node_id": drive.node_id, "nmt_state": drive.nmt_state,
            "params": {f"{p.upid:04X}": [p.rom, p.ram] for p in drive.params},
            "curves": {"ram": curves(drive.curves.ram), "flash": curves(drive.curves.flash)},
            "command_table": {"ram": entries(drive.ct.ram), "flash": entries(drive.ct.flash)}}


def load(drive, memory: dict) -> None:
    """Put a dump() into `drive` (same profile: a UPID it does not have is a ValueError). The NMT state is
    recorded in the dump for information only: `drive` keeps its own."""
    if memory.get("format") != FORMAT:
        raise ValueError(f"not a drive memory dump (format {memory.get('format')!r}, expected {FORMAT})")
    for upid_hex, (rom, ram) in memory["params"].items():
        upid = int(upid_hex, 16)
        if upid not in drive.params:
            raise ValueError(f"UPID {upid_hex}h of the dump is not a parameter of this drive's profile")
        p = drive.params[upid]
        p.rom, p.ram = rom, ram
    for where in ("ram", "flash"):
        setattr(drive.curves, where, {int(cid): Curve(int(cid), bytes.fromhex(c["info"]), bytes.fromhex(c["data"]))
                                      for cid, c in memory["curves"][where].items()})
        setattr(drive.ct, where, {int(eid): bytes.fromhex(data) for eid, data in memory["command_table"][where].items()})


def write(drive, path: Path | str) -> None:
    Path(path).write_text(json.dumps(dump(drive), indent=1) + "\n", encoding="utf-8")


def read(path: Path | str) -> dict:
    return json.loads(Path(path).read_text(encoding="utf-8"))
