"""Exact bit length of classic CAN 2.0A frames (11-bit identifier), stuff bits included.

A frame on the wire, in order (CAN 2.0 part A; ISO 11898-1 classic base format):
  SOF 1 | identifier 11 | RTR 1 | IDE 1 | r0 1 | DLC 4 | data 8*n | CRC 15   <- bit stuffing applies
  CRC delimiter 1 | ACK slot 1 | ACK delimiter 1 | EOF 7                     <- fixed form, no stuffing
  then the interframe space (intermission) of 3 recessive bits before the next frame may start.
Dominant = 0, recessive = 1; every field is sent most significant bit first. The CRC-15 (polynomial
0x4599, initial value 0) covers SOF up to the last data bit. The transmitter inserts a complementary
stuff bit after five equal bits, counting stuff bits themselves, from SOF to the last CRC bit (a stuff
bit may follow the last CRC bit). A remote frame (RTR = 1) carries its DLC but no data field.

``frame_bits``/``stuff`` are the plain reference (one bit at a time); ``frame_length_bits`` computes
the same result from byte tables and a per-header cache, because the simulated bus needs it per frame.
"""

from __future__ import annotations

from .frame import Frame

CRC15_POLY = 0x4599
FIXED_TAIL_BITS = 3 + 7     # CRC delimiter, ACK slot, ACK delimiter, EOF: never stuffed
IFS_BITS = 3                # interframe space (intermission)
ERROR_FRAME_BITS = 6 + 8    # error flag 6 (flags of all receivers overlap) + error delimiter 8


# -- reference: one bit at a time --------------------------------------------------------------
def _bits(value: int, width: int) -> list[int]:
    return [(value >> i) & 1 for i in range(width - 1, -1, -1)]


def crc15(bits: list[int]) -> int:
    """CRC-15/CAN of a bit sequence (MSB first)."""
    crc = 0
    for bit in bits:
        feedback = bit ^ ((crc >> 14) & 1)
        crc = (crc << 1) & 0x7FFF
        if feedback:
            crc ^= CRC15_POLY
    return crc


def frame_bits(frame: Frame) -> list[int]:
    """The unstuffed bits of a frame from SOF to the last CRC bit (34 + 8 * data bytes)."""
    bits = [0] + _bits(frame.can_id, 11) + [1 if frame.rtr else 0, 0, 0] + _bits(frame.dlc, 4)
    if not frame.rtr:
        for byte in frame.data:
            bits += _bits(byte, 8)
    return bits + _bits(crc15(bits), 15)


def stuff(bits: list[int]) -> list[int]:
    """The bits as transmitted: a complementary bit after every run of five equal bits."""
    out: list[int] = []
    last, run = -1, 0
    for bit in bits:
        out.append(bit)
        run = run + 1 if bit == last else 1
        last = bit
        if run == 5:
            last, run = 1 - bit, 1
            out.append(last)
    return out


# -- fast path: byte tables -------------------------------------------------------------------
# Stuffing state after a bit: (last bit, run length 1..4), encoded last * 5 + run; state 0 = before SOF.
def _advance(state: int, value: int, width: int) -> tuple[int, int]:
    last, run = divmod(state, 5)
    if state == 0:
        last = -1
    stuffed = 0
    for bit in _bits(value, width):
        run = run + 1 if bit == last else 1
        last = bit
        if run == 5:
            stuffed += 1
            last, run = 1 - bit, 1
    return stuffed, last * 5 + run


def _stuff_table(width: int) -> list[list[tuple[int, int]]]:
    return [[_advance(s, v, width) for v in range(1 << width)] for s in range(10)]


_STUFF8 = _stuff_table(8)
_STUFF7 = _stuff_table(7)


def _crc_table() -> list[int]:
    table = []
    for byte in range(256):
        crc = byte << 7
        for _ in range(8):
            crc = ((crc << 1) ^ CRC15_POLY) & 0x7FFF if crc & 0x4000 else (crc << 1) & 0x7FFF
        table.append(crc)
    return table


