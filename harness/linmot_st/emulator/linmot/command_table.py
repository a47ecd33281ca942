"""Command table: 256 entries of 64 bytes in RAM and in flash (seeds chapter 6; spec 2.2, 3.5).

E1100 transfers an entry in 2-byte steps (the protocol options allow 4): `prepare` (83h, block size 64) then
`write` (84h) until 64 bytes arrived; the entry becomes present then, if its version word is A701h. Reading:
`get` (85h) returns the block size and rewinds the read cursor, `read` (86h) the next bytes with a result.
"""

from __future__ import annotations

import struct

from .. import codes
from ..codes import NoMoreData, NotStarted

ENTRY_SIZE = 64
ENTRIES = range(256)
VERSION_ID = 0xA701
NOT_LINKED = 0xFFFF


def build_entry(header: int, params: bytes = b"", *, name: str = "", link: int = NOT_LINKED) -> bytes:
    """A 64-byte entry laid out as seeds table 10 (version A701h, link, motion command header, parameters, name)."""
    if len(params) > 32:
        raise ValueError("motion command parameters take at most 32 bytes")
    if len(name) > 15:
        raise ValueError("entry name takes at most 15 characters plus 00h")
    return struct.pack("<HHH32s16s10s", VERSION_ID, link, header, params, name.encode("latin-1"), b"")


class CommandTable:
    def __init__(self):
        self.ram: dict[int, bytes] = {}
        self.flash: dict[int, bytes] = {}
        self._writes: dict[int, bytearray] = {}
        self._reads: dict[int, int] = {}

    def boot(self) -> None:
        self.ram = dict(self.flash)
        self._writes.clear()
        self._reads.clear()

    # ---- write (83h, 84h) ----
    def prepare(self, entry: int, size: int) -> int:
        if size != ENTRY_SIZE:
            return codes.RC_SIZE_ERROR
        self.ram.pop(entry, None)          # the entry is rewritten: absent until its block is complete
        self._reads.pop(entry, None)
        self._writes[entry] = bytearray()
        return codes.RC_OK

    def write(self, entry: int, chunk: bytes) -> int:
        buf = self._writes.get(entry)
        if buf is None:
            return codes.RC_BLOCK_FINISHED
        buf += chunk
        if len(buf) < ENTRY_SIZE:
            return codes.RC_NOT_FINISHED
        del self._writes[entry]
        if struct.unpack_from("<H", buf, 0)[0] != VERSION_ID:
            return codes.RC_RANGE_ERROR     # refused: the entry stays absent
        self.ram[entry] = bytes(buf[:ENTRY_SIZE])
        return codes.RC_OK

    # ---- read (85h, 86h) ----
    def get(self, entry: int) -> tuple[int, int]:
        if entry not in self.ram:
            self._reads.pop(entry, None)
            return codes.RC_NOT_PRESENT, 0
        self._reads[entry] = 0
        return codes.RC_OK, ENTRY_SIZE

    def read(self, entry: int, size: int = 2) -> tuple[int, bytes]:
        """The next `size` bytes of the entry and the result 04h (more follows) or 00h (that was the last
        step). NotStarted without an 85h; NoMoreData after the end."""
        pos = self._reads.get(entry)
        if pos is None or entry not in self.ram:
            raise NotStarted(f"CT entry {entry}: no get-entry (85h) before reading")
        if pos >= ENTRY_SIZE:
            raise NoMoreData(f"CT entry {entry}: already read to the end")
        self._reads[entry] = pos + size
        rc = codes.RC_OK if pos + size >= ENTRY_SIZE else codes.RC_NOT_FINISHED
        return rc, self.ram[entry][pos:pos + size]

    # ---- delete, presence, flash ----
    def delete(self, entry: int) -> None:
        self.ram.pop(entry, None)
        self._writes.pop(entry, None)
        self._reads.pop(entry, None)

    def delete_all(self) -> None:
        self.ram.clear()
        self._writes.clear()
        self._reads.clear()

    def presence(self, block: int) -> int:
        """Presence list `block` (0..7): bit n = entry 32*block + n, 0 = present."""
        bits = 0xFFFFFFFF
        for n in range(32):
            if 32 * block + n in self.ram:
                bits &= ~(1 << n)
        return bits

    def flash_image_bytes(self) -> int:
        return ENTRY_SIZE * len(self.ram)

    def commit_to_flash(self) -> None:
        self.flash = dict(self.ram)
