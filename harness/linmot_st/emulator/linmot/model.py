"""DriveModel: what makes one LinMot drive type differ from another in the emulator, as data.

A model is its name, its parameter profile (a data file: identity, firmware layers, parameter and error-text
tables; profile.py), the manufacturer services its firmware offers (manufacturer.py: one row per sub-index,
with read/write handlers), and its quirks: small objects whose `apply(drive)` changes a freshly built drive
where this type behaves differently (a boot time, a refused service, ...). The drive (drive.py) takes its
defaults from the model; emulator/models.py names the models and builds drives (`make_drive`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Protocol

from .manufacturer import E1100_SERVICES, Service
from .profile import DEFAULT_PROFILE, DriveProfile, load_profile


class Quirk(Protocol):
    """A behaviour of one drive type, applied to each drive of the model when it is built."""

    def apply(self, drive) -> None: ...


@dataclass(frozen=True)
class DriveModel:
    name: str                                  # "E1100": `linmot-st emulate --drive NAME`, make_drive(NAME, ...)
    profile: Path                              # the parameter profile data file (JSON, profile.py's format)
    services: tuple[Service, ...]              # the manufacturer services 2000h..5FFFh, by sub-index
    quirks: tuple[Quirk, ...] = ()
    description: str = ""
    drive_class: type | None = None            # the node class when the model needs more than data and quirks
    default_node_id: int = 1                   # where the harness lets the drive choose (`emulate --drive`)

    def load_profile(self) -> DriveProfile:
        return load_profile(self.profile)

    def without_services(self, *subs: int) -> tuple[Service, ...]:
        """This model's services less the given sub-indexes (a firmware that does not offer them)."""
        return tuple(s for s in self.services if s.sub not in subs)


# ---------------------------------------------------------------- ready-made quirks

@dataclass(frozen=True)
class BootTime:
    """Boot-up message `boot_ns` after power-on or reset, whatever timings the drive was given."""
    boot_ns: int

    def apply(self, drive) -> None:
        drive.timings = replace(drive.timings, boot_ns=self.boot_ns)


@dataclass(frozen=True)
class FifoTransmit:
    """One transmit FIFO instead of one buffer per message kind (bus/sim.py `tx_by_priority`)."""

    def apply(self, drive) -> None:
        drive.tx_by_priority = False


E1100 = DriveModel(
    name="E1100",
    profile=DEFAULT_PROFILE,
    services=E1100_SERVICES,
    description="LinMot E1100-CO (CANopen firmware): the seeds' example drive",
)
