"""The emulated LinMot B1100 (CANopen firmware): a drive model on the drive-model seam (docs/emulator.md 14).

What differs from the E1100, and where it is done here:
- the manufacturer object: only 2000h, with subs 00h, 01h (RAM value of the selected UPID), 02h (ROM value),
  0Bh (reset drive) and C0h (select the UPID); access is select, then read or write ([CO1100] p.23, p.31-33).
  Everything else of 2000h..5FFFh is absent and refused as a CANopen device refuses a missing object (no
  curves, command table, defaults, UPID lists, MC stop/start, flash): `B1100_SERVICES`.
- parameters: 16-bit UPIDs in mixed ranges, stringlet 1 at the string's UPID, no stored defaults, limits or
  access rights (data/b1100_default.json, profile.py `Definitions`).
- the motion control and PDOs run the E1100's model on the B1100's parameters: each B1100 row names its
  E1100 counterpart (`e1100_upid` in data/b1100_parameters.csv), and the MC and the PDOs see the store
  through `E1100View`, keyed by those counterparts; the bus sees the B1100 UPIDs.
- 1018h holds the vendor ID only ([CO1100] p.23); the 6085h flag restores the installation values at boot
  (LT6 4.1); the default node ID is 63 ([CO1100] p.9-10).
"""

from __future__ import annotations

import csv
import json
from dataclasses import dataclass
from functools import cache
from pathlib import Path

from .. import codes
from ..cia301.objects import INTEGER32, UNSIGNED16
from ..cia301.sdo import Reply
from ..codes import SdoAbort
from .drive import E1100Drive
from .manufacturer import Service
from .model import DriveModel
from .params import NotWritable, NoValueAccess, OutOfRange, UnknownUpid
from .profile import B1100_PROFILE

DEFAULT_NODE_ID = 63                  # MACID Parameter Value 6081h, default 63 ([CO1100] p.9-10)
DEFAULT_FLAG_UPID = 0x6085            # "Set All Parameters To Default At Next Boot" (LT6 4.1)
SUB_SELECT = 0xC0


@dataclass(frozen=True)
class B1100Settings:
    """The B1100 model's choices where the sources are silent (docs/emulator.md 14.2, INFERRED each).

    select_check       "access": C0h stores any 16-bit value and 01h/02h refuse an unknown UPID (06020000h);
                       "select": C0h itself refuses an unknown UPID
    initial_selection  the selected UPID after power-on and reset (0000h: no parameter, so 01h/02h abort)
    default_flag       6085h = 1 at boot restores the installation values to ROM and clears the flag
    special_mode       control word bit 10 in Operation Enabled enters state 20 (current 0: no analog input)
    """
    select_check: str = "access"
    initial_selection: int = 0x0000
    default_flag: bool = True
    special_mode: bool = True


# ---------------------------------------------------------------- the manufacturer services (2000h)

def _selected(m) -> int:
    return m.host.selected_upid


def _select(m, arg, sub, data):
    upid = int.from_bytes(data[0:2], "little")     # bytes 4-5 of the frame; 6-7 unused ([CO1100] p.31)
    h = m.host
    if h.b1100.select_check == "select" and upid not in h.params:
        raise SdoAbort(codes.ABORT_NO_OBJECT, f"no parameter with UPID {upid:04X}h")
    h.selected_upid = upid
    return codes.RC_OK


def _read_selected(m, arg, sub):
    upid = _selected(m)
    try:
        value = m.host.params.read(upid, "ram" if sub == 1 else "rom")
    except UnknownUpid as exc:
        raise SdoAbort(codes.ABORT_NO_OBJECT, str(exc)) from None
    except NoValueAccess as exc:             # the ROM of a variable
        raise SdoAbort(codes.ABORT_UNSUPPORTED, str(exc)) from None
    return (value & 0xFFFFFFFF).to_bytes(4, "little")


def _write_selected(m, arg, sub, data):
    upid = _selected(m)
    try:
        m.host.params.write(upid, int.from_bytes(data, "little"), ram=sub == 1, rom=sub == 2)
    except UnknownUpid as exc:
        raise SdoAbort(codes.ABORT_NO_OBJECT, str(exc)) from None
    except NoValueAccess as exc:
        raise SdoAbort(codes.ABORT_UNSUPPORTED, str(exc)) from None
    except NotWritable as exc:               # variables, the tree rows
        raise SdoAbort(codes.ABORT_READ_ONLY, str(exc)) from None
    except OutOfRange as exc:                # pragma: no cover - no limits stored: any value of the type
        raise SdoAbort(codes.ABORT_RANGE, str(exc)) from None
    return codes.RC_OK


def _reset(m, arg, sub, data):
    return Reply(then=m.host.software_reset)   # answered at once, then the boot ([CO1100] p.23)


