"""Curve store: curves in RAM (what the motion control uses) and in flash (copied to RAM at boot), with the
per-curve cursors of the curve service (spec 2.2, 3.2..3.4; seeds chapter 5).

Writing: `add` (50h) opens a curve with its info and data block sizes; `add_info` (51h/54h) and `add_data`
(52h/53h) append 2 or 4 bytes per step. The info block is validated as soon as it is complete; a bad one
discards the curve and answers a result code. The curve becomes present (readable, saved by a flash save)
once both blocks are complete. Reading: `get` (60h) returns the sizes and rewinds the read cursors;
`read` (61h / 62h) returns the next bytes of a block, as many per step as the protocol options say.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

from .. import codes
from ..codes import NoMoreData, NotStarted

INFO_BLOCK_SIZE = 70
CURVE_IDS = range(1, 101)
OBJECT_TYPES = (0x0003, 0x0103)   # position vs time; cam (position vs encoder position)


@dataclass(frozen=True)
class Curve:
    curve_id: int
    info: bytes      # the 70-byte info block
    data: bytes      # setpoints, SInt32 little endian

    @property
    def object_type(self) -> int:
        return struct.unpack_from("<H", self.info, 2)[0]

    @property
    def setpoint_count(self) -> int:
        return struct.unpack_from("<H", self.info, 4)[0]

    @property
    def name(self) -> str:
        return self.info[8:30].split(b"\0", 1)[0].decode("latin-1")

    @property
    def x_length(self) -> int:
        return struct.unpack_from("<I", self.info, 32)[0]

    @property
    def setpoints(self) -> list[int]:
        return list(struct.unpack(f"<{len(self.data) // 4}i", self.data))

    @classmethod
    def build(cls, curve_id: int, setpoints: list[int], *, name: str = "", x_length: int = 0,
              object_type: int = 0x0003, x_dim: int = 0x001A, y_dim: int = 0x0005) -> Curve:
        """A curve with an info block laid out as seeds table 6 (wizard fields 0)."""
        info = struct.pack("<HHHH22sHIHHH28s", INFO_BLOCK_SIZE, object_type, len(setpoints), 4,
                           name.encode("latin-1"), curve_id, x_length, x_dim, y_dim, 0, b"")
        return cls(curve_id, info, struct.pack(f"<{len(setpoints)}i", *setpoints))


def validate_info(curve_id: int, info: bytes, data_size: int) -> int:
    """Result code for a complete info block: 00h, or D1h (a size field wrong) / C2h (a field out of range)."""
    offset, obj_type, n, type_size = struct.unpack_from("<HHHH", info, 0)
    (cid,) = struct.unpack_from("<H", info, 30)
    if offset != INFO_BLOCK_SIZE or type_size != 4 or n < 2 or data_size != 4 * n:
        return codes.RC_SIZE_ERROR
    if obj_type not in OBJECT_TYPES or cid != curve_id:
        return codes.RC_RANGE_ERROR
    return codes.RC_OK


class _Write:
    __slots__ = ("info_size", "data_size", "info", "data", "info_ok")

    def __init__(self, info_size: int, data_size: int):
        self.info_size, self.data_size = info_size, data_size
        self.info, self.data = bytearray(), bytearray()
        self.info_ok = False


class CurveStore:
    def __init__(self, capacity_bytes: int = 256 * 1024):
        self.capacity_bytes = capacity_bytes
        self.ram: dict[int, Curve] = {}
        self.flash: dict[int, Curve] = {}
        self._writes: dict[int, _Write] = {}
        self._reads: dict[int, list[int]] = {}

    def boot(self) -> None:
        """Firmware start: RAM = flash; transfers in progress are lost."""
        self.ram = dict(self.flash)
        self._writes.clear()
        self._reads.clear()

    def used_bytes(self) -> int:
        return (sum(len(c.info) + len(c.data) for c in self.ram.values())
                + sum(w.info_size + w.data_size for w in self._writes.values()))

    # ---- write (50h..54h) ----
    def add(self, cid: int, info_size: int, data_size: int) -> int:
        if cid in self.ram or cid in self._writes:
            return codes.RC_CURVE_EXISTS
        if (info_size != INFO_BLOCK_SIZE or data_size < 8 or data_size % 4
                or self.used_bytes() + info_size + data_size > self.capacity_bytes):
            return codes.RC_SIZE_ERROR
        self._writes[cid] = _Write(info_size, data_size)
        return codes.RC_OK

    def _open(self, cid: int) -> _Write | int:
        w = self._writes.get(cid)
        if w is None:
            return codes.RC_BLOCK_FINISHED if cid in self.ram else codes.RC_NOT_PRESENT
        return w

    def add_info(self, cid: int, chunk: bytes) -> int:
        w = self._open(cid)
        if isinstance(w, int):
            return w
        if len(w.info) >= w.info_size:
            return codes.RC_BLOCK_FINISHED
        w.info += chunk
        if len(w.info) < w.info_size:
            return codes.RC_NOT_FINISHED
        del w.info[w.info_size:]          # the 18th 4-byte step carries 2 pad bytes
        rc = validate_info(cid, bytes(w.info), w.data_size)
        if rc != codes.RC_OK:
            del self._writes[cid]         # refused: the curve is discarded, 50h may start again
            return rc
        w.info_ok = True
        self._complete(cid, w)
        return codes.RC_OK

    def add_data(self, cid: int, chunk: bytes) -> int:
        w = self._open(cid)
        if isinstance(w, int):
            return w
        if len(w.data) >= w.data_size:
            return codes.RC_BLOCK_FINISHED
        w.data += chunk
        if len(w.data) < w.data_size:
            return codes.RC_NOT_FINISHED
        del w.data[w.data_size:]
        self._complete(cid, w)
        return codes.RC_OK

    def _complete(self, cid: int, w: _Write) -> None:
        if w.info_ok and len(w.data) >= w.data_size:
            self.ram[cid] = Curve(cid, bytes(w.info), bytes(w.data))
            del self._writes[cid]

    def in_progress(self) -> list[int]:
        return sorted(self._writes)

    # ---- read (60h..62h) ----
    def get(self, cid: int) -> tuple[int, int, int]:
        c = self.ram.get(cid)
        if c is None:
            self._reads.pop(cid, None)
            return codes.RC_NOT_PRESENT, 0, 0
        self._reads[cid] = [0, 0]
        return codes.RC_OK, len(c.info), len(c.data)

    def read(self, cid: int, block: str, size: int) -> tuple[int, bytes]:
        """The next `size` bytes of the "info" or "data" block (the last step padded with 00h) and the result
        04h (more follows) or 00h (that was the last step). NotStarted without a 60h; NoMoreData after the end."""
        c = self.ram.get(cid)
        cur = self._reads.get(cid)
        if c is None or cur is None:
            raise NotStarted(f"curve {cid}: no get-curve (60h) before reading")
        which = 0 if block == "info" else 1
        data = c.info if which == 0 else c.data
        pos = cur[which]
        if pos >= len(data):
            raise NoMoreData(f"curve {cid}: {block} block already read")
        cur[which] = pos + size
        rc = codes.RC_OK if pos + size >= len(data) else codes.RC_NOT_FINISHED
        return rc, data[pos:pos + size].ljust(size, b"\0")

    # ---- delete, flash ----
    def delete_all(self) -> None:
        self.ram.clear()
        self._writes.clear()
        self._reads.clear()

    def flash_image_bytes(self) -> int:
        return sum(len(c.info) + len(c.data) for c in self.ram.values())

    def commit_to_flash(self) -> None:
        """The end of a flash save: flash holds exactly the complete curves in RAM."""
        self.flash = dict(self.ram)
