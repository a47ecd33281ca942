"""The binary layouts a PVL file carries as text: 32-bit words, stringlets, the curve info block and
the command-table entry block.

Byte order: every multi-byte field is little-endian, like all LinMot fieldbus data. A PVL block is
listed as 32-bit words where word k holds bytes 4k..4k+3 of the block, least significant byte first:
the seed's first info word 00030046h is the bytes 46 00 03 00, i.e. data offset 0046h then object type
0003h. A block whose size is not a multiple of 4 (the 70-byte info block) ends with zero pad bytes.

Text <-> bytes uses Latin-1 (one byte per character, every byte decodes), see docs/pvl.md.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, field

TEXT_ENCODING = "latin-1"

INFO_BLOCK_SIZE = 70          # bytes; also the data offset field's required value (seeds 5.2)
SETPOINT_SIZE = 4             # bytes per setpoint ("Data Type Size", seeds 5.2)
CURVE_NAME_SIZE = 22          # bytes reserved for the name, 00h-terminated
CURVE_ID_MIN, CURVE_ID_MAX = 1, 100
MIN_SETPOINTS = 2

CT_BLOCK_SIZE = 64            # bytes of a command-table entry data block (seeds 6.1)
CT_VERSION_ID = 0xA701        # "Command entry Version ID fix A701h"
CT_NOT_LINKED = 0xFFFF
CT_NAME_SIZE = 16
CT_PARAMS_SIZE = 32
CT_ENTRY_MIN, CT_ENTRY_MAX = 0, 255

# Object type word: version nibble (3), object-type nibble (0 = curve), X code, Y code (seeds Table 7)
OBJECT_TYPE_POSITION_TIME = 0x0003
OBJECT_TYPE_CAM = 0x0103
UUID_POSITION = 0x0005        # 0.1 um
UUID_TIME = 0x001A            # 0.01 ms
UUID_ENCODER = 0x001B         # 1 increment
# the only object types the firmware supports ("Other object types are not supported yet"),
# with the X/Y unit IDs the seeds call correct for them
SUPPORTED_OBJECT_TYPES = {
    OBJECT_TYPE_POSITION_TIME: (UUID_TIME, UUID_POSITION),
    OBJECT_TYPE_CAM: (UUID_ENCODER, UUID_POSITION),
}
X_DIMENSIONS = {0: "time", 1: "encoder position", 2: "position"}
Y_DIMENSIONS = {0: "position", 1: "velocity", 2: "current", 3: "encoder position", 4: "encoder speed",
                5: "microsteps"}
UUID_UNITS = {UUID_POSITION: "0.1 um", UUID_TIME: "0.01 ms", UUID_ENCODER: "increment"}


# --- 32-bit words ---------------------------------------------------------------------------------

def words_for(size: int) -> int:
    """Number of 32-bit words that list a block of `size` bytes."""
    return (size + 3) // 4


def bytes_to_words(block: bytes) -> tuple[int, ...]:
    padded = block + bytes(-len(block) % 4)
    return struct.unpack(f"<{len(padded) // 4}I", padded)


def words_to_bytes(words: tuple[int, ...] | list[int], size: int) -> tuple[bytes, bytes]:
    """The first `size` bytes of the little-endian words, and the pad bytes after them."""
    raw = struct.pack(f"<{len(words)}I", *words)
    return raw[:size], raw[size:]


def to_signed32(word: int) -> int:
    return word - (1 << 32) if word & 0x80000000 else word


def to_unsigned32(value: int) -> int:
    return value & 0xFFFFFFFF


# --- stringlets (seeds 2.5) -------------------------------------------------------------------------

def stringlet_text(value: int) -> str:
    """The characters of one stringlet: its four bytes, least significant first, up to the first 00h."""
    raw = value.to_bytes(4, "little")
    return raw.split(b"\0", 1)[0].decode(TEXT_ENCODING)


def decode_stringlets(values) -> str:
    """A string from consecutive stringlet values; it ends at the first 00h byte."""
    raw = b"".join(v.to_bytes(4, "little") for v in values)
    return raw.split(b"\0", 1)[0].decode(TEXT_ENCODING)


def encode_stringlets(text: str, count: int | None = None) -> tuple[int, ...]:
    """Stringlet values for `text`, zero-padded to `count` stringlets (default: just enough for the text,
    the terminating 00h included only when it fits in the last stringlet's spare bytes)."""
    raw = text.encode(TEXT_ENCODING)
    if b"\0" in raw:
        raise ValueError("a string parameter cannot contain a 00h character")
    needed = words_for(len(raw))
    if count is None:
        count = needed
    if needed > count:
        raise ValueError(f"{text!r} needs {needed} stringlets, only {count} available")
    raw += bytes(4 * count - len(raw))
    return struct.unpack(f"<{count}I", raw)


def stringlet_upid(string_upid: int, k: int, first_offset: int = 1) -> int:
    """UPID of stringlet k (k = 1, 2, ...) of a string parameter: string UPID + k on the E1100/E1200
    (first_offset 1), string UPID + k - 1 on the B1100 (first_offset 0; seed 000 2.5)."""
    return string_upid + k - 1 + first_offset


# --- names in fixed-size fields ---------------------------------------------------------------------

def encode_name(name: str, size: int) -> bytes:
    raw = name.encode(TEXT_ENCODING)
    if b"\0" in raw:
        raise ValueError(f"name {name!r} contains a 00h character")
    if len(raw) > size:
        raise ValueError(f"name {name!r} is longer than {size} bytes")
    return raw + bytes(size - len(raw))


def decode_name(field_bytes: bytes) -> str:
    return field_bytes.split(b"\0", 1)[0].decode(TEXT_ENCODING)


# --- curve info block (seeds Table 6 and 5.2) --------------------------------------------------------

_INFO = struct.Struct("<HHHH22sHIHHH7I")
assert _INFO.size == INFO_BLOCK_SIZE


@dataclass(frozen=True)
class CurveInfo:
    """The decoded fields of a 70-byte curve info block."""

    curve_id: int
    name: str
    setpoints: int
    x_length: int                               # time curves: 10 us units; cams: encoder increments
    object_type: int = OBJECT_TYPE_POSITION_TIME
    x_dim_uuid: int = UUID_TIME
    y_dim_uuid: int = UUID_POSITION
    data_offset: int = INFO_BLOCK_SIZE
    type_size: int = SETPOINT_SIZE
    wizard_type: int = 0
    wizard_params: tuple[int, ...] = field(default=(0,) * 7)

    def to_bytes(self) -> bytes:
        if len(self.wizard_params) != 7:
            raise ValueError("a curve info block has 7 wizard parameters")
        return _INFO.pack(self.data_offset, self.object_type, self.setpoints, self.type_size,
                          encode_name(self.name, CURVE_NAME_SIZE), self.curve_id, self.x_length,
                          self.x_dim_uuid, self.y_dim_uuid, self.wizard_type, *self.wizard_params)

    @classmethod
    def from_bytes(cls, block: bytes) -> CurveInfo:
        if len(block) != INFO_BLOCK_SIZE:
            raise ValueError(f"a curve info block has {INFO_BLOCK_SIZE} bytes, got {len(block)}")
        (offset, otype, n, tsize, name, cid, xlen, xuuid, yuuid, wtype, *wpar) = _INFO.unpack(block)
        return cls(curve_id=cid, name=decode_name(name), setpoints=n, x_length=xlen, object_type=otype,
                   x_dim_uuid=xuuid, y_dim_uuid=yuuid, data_offset=offset, type_size=tsize,
                   wizard_type=wtype, wizard_params=tuple(wpar))

    @property
    def x_dimension(self) -> str:
        return X_DIMENSIONS.get((self.object_type >> 8) & 0xF, "unknown")

    @property
    def y_dimension(self) -> str:
        return Y_DIMENSIONS.get((self.object_type >> 12) & 0xF, "unknown")

    @property
    def kind(self) -> str:
        """'position vs time', 'position vs encoder position', ..."""
        return f"{self.y_dimension} vs {self.x_dimension}"


def curve_info_problems(block: bytes, data_setpoints: int | None = None) -> list[tuple[int, str]]:
    """What is wrong with an info block, as (byte offset of the field, message) pairs.
    `data_setpoints`: the number of setpoints in the data block, checked against the info block."""
    info = CurveInfo.from_bytes(block)
    out: list[tuple[int, str]] = []
    if info.data_offset != INFO_BLOCK_SIZE:
        out.append((0, f"data offset is {info.data_offset}, must be {INFO_BLOCK_SIZE} (0046h)"))
    if info.object_type not in SUPPORTED_OBJECT_TYPES:
        out.append((2, f"object type {info.object_type:04X}h is not supported "
                       "(0003h position vs time, 0103h position vs encoder position)"))
    if info.setpoints < MIN_SETPOINTS:
        out.append((4, f"{info.setpoints} setpoints, a curve has at least {MIN_SETPOINTS}"))
    if data_setpoints is not None and info.setpoints != data_setpoints:
        out.append((4, f"info block says {info.setpoints} setpoints, the data block holds {data_setpoints}"))
    if info.type_size != SETPOINT_SIZE:
        out.append((6, f"data type size is {info.type_size}, must be {SETPOINT_SIZE}"))
    if 0 not in block[8:8 + CURVE_NAME_SIZE]:
        out.append((8, f"curve name is not terminated with 00h within its {CURVE_NAME_SIZE} bytes"))
    if not CURVE_ID_MIN <= info.curve_id <= CURVE_ID_MAX:
        out.append((30, f"curve ID {info.curve_id} is outside {CURVE_ID_MIN}..{CURVE_ID_MAX}"))
    if info.x_length == 0:
        out.append((32, "x-length is 0"))
    expected = SUPPORTED_OBJECT_TYPES.get(info.object_type)
    if expected and (info.x_dim_uuid, info.y_dim_uuid) != expected:
        out.append((36, f"XDimUUID/YDimUUID {info.x_dim_uuid:04X}h/{info.y_dim_uuid:04X}h do not match object "
                        f"type {info.object_type:04X}h (expected {expected[0]:04X}h/{expected[1]:04X}h)"))
    return out


# --- command-table entry data block (seeds Table 10) -------------------------------------------------

_CT = struct.Struct(f"<HHH{CT_PARAMS_SIZE}s{CT_NAME_SIZE}s10s")
assert _CT.size == CT_BLOCK_SIZE


@dataclass(frozen=True)
class CtEntryBlock:
    """The decoded fields of a 64-byte command-table entry data block."""

    name: str
    motion_header: int                        # master ID << 8 | sub ID << 4 | count (count 0 in a CT)
    parameters: bytes = bytes(CT_PARAMS_SIZE)
    linked_entry: int = CT_NOT_LINKED
    version_id: int = CT_VERSION_ID
    reserved: bytes = bytes(10)

    def to_bytes(self) -> bytes:
        if len(self.parameters) > CT_PARAMS_SIZE:
            raise ValueError(f"motion command parameters take at most {CT_PARAMS_SIZE} bytes")
        return _CT.pack(self.version_id, self.linked_entry, self.motion_header,
                        self.parameters.ljust(CT_PARAMS_SIZE, b"\0"),
                        encode_name(self.name, CT_NAME_SIZE), self.reserved)

    @classmethod
    def from_bytes(cls, block: bytes) -> CtEntryBlock:
        if len(block) != CT_BLOCK_SIZE:
            raise ValueError(f"a command-table entry has {CT_BLOCK_SIZE} bytes, got {len(block)}")
        version, linked, header, params, name, reserved = _CT.unpack(block)
        return cls(name=decode_name(name), motion_header=header, parameters=params, linked_entry=linked,
                   version_id=version, reserved=reserved)


def ct_entry_problems(block: bytes) -> list[tuple[int, str]]:
    """What is wrong with a command-table entry block, as (byte offset, message) pairs."""
    entry = CtEntryBlock.from_bytes(block)
    out: list[tuple[int, str]] = []
    if entry.version_id != CT_VERSION_ID:
        out.append((0, f"entry version ID is {entry.version_id:04X}h, must be {CT_VERSION_ID:04X}h"))
    if entry.linked_entry != CT_NOT_LINKED and not CT_ENTRY_MIN <= entry.linked_entry <= CT_ENTRY_MAX:
        out.append((2, f"linked entry ID {entry.linked_entry:04X}h is neither an entry ID "
                       f"({CT_ENTRY_MIN}..{CT_ENTRY_MAX}) nor FFFFh (not linked)"))
    return out
