"""LinMot parameter types (LinRS type codes, spec 3.7) and the 32-bit raw access every parameter offers.

Over the bus every parameter is a 32-bit value; the drive keeps only the bits of the parameter's type
("the operating system will filter out the relevant number of bits", seeds 2.5) and sign-extends signed
types when it reads them back.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ParamType:
    name: str
    code: int        # LinRS "get parameter type" code
    bits: int        # width kept by the drive; 0 for the string header (no 32-bit value)
    signed: bool

    @property
    def mask(self) -> int:
        return (1 << self.bits) - 1

    @property
    def lowest(self) -> int:
        return -(1 << (self.bits - 1)) if self.signed else 0

    @property
    def highest(self) -> int:
        return (1 << (self.bits - 1)) - 1 if self.signed else self.mask

    def from_raw(self, raw32: int) -> int:
        """The value the drive keeps when `raw32` (the 4 SDO bytes as an unsigned number) is written."""
        v = raw32 & self.mask
        if self.signed and v >> (self.bits - 1):
            v -= 1 << self.bits
        return v

    def to_raw(self, value: int) -> int:
        """The 32-bit raw value read back (two's complement, sign-extended for signed types)."""
        return value & 0xFFFFFFFF


TYPES: dict[str, ParamType] = {t.name: t for t in (
    ParamType("BOOL", 0x00, 1, False),
    ParamType("UINT8", 0x01, 8, False),
    ParamType("SINT8", 0x02, 8, True),
    ParamType("UINT16", 0x03, 16, False),
    ParamType("SINT16", 0x04, 16, True),
    ParamType("UINT32", 0x05, 32, False),
    ParamType("SINT32", 0x06, 32, True),
    ParamType("STRING", 0x08, 0, False),
    ParamType("RADIO_DIR_BIT", 0x0A, 16, False),   # width INFERRED (as RADIO_DIR16); LinRS types UPID 2008h so
    ParamType("RADIO_DIR16", 0x0B, 16, False),
    ParamType("ENUM_DIR8", 0x0C, 8, False),
    ParamType("ENUM_DIR16", 0x0D, 16, False),
    ParamType("STRINGLET", 0x0E, 32, False),
)}


def stringlets_of(text: str, count: int) -> list[int]:
    """Split `text` into `count` stringlet values: 4 characters each, first character in the low byte
    ('X Ax' -> 78412058h, seeds 2.5), padded with 00h."""
    raw = text.encode("latin-1")
    if len(raw) > 4 * count:
        raise ValueError(f"string {text!r} is longer than {4 * count} characters")
    raw = raw.ljust(4 * count, b"\0")
    return [int.from_bytes(raw[4 * k:4 * k + 4], "little") for k in range(count)]


def text_of(stringlets: list[int]) -> str:
    """The string held by stringlet values, up to the first 00h."""
    raw = b"".join((v & 0xFFFFFFFF).to_bytes(4, "little") for v in stringlets)
    return raw.split(b"\0", 1)[0].decode("latin-1")
