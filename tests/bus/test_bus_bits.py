"""Frame bit length with exact stuff bits (linmot_st.bus.bits)."""

import random

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from linmot_st.bus import Frame
from linmot_st.bus.bits import (
    bus_bits,
    crc15,
    frame_bits,
    frame_length_bits,
    max_bus_bits,
    stuff,
    stuff_bit_count,
    unstuffed_bus_bits,
)


def bits_of(data: bytes) -> list[int]:
    return [(b >> i) & 1 for b in data for i in range(7, -1, -1)]


def destuff(bits: list[int]) -> list[int]:
    out, last, run, skip = [], -1, 0, False
    for bit in bits:
        if skip:
            assert bit != last, "a stuff bit must be the complement of the run it ends"
            last, run, skip = bit, 1, False
            continue
        out.append(bit)
        run = run + 1 if bit == last else 1
        last = bit
        skip = run == 5
    return out


frames = st.one_of(
    st.builds(Frame, st.integers(0, 0x7FF), st.binary(max_size=8)),
    st.builds(lambda i, n: Frame(i, rtr=True, rtr_dlc=n), st.integers(0, 0x7FF), st.integers(0, 8)),
)


def test_crc15_check_value():
    # CRC-15/CAN catalogue check value: the CRC of ASCII "123456789" is 0x059E
    assert crc15(bits_of(b"123456789")) == 0x059E


def test_all_dominant_frame_counted_by_hand():
    # ID 0, data frame, DLC 0: SOF..DLC are 19 zeros and the CRC of zeros is 0, so SOF..CRC is
    # 34 zeros. A stuff bit (1) follows every 5 zeros: 6 stuff bits (34 = 6 * 5 + 4).
    f = Frame(0x000, b"")
    assert frame_bits(f) == [0] * 34
    assert stuff_bit_count(f) == 6
    assert frame_length_bits(f) == 34 + 6 + 3 + 7
    assert bus_bits(f) == 53


def test_stuffing_of_a_long_run_counts_the_stuff_bit_itself():
    # 0 0 0 0 0 [1] 1 1 1 1 [0]: the stuff bit starts the next run
    assert stuff([0] * 5 + [1] * 4) == [0] * 5 + [1] + [1] * 4 + [0]


def test_limits_of_can_bus_limits_doc():
    # can-bus-limits.md counts the interframe space: 111 bits unstuffed, 135 worst case for 8 bytes
    assert unstuffed_bus_bits(8) == 111
    assert max_bus_bits(8) == 135
    assert unstuffed_bus_bits(0) == 47


@settings(max_examples=2000, deadline=None)
@given(frames)
def test_fast_count_equals_reference_and_stream_is_valid(f):
    raw = frame_bits(f)
    assert len(raw) == 34 + (0 if f.rtr else 8 * f.dlc)
    wire = stuff(raw)
    assert destuff(wire) == raw
    assert "000000" not in "".join(map(str, wire)) and "111111" not in "".join(map(str, wire))
    assert stuff_bit_count(f) == len(wire) - len(raw)
    assert unstuffed_bus_bits(f.dlc, f.rtr) <= bus_bits(f) <= max_bus_bits(f.dlc, f.rtr)
    assert bus_bits(f) == len(wire) + 3 + 7 + 3


# ISO 16845 8.1.6 "stuff bits in a base format frame": frames chosen to put stuff bits everywhere
ISO16845_FRAMES = [
    Frame(0x078, bytes([0x01] + [0xE1] * 7)),
    Frame(0x41F, b"\x00"),
    Frame(0x47F, b"\x1F"),
    Frame(0x758, b""),
    Frame(0x777, b"\x1F"),
    Frame(0x7EF, rtr=True, rtr_dlc=2),
]


@pytest.mark.parametrize("f", ISO16845_FRAMES, ids=str)
def test_iso16845_stuffing_frames(f):
    assert stuff_bit_count(f) == len(stuff(frame_bits(f))) - len(frame_bits(f))
    assert stuff_bit_count(f) > 0


def test_remote_frame_has_dlc_but_no_data_field():
    f = Frame(0x701, rtr=True, rtr_dlc=1)
    bits = frame_bits(f)
    assert bits[12] == 1 and bits[15:19] == [0, 0, 0, 1]
    assert len(bits) == 34


def test_sdo_frames_stay_within_the_bounds():
    rng = random.Random(7)
    lengths = {bus_bits(Frame(0x601, bytes(rng.randrange(256) for _ in range(8)))) for _ in range(500)}
    assert min(lengths) >= 111 and max(lengths) <= 135
    assert len(lengths) > 5   # stuffing really depends on the content


def test_remote_frame_keeps_its_dlc_through_python_can_and_in_its_bit_length():
    import can

    from linmot_st.bus import Frame
    from linmot_st.bus.bits import frame_length_bits

    msg = can.Message(arbitration_id=0x701, is_extended_id=False, is_remote_frame=True, dlc=1)
    frame = Frame.from_message(msg)
    assert (frame.rtr, frame.dlc, frame.data) == (True, 1, b"")
    assert frame.to_message().dlc == 1
    # the DLC field's bits are stuffed like any others: DLC 1 and DLC 0 frames may differ only by stuffing
    assert frame_length_bits(frame) >= 34 + 10 and frame_length_bits(Frame(0x701, rtr=True)) >= 44
