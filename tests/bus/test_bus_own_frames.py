"""OwnFrames: a PLC's own frames, returned by a bus with receive_own_messages, told from other nodes' frames
that python-can also marks is_rx False (SocketCAN: every frame sent from this host, e.g. a drive served by
another process on the same vcan0)."""

import can

from linmot_st.bus.pycan import OwnFrames


def msg(can_id: int, data: bytes, is_rx: bool) -> can.Message:
    return can.Message(arbitration_id=can_id, data=data, is_extended_id=False, is_rx=is_rx)


def test_a_local_drive_answer_is_not_taken_for_an_echo():
    own = OwnFrames()
    req = msg(0x601, bytes.fromhex("4000100000000000"), True)
    own.sent(req)
    assert own.is_own(msg(0x601, bytes(req.data), False))               # the request coming back
    assert not own.is_own(msg(0x581, bytes.fromhex("4300100000000000"), False))   # local, not ours
    assert not own.is_own(msg(0x581, bytes.fromhex("4300100000000000"), True))    # from the wire


def test_echoes_match_in_send_order_and_only_once():
    own = OwnFrames()
    a, b = msg(0x601, b"\x40\x00\x10\x00", True), msg(0x601, b"\x40\x00\x10\x01", True)
    own.sent(a)
    own.sent(a)
    own.sent(b)
    assert own.is_own(msg(0x601, bytes(a.data), False))
    assert own.is_own(msg(0x601, bytes(b.data), False))                # the second `a` never came back
    assert not own.is_own(msg(0x601, bytes(a.data), False))            # so a later copy is another node's


def test_what_it_remembers_is_bounded():
    own = OwnFrames()
    for k in range(OwnFrames.LIMIT + 10):
        own.sent(msg(0x601, k.to_bytes(4, "little"), True))
    assert not own.is_own(msg(0x601, (0).to_bytes(4, "little"), False))  # forgotten
    assert own.is_own(msg(0x601, (OwnFrames.LIMIT + 9).to_bytes(4, "little"), False))
