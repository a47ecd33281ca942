"""Whatever arrives, the drive answers with a well-formed frame or stays silent; it never raises."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from linmot_st.bus import Frame
from linmot_st.emulator import OPERATIONAL, PRE_OPERATIONAL, E1100Drive
from linmot_st.emulator.testing import DirectLink

_LINK = DirectLink(E1100Drive(1))

# requests biased toward the interesting part of the object dictionary
_index = st.one_of(st.integers(0x2000, 0x20FF), st.integers(0x3000, 0x3EFF), st.sampled_from([0x1000, 0x1008,
                   0x1017, 0x1018, 0x1400, 0x1800, 0x2000]), st.integers(0, 0xFFFF))
_request = st.builds(lambda cs, idx, sub, tail, n: (bytes([cs, idx & 0xFF, idx >> 8, sub]) + tail)[:n],
                     st.integers(0, 255), _index, st.integers(0, 255), st.binary(min_size=4, max_size=4),
                     st.sampled_from([8, 8, 8, 0, 1, 3, 4, 7]))


@settings(max_examples=800, deadline=None)
@given(_request)
def test_any_sdo_request_gets_one_8_byte_answer_or_none(data):
    link = _LINK
    node = link.node
    if node.sdo_busy or not node.booted:                   # a deferred service or a reset is running: let it end
        link.advance(6_000_000_000)
    # a drive that must answer: booted, Pre-Operational or Operational, its SDO server not busy
    must_answer = node.nmt_state in (PRE_OPERATIONAL, OPERATIONAL) and not node.sdo_busy
    before = len(link.received)
    link.send(Frame(0x601, data))
    link.advance(5_000_000)
    answers = [f for _, f in link.received[before:] if f.can_id == 0x581]
    assert len(answers) <= 1
    for f in answers:
        assert f.dlc == 8
        assert f.data[0] in (0x60, 0x80, 0x41, 0x43, 0x47, 0x4B, 0x4F, 0x20, 0x30) or f.data[0] & 0xE0 == 0x00
    client_abort = len(data) >= 1 and data[0] >> 5 == 4    # never answered (CiA 301)
    malformed = len(data) < 8 or data[0] >> 5 in (5, 6, 7)  # short, block transfer or unknown specifier
    if malformed and not client_abort and must_answer:
        assert len(answers) == 1 and answers[0].data[0] == 0x80, (data.hex(" "), answers)


@settings(max_examples=200, deadline=None)
@given(st.integers(0, 0x7FF), st.binary(max_size=8), st.booleans())
def test_any_frame_on_any_identifier_is_harmless(can_id, data, rtr):
    d = E1100Drive(3)
    link = DirectLink(d)
    link.nmt(0x01)
    link.send(Frame(can_id, b"", True, len(data)) if rtr else Frame(can_id, data))
    link.advance(10_000_000)
    for _, f in link.received:
        assert f.dlc <= 8
