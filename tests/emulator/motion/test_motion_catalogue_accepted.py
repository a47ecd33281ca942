"""Every motion command of the protocol catalogue that the E1100 has is accepted by the emulated E1100: run as
its transport says (RxPDO2 + RxPDO3 up to 12 parameter bytes, a command-table entry started by 200xh beyond),
the drive never logs 0081h (Unknown Motion Cmd) for it, and executes it (its header is the last the interpreter
ran). One parametrised test over the whole catalogue, so a row added without a handler fails here.

The field values are small and valid for every group (curve 1 exists, entry 1 is a NOP); a command may still
end in a drive error of its own kind (e.g. a stream stopped, a wait left waiting), which is not 0081h.
"""

from __future__ import annotations

import pytest

from linmot_st.emulator import DriveTimings, E1100Drive, build_entry, load_profile
from linmot_st.emulator.testing import MotionLink
from linmot_st.protocol import commands as C
from linmot_st.protocol import words as W

MS = 1_000_000
MM = 10_000
VALUES = {0x1194: 2, 0x146F: 280 * MM, 0x146E: -10 * MM, 0x14BE: 500_000, 0x14BF: 500_000, 0x14C0: 500_000,
          0x2041: 2}                       # RxPDO3 carries parameter bytes 6..11
SMALL = {"target": 10, "vmax": 100, "acc": 100, "dec": 100, "curve_id": 1, "offset": 0, "curve_time": 100_000,
         "amplitude": 1000, "time_scale": 10_000, "entry": 1, "mask": 1, "value": 1, "time": 10,
         "control_word": 0x003F, "upid": 0x14BE, "home_position": 0, "set": 0}
# 00Fxh restarts the whole drive (its own test: tests/emulator/motion/test_motion_vai_variants.py)
NOT_HERE = {getattr(C, "RESET", None)}
E1100_ROWS = sorted(cid for cid, row in C.COMMANDS.items() if C.E1100 in row.drives and cid not in NOT_HERE)


def _link() -> MotionLink:
    d = E1100Drive(1, load_profile().with_defaults(VALUES), timings=DriveTimings.fast())
    link = MotionLink(d)
    link.enable()
    link.home()
    link.advance(5 * MS)
    return link


def test_the_catalogue_is_large():
    # the 30 commands of the first motion issue and the rows added since (issue 20 and its companion)
    assert len(E1100_ROWS) > 150, len(E1100_ROWS)


@pytest.mark.parametrize("cid", E1100_ROWS, ids=lambda c: f"{c:03X}h")
def test_every_e1100_row_is_accepted(cid):
    row = C.COMMANDS[cid]
    link = _link()
    d = link.drive
    d.ct.ram[1] = build_entry(C.NOP << 4, b"")
    fields = {n: SMALL.get(n, 1) for n in row.field_names}
    if row.transport is C.Transport.COMMAND_TABLE:
        d.ct.ram[9] = build_entry(cid << 4, C.encode(cid, 0, **fields)[2:])
        link.command(C.START_COMMAND_TABLE, entry=9)
    else:
        link.command(cid, **fields)
    link.advance(20 * MS)
    assert W.ERR_UNKNOWN_MOTION_CMD not in [e.code for e in d.errlog.entries], f"{cid:03X}h: 0081h"
    assert cid in [h >> 4 for _, h, _ in d.mc.executed], f"{cid:03X}h was not executed"
