"""The CAN frame as the simulated bus, the emulator and the co-simulation pass it around.

A small immutable value, cheaper than python-can's Message on the hot path of the simulated bus;
`to_message`/`from_message` convert at the boundary to real python-can buses.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True, slots=True)
class Frame:
    can_id: int          # 11-bit identifier (COB-ID)
    data: bytes = b""    # 0..8 bytes; the DLC is its length
    rtr: bool = False    # remote transmission request (node guarding)
    rtr_dlc: int = 0     # a remote frame carries a DLC but no data: the length it asks for

    def __post_init__(self) -> None:
        if not 0 <= self.can_id <= 0x7FF:
            raise ValueError(f"CAN identifier {self.can_id:#x} is not an 11-bit identifier")
        if len(self.data) > 8:
            raise ValueError(f"CAN frame carries at most 8 data bytes, got {len(self.data)}")
        if self.rtr and self.data:
            raise ValueError("a remote frame carries no data (give its DLC as rtr_dlc)")
        if not 0 <= self.rtr_dlc <= 8 or (self.rtr_dlc and not self.rtr):
            raise ValueError(f"rtr_dlc {self.rtr_dlc} is only for remote frames, 0..8")

    @classmethod
    def checked_by_caller(cls, can_id: int, data: bytes) -> Frame:
        """A data frame without __post_init__'s checks, for a hot path whose identifier is 11-bit and whose
        data is at most 8 bytes by construction (the emulated drive's PDOs: COB-ID masked with 7FFh, a
        mapping longer than 8 bytes refused)."""
        f = _new_object(cls)
        _set_can_id(f, can_id)
        _set_data(f, data)
        _set_rtr(f, False)
        _set_rtr_dlc(f, 0)
        return f

    @property
    def dlc(self) -> int:
        return self.rtr_dlc if self.rtr else len(self.data)

    def __str__(self) -> str:  # candump style: 601#2301205046000A00
        return f"{self.can_id:03X}#" + ("R" if self.rtr else self.data.hex().upper())

    def to_message(self, timestamp: float = 0.0):
        import can

        return can.Message(arbitration_id=self.can_id, data=self.data, is_extended_id=False,
                           is_remote_frame=self.rtr, dlc=self.dlc, timestamp=timestamp)

    @classmethod
    def from_message(cls, msg) -> Frame:
        if msg.is_remote_frame:
            return cls(msg.arbitration_id, b"", True, msg.dlc)
        return cls(msg.arbitration_id, bytes(msg.data))


# the slots' own setters (they bypass the frozen __setattr__ without object.__setattr__'s lookup by name):
# checked_by_caller builds a frame in about 60 % of the time of object.__setattr__ per field
_new_object = object.__new__
_set_can_id, _set_data, _set_rtr, _set_rtr_dlc = (Frame.__dict__[name].__set__
                                                  for name in ("can_id", "data", "rtr", "rtr_dlc"))
