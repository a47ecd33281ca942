"""The drive series a PVL file is for, and what the file format does differently for each.

Seed 000 (23.06.2010) is written for the E1100 and the B1100 and names where they differ:
- stringlets (2.5): E1100/E1200 stringlet k at string UPID + k; B1100 at string UPID + k - 1;
- UPID ranges (3, Table 3): E1100 layers have their own ranges; "On B1100 controllers, the UPIDs of the
  different software layers are mixed and cannot be grouped";
- tree identity (Table 4): E1100 0539h/0532h/0533h ...; B1100 2CA1h/2C96h/2C97h (OS), 2FA1h/2F96h/2F97h (MC),
  2EA1h/2E96h/2E97h (interface), 2DA1h/2D96h/2D97h (application);
- curves (5) and command tables (6) exist only on the E1100.

Which series a file is for: the seeds' PVL format has no field for it. The only place a file names its
firmware is @TreeFileName (seed example: `OSTREE1100OS__V3S0_b1`, an E1100). INFERRED (docs/pvl.md): a tree
file name containing "B1100" marks a B1100 file; any other name an E1100 file (every name in the sources).
"""

from __future__ import annotations

from dataclasses import dataclass

from . import codec
from .layers import LAYERS


@dataclass(frozen=True)
class DriveType:
    name: str                                   # "E1100", "B1100"
    first_stringlet_offset: int                 # stringlet 1 at string UPID + this (seed 000 2.5)
    identity_upids: dict[int, tuple[int, int, int]]  # layer -> (tree ID, main version, sub version) UPIDs
    layer_ranges: bool                          # each layer has its own UPID range (Table 3)
    curves: bool                                # seed 000 chapter 5
    command_table: bool                         # seed 000 chapter 6

    @property
    def a_name(self) -> str:
        """'an E1100', 'a B1100' (for messages)."""
        return ("an " if self.name[0] in "AEFHILMNORSX" else "a ") + self.name

    def stringlet_upid(self, string_upid: int, k: int) -> int:
        """UPID of stringlet k (k = 1, 2, ...) of the string parameter at `string_upid`."""
        return codec.stringlet_upid(string_upid, k, self.first_stringlet_offset)

    def string_upid_of_first(self, first_stringlet_upid: int) -> int:
        return first_stringlet_upid - self.first_stringlet_offset


E1100 = DriveType("E1100", 1,
                  {n: (lay.tree_id_upid, lay.main_version_upid, lay.sub_version_upid) for n, lay in LAYERS.items()},
                  layer_ranges=True, curves=True, command_table=True)
B1100 = DriveType("B1100", 0,
                  {1: (0x2CA1, 0x2C96, 0x2C97), 2: (0x2FA1, 0x2F96, 0x2F97),
                   3: (0x2EA1, 0x2E96, 0x2E97), 4: (0x2DA1, 0x2D96, 0x2D97)},
                  layer_ranges=False, curves=False, command_table=False)
DRIVE_TYPES: dict[str, DriveType] = {t.name: t for t in (E1100, B1100)}

B1100_TREE_MARK = "B1100"     # INFERRED: how a B1100 tree file name is told from an E1100 one


def drive_type_of_tree_file(tree_file_name: str) -> DriveType:
    return B1100 if B1100_TREE_MARK in tree_file_name.upper() else E1100


def drive_type(name: str) -> DriveType:
    """The drive type called `name` (case-insensitive: "e1100", "B1100"). Raises ValueError."""
    try:
        return DRIVE_TYPES[name.upper()]
    except KeyError:
        raise ValueError(f"unknown drive type {name!r} (known: {', '.join(DRIVE_TYPES)})") from None
