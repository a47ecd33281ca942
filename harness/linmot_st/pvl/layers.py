"""Firmware layers of the E1100 (seed documents, chapter 3): names, UPID ranges, tree-identity UPIDs.

A PVL Parameter object holds the parameters of one layer together with the identity of the parameter
tree they were exported from. The commissioning code reads the same identity from the drive (Table 4)
and applies the compatibility rules of Table 5 (see `TreeIdentity.problems_against`).
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Layer:
    number: int
    name: str
    upid_first: int          # E1100 UPID range of the layer (Table 3)
    upid_last: int
    tree_id_upid: int        # where the drive reports the installed tree (Table 4, E1100 column)
    main_version_upid: int
    sub_version_upid: int

    def holds(self, upid: int) -> bool:
        return self.upid_first <= upid <= self.upid_last


LAYERS: dict[int, Layer] = {
    1: Layer(1, "Operating System", 0x0000, 0x0EFF, 0x0539, 0x0532, 0x0533),
    2: Layer(2, "Motion Control SW", 0x1000, 0x1EFF, 0x0561, 0x055A, 0x055B),
    3: Layer(3, "Interface SW", 0x2000, 0x2EFF, 0x0589, 0x0582, 0x0583),
    4: Layer(4, "Application", 0x3000, 0x3EFF, 0x05B1, 0x05AA, 0x05AB),
}


@dataclass(frozen=True)
class TreeIdentity:
    """The parameter tree of one layer: Tree ID, Main Version, Sub Version (seeds, chapter 3 and 4)."""

    layer: int
    tree_id: int
    main_version: int
    sub_version: int

    def problems_against(self, tree_id: int, main_version: int, sub_version: int) -> list[str]:
        """The compatibility rules of Table 5, this identity being the source file and the arguments
        the target drive. Returns the broken rules as sentences; empty when the layer may be written."""
        problems = []
        if tree_id != self.tree_id:
            problems.append(f"layer {self.layer}: tree ID {self.tree_id} in the file, {tree_id} on the drive "
                            "(must be the same)")
        if main_version != self.main_version:
            problems.append(f"layer {self.layer}: main version {self.main_version} in the file, {main_version} "
                            "on the drive (must be the same)")
        if sub_version < self.sub_version:
            problems.append(f"layer {self.layer}: sub version {self.sub_version} in the file, {sub_version} "
                            "on the drive (the drive's must be the same or greater)")
        return problems