# The B1100's object 2000h ([CO1100] p.23): sub 00h answers the highest sub-index (C0h)
B1100_SERVICES: tuple[Service, ...] = (
    Service(0x01, "RAM value of the selected UPID", "system", _read_selected, _write_selected, INTEGER32),
    Service(0x02, "ROM value of the selected UPID", "system", _read_selected, _write_selected, INTEGER32),
    Service(0x0B, "Reset drive", "system", None, _reset),
    Service(SUB_SELECT, "Update current UPID (select)", "system", None, _select, UNSIGNED16),
)


# ---------------------------------------------------------------- the E1100 view of the B1100's parameters

@cache
def e1100_counterparts(profile_path: Path = B1100_PROFILE) -> dict[int, int]:
    """B1100 UPID -> the E1100 UPID of the row it corresponds to (data/b1100_parameters.csv `e1100_upid`)."""
    spec = json.loads(Path(profile_path).read_text(encoding="utf-8"))
    path = Path(profile_path).parent / spec["parameter_file"]
    lines = [ln for ln in path.read_text(encoding="utf-8").splitlines() if ln.strip() and not ln.startswith("#")]
    out = {}
    for row in csv.DictReader(lines):
        if (row.get("e1100_upid") or "").strip():
            out[int(row["upid"], 16)] = int(row["e1100_upid"], 16)
    return out


class E1100View:
    """The B1100's parameter store under the E1100 UPIDs of their counterparts: what the E1100's motion
    control and PDO code read and write (the same Parameter objects, so a bus write is seen at once)."""

    def __init__(self, store, b_to_e: dict[int, int]):
        self.store = store
        self.e1100_of = {b: e for b, e in b_to_e.items() if b in store}
        self.by_upid = {e: store[b] for b, e in self.e1100_of.items()}

    def __getitem__(self, upid: int):
        try:
            return self.by_upid[upid]
        except KeyError:
            raise UnknownUpid(f"the B1100 has no counterpart of E1100 UPID {upid:04X}h") from None

    def __contains__(self, upid: int) -> bool:
        return upid in self.by_upid

    def write(self, upid: int, raw32: int, ram: bool, rom: bool) -> None:
        """A write as over the bus, to the B1100 UPID of E1100 UPID `upid` (test and harness setup)."""
        self.store.write(self[upid].upid, raw32, ram=ram, rom=rom)

    def set_variable(self, upid: int, value: int) -> None:
        p = self.by_upid.get(upid)
        if p is not None:
            p.ram = p.d.type.from_raw(value)


# ---------------------------------------------------------------- the drive

class B1100Drive(E1100Drive):
    """The emulated B1100: the E1100 node (NMT, heartbeat, SDO server, PDOs, MC) with the B1100's object
    dictionary, parameter protocol and data. Build it with `make_drive("B1100", node_id)`."""

    def __init__(self, node_id: int = DEFAULT_NODE_ID, *args, b1100: B1100Settings | None = None, **kw):
        self.b1100 = b1100 or B1100Settings()
        self.selected_upid = self.b1100.initial_selection
        kw.setdefault("model", B1100)
        super().__init__(node_id, *args, **kw)
        view, mc = self.mc.params, self.mc
        mc.special_mode = self.b1100.special_mode
        e_of = view.e1100_of
        self.params.use_strings([d for d in self.profile.parameters if d.kind == "string"],
                                self.profile.definitions.stringlet_offset)
        # SDO reads of the B1100's variables ask the MC by their E1100 counterparts
        self.params.live = lambda upid: mc.variable(e_of[upid]) if upid in e_of else None
        # 1018h: sub 1 (vendor ID) only ([CO1100] p.23)
        ident = self.comm.objects[0x1018]
        for s in (2, 3, 4):
            ident.subs.pop(s, None)
        ident.subs[0].default = ident.subs[0].value = 1

    def motion_params(self, store) -> E1100View:
        return E1100View(store, e1100_counterparts(Path(self.model.profile)))

    def _start_boot(self, t: int) -> None:
        self.selected_upid = self.b1100.initial_selection        # a RAM variable of the firmware
        p = self.params
        if self.b1100.default_flag and DEFAULT_FLAG_UPID in p and p[DEFAULT_FLAG_UPID].rom:
            for q in p:                     # the installation values back in ROM, the flag cleared (LT6 4.1)
                if q.d.kind == "par" and q.d.access == "rw":
                    q.rom = q.d.default
            p[DEFAULT_FLAG_UPID].rom = 0
        super()._start_boot(t)


B1100 = DriveModel(
    name="B1100",
    profile=B1100_PROFILE,
    services=B1100_SERVICES,
    description="LinMot B1100-GP with CANopen firmware: select-then-access parameters, no curves or command table",
    drive_class=B1100Drive,
    default_node_id=DEFAULT_NODE_ID,
)