_CRC8 = _crc_table()

# The stuffing state and the stuff bits counted so far as one object, a row: row[byte] is the row after that
# data byte, row[256] = (stuff bits so far, state). A data byte then costs one subscript (the bus computes
# the length of every frame whose payload it has not seen, e.g. each TxPDO2 of a moving axis).
_MAX_STUFFED = (19 + 64 - 1) // 4       # stuff bits up to the last data bit: at most one per 4 after the first


def _count_rows() -> list[list[list]]:
    rows = [[[None] * 256 + [(c, s)] for s in range(10)] for c in range(_MAX_STUFFED + 1)]
    for c, by_state in enumerate(rows):
        for s, row in enumerate(by_state):
            for byte, (n, after) in enumerate(_STUFF8[s]):
                if c + n <= _MAX_STUFFED:       # beyond: no frame gets there
                    row[byte] = rows[c + n][after]
    return rows


_ROWS = _count_rows()
_HEADERS: dict[int, tuple[int, int, int]] = {}   # header key -> (crc, stuff state, stuff bits so far)


def _header(can_id: int, rtr: bool, dlc: int) -> tuple[int, int, int]:
    bits = [0] + _bits(can_id, 11) + [1 if rtr else 0, 0, 0] + _bits(dlc, 4)
    stuffed, state = 0, 0
    for bit in bits:
        n, state = _advance(state, bit, 1)
        stuffed += n
    return crc15(bits), state, stuffed


def stuff_bit_count(frame: Frame) -> int:
    """Number of stuff bits the transmitter inserts into this frame."""
    can_id, rtr, data = frame.can_id, frame.rtr, frame.data
    dlc = frame.rtr_dlc if rtr else len(data)       # frame.dlc without the property's call
    key = (can_id << 5) | (rtr << 4) | dlc
    header = _HEADERS.get(key)
    if header is None:
        header = _HEADERS[key] = _header(can_id, rtr, dlc)
    crc, state, stuffed = header
    if not rtr:
        crc8 = _CRC8
        row = _ROWS[stuffed][state]
        for byte in data:
            crc = ((crc << 8) & 0x7FFF) ^ crc8[(crc >> 7) ^ byte]     # (crc >> 7) ^ byte < 256: crc is 15-bit
            row = row[byte]
        stuffed, state = row[256]
    n, state = _STUFF7[state][crc >> 8]
    stuffed += n
    n, state = _STUFF8[state][crc & 0xFF]
    return stuffed + n


def frame_length_bits(frame: Frame) -> int:
    """Bits from SOF to the end of EOF, stuff bits included; the interframe space is not included."""
    data_bits = 0 if frame.rtr else 8 * len(frame.data)
    return 34 + data_bits + stuff_bit_count(frame) + FIXED_TAIL_BITS


def bus_bits(frame: Frame) -> int:
    """Bus time of a frame in bits: ``frame_length_bits`` plus the 3-bit interframe space.

    This is the figure CAN bus-load tools and can-bus-limits.md use: 111 bits for 8 data bytes without
    stuffing, at most 135 (Linux CAN_FRAME_LEN_MAX) with the worst-case floor((34 + 8n - 1) / 4) stuff bits.
    """
    return frame_length_bits(frame) + IFS_BITS


def unstuffed_bus_bits(dlc: int, rtr: bool = False) -> int:
    """Bus time in bits of a frame with no stuff bits: the lower bound 47 + 8 * dlc (111 for 8 bytes)."""
    return 34 + (0 if rtr else 8 * dlc) + FIXED_TAIL_BITS + IFS_BITS


def max_bus_bits(dlc: int, rtr: bool = False) -> int:
    """Upper bound of ``bus_bits`` for a frame with this DLC (135 for 8 bytes)."""
    stuffed_span = 34 + (0 if rtr else 8 * dlc)
    return unstuffed_bus_bits(dlc, rtr) + (stuffed_span - 1) // 4
