"""The channel against the answers a CAN bus can deliver besides the right one: a late answer after the
request timed out (the delay swept across the timeout), duplicated answers (CAN's double reception), and a
second channel on a node another channel of the same mailbox owns (docs/st-library.md section 3.5)."""

from __future__ import annotations

import struct

import pytest

from linmot_st.protocol.errors import BY_NAME
from stbench import Bench

E = {name: e.value for name, e in BY_NAME.items()}
MS = 1_000_000
LIVE = 0x1005                  # Max Current Limit: live, 100..2500 (data/e1100_parameters.csv)
GOOD, REFUSED = 1500, 3000     # the drive refuses 3000 with abort 06090030h


def answers_of(node: int, sub: int | None = None):
    def pred(f) -> bool:
        return f.can_id == 0x580 + node and (sub is None or (len(f.data) == 8 and f.data[3] == sub))
    return pred


def each_answer_twice(node: int):
    """A `duplicate` predicate: every answer of the node is received twice (the copy itself is not
    duplicated again: the bus asks the predicate at the end of each transmission)."""
    state = {"copy": False}

    def pred(f) -> bool:
        if f.can_id != 0x580 + node:
            return False
        state["copy"] = not state["copy"]
        return state["copy"]
    return pred


def first_write_then_refused_retry(delay_ns: int, echo: bool) -> dict:
    """Write 1005h := 1500 (RAM+ROM) with the drive's answer delayed by delay_ns (the drive keeps its
    order: the answers that follow wait behind it); when the write fails, retry at once with 3000, which
    the drive refuses. Returns both outcomes and the drive's values."""
    b = Bench(nodes=1, echo=echo)
    b.bus.delay(answers_of(1, 0x06), delay_ns, count=1, fifo=True)
    wr = b.fb("WR")
    first = wr.run(UPID=LIVE, VALUE=GOOD, MEM="LM_RAM_ROM", max_scans=5000)
    out = dict(first=first, retry=None)
    if first.error:
        out["retry"] = wr.run(UPID=LIVE, VALUE=REFUSED, MEM="LM_RAM_ROM", max_scans=5000)
        b.step(3000)                   # let every late frame arrive
    out["ram"], out["rom"] = b.drive.ram(LIVE), b.drive.rom(LIVE)
    out["bench"] = b
    return out


# the delay of the first answer around the 1 s SdoTimeout, fine steps where the timeout and the retry fall
DELAYS_MS = [500, 998, 999, 999.5, 999.8, 1000, 1000.2, 1000.5, 1001, 1001.5, 1002, 1002.5, 1003, 1004, 1006,
             1010, 1100, 1999, 2001, 3500]


@pytest.mark.parametrize("echo", [True, False], ids=["tx-echo", "no-echo"])
def test_a_late_answer_never_confirms_the_retry(echo):
    """The write times out or not depending on the delay; in no case does the late answer of the first
    write complete the retry (which the drive refuses): a Done always means the drive holds the value."""
    seen = set()
    for d in DELAYS_MS:
        o = first_write_then_refused_retry(int(d * MS), echo)
        first, retry = o["first"], o["retry"]
        if first.done:
            assert (o["ram"], o["rom"]) == (GOOD, GOOD), d
            seen.add("done")
            continue
        assert first.error_id == E["SdoTimeout"], d
        assert retry.error and not retry.done, d
        if d < 2000:
            # the drive answered the sync request in time: the retry went out and got the drive's refusal
            assert (retry.error_id, retry["ABORTCODE"]) == (E["SdoAbort"], 0x06090030), d
        else:
            # the drive stayed out of step for a whole SdoTimeout after the retry was queued
            assert retry.error_id in (E["SdoAbort"], E["SdoTimeout"]), d
        # the first write did reach the drive (only its answer was late); the refused value never did
        assert (o["ram"], o["rom"]) == (GOOD, GOOD), d
        b = o["bench"]
        assert b["AX1.RESYNCS"] >= 1 and not b["AX1.RESYNC"], d
        seen.add("timeout")
    assert seen == {"done", "timeout"}          # the sweep crossed the timeout


def test_after_a_timeout_the_channel_aborts_and_resyncs_before_the_next_request():
    """The frames after a timeout, in bus order: the CiA 301 abort of the abandoned request, the sync
    request (upload 1000h:00); the late answer and the sync answer; only then the next service request."""
    o = first_write_then_refused_retry(1500 * MS, echo=True)
    b = o["bench"]
    frames = [e.frame for e in b.sdo_trace()]
    i = next(k for k, f in enumerate(frames) if f.data[0] == 0x80 and f.can_id == 0x601)
    tail = [(f.can_id, f.data[0], f.data[1:4]) for f in frames[i:i + 5]]
    assert tail[0] == (0x601, 0x80, bytes([0x05, 0x30, 0x06]))                  # abort 2000h+1005h sub 06h
    assert frames[i].data[4:8] == (0x05040000).to_bytes(4, "little")
    assert tail[1] == (0x601, 0x40, bytes([0x00, 0x10, 0x00]))                  # sync: upload 1000h:00
    assert tail[2] == (0x581, 0x60, bytes([0x05, 0x30, 0x06]))                  # the late answer, a stray
    assert tail[3][:2] == (0x581, 0x43) and tail[3][2] == bytes([0x00, 0x10, 0x00])
    assert tail[4] == (0x601, 0x23, bytes([0x05, 0x30, 0x06]))                  # the retry, after the sync
    assert b["AX1.STRAYS"] >= 1


def test_a_drive_that_answers_nothing_after_a_timeout_fails_the_next_request_in_bounded_time():
    """No answer to the sync request either (the drive went silent): the next request waits for the
    re-synchronisation, and fails with SdoTimeout one SdoTimeout after it was queued, not never."""
    b = Bench(nodes=1)
    b.bus.drop(answers_of(1))
    first = b.fb("WR").run(UPID=LIVE, VALUE=GOOD, MEM="LM_RAM_ROM", max_scans=5000)
    assert first.error_id == E["SdoTimeout"] and first.scans == 1001
    second = b.fb("RD").run(UPID=LIVE, max_scans=5000)
    assert second.error_id == E["SdoTimeout"] and second.scans == 1001
    assert b["AX1.RESYNC"]                                      # still out of step: the drive never answered


def curve_info(curve_id: int, n: int) -> list[int]:
    return list(struct.pack("<HHHH22sHIHHH28s", 70, 3, n, 4, b"dup", curve_id, 100 * n, 0x1A, 5, 0, b""))


@pytest.mark.parametrize("drives", [1, 2], ids=["one-drive", "two-drives-500k"])
def test_duplicated_answers_are_never_taken_as_the_next_answer(drives):
    """Every answer of every drive is received twice (double reception). With two drives at 500 kbit/s
    the second copy of node 2's answer lands in the next scan, among the answer to the next request of
    the same object (block steps share node, index and sub-index). Curve add and read back byte for byte,
    no Sequence or protocol error, one request per answer."""
    n = 40
    b = Bench(nodes=drives)
    for k in range(1, drives + 1):
        b.bus.duplicate(each_answer_twice(k))
    b.set_setpoints([7 * i - 100 for i in range(n)])
    names = ["CA", "CA2"][:drives]
    for k, name in enumerate(names, start=1):
        b.fb(name).start(CURVEID=k, INFO=curve_info(k, n), DATASIZE=4 * n)
    for _ in range(400):
        b.step(1)
        if all(b.fb(x)["DONE"] or b.fb(x)["ERROR"] for x in names):
            break
    for k, name in enumerate(names, start=1):
        assert b.fb(name)["DONE"], (name, b.fb(name)["ERRORID"])
        assert b.drives[k].curves.ram[k].setpoints == [7 * i - 100 for i in range(n)]
        assert b[f"AX{k}.STRAYS"] >= 1 + 18 + n                  # every copy was counted as a stray
    if drives == 2:
        late = [e for e in b.bus.trace if e.frame.can_id == 0x582 and e.end_ns % MS > 0]
        assert any(e.end_ns % MS < 300_000 for e in late)         # some copies did land in the next scan
    r = b.fb("CG").run(CURVEID=1)
    assert r.done and b["SPGET"][:n] == [7 * i - 100 for i in range(n)]


def test_a_second_channel_on_an_owned_node_is_refused_before_anything_is_sent():
    b = Bench(nodes=1, enable=False)
    b["CH1.NODEID"], b["CH2.NODEID"] = 1, 1
    b["CH1.ENABLE"] = True
    b.sim.run_until(lambda: b["AX1.BOOTCOUNT"] >= 1, max_scans=5000)
    b.step(2)
    t0 = b.plc.time_ns
    b["CH2.ENABLE"] = True
    b.step(1)
    assert not b["CH2.READY"] and b["CH2.ERROR"] and b["CH2.ERRORID"] == E["NodeIdInUse"]
    r = b.fb("CA2").run(CURVEID=1, INFO=curve_info(1, 10), DATASIZE=40)
    assert r.error and r.error_id == E["NodeIdInUse"] and r.scans == 1
    assert [e for e in b.bus.trace if e.start_ns >= t0 and e.sender == "plc"] == []   # not even an NMT Start
    assert b.fb("RD").run(UPID=LIVE).done                       # the owner works on
    # the owner disabled: the node is free, the second channel takes it (its NMT Start is its first frame)
    b["CH1.ENABLE"] = False
    b.step(2)
    assert b["CH2.READY"] and not b["CH2.ERROR"]
    assert b.fb("CA2").run(CURVEID=1, INFO=curve_info(1, 10), DATASIZE=40).done
    # channel 1 enabled again is refused in its turn
    b["CH1.ENABLE"] = True
    b.step(1)
    assert b["CH1.ERRORID"] == E["NodeIdInUse"] and b.fb("RD").run(UPID=LIVE).error_id == E["NodeIdInUse"]


def test_a_node_whose_owner_is_no_longer_called_is_taken_over():
    """The owner's channel is no longer called (its instance dropped from the program): after HolderScans
    unanswered probes the other channel takes the node; the old owner, called again, is refused."""
    b = Bench(nodes=1, enable=False)
    b["CH1.NODEID"], b["CH2.NODEID"] = 1, 1
    b["CH1.ENABLE"] = True
    b.sim.run_until(lambda: b["AX1.BOOTCOUNT"] >= 1, max_scans=5000)
    b["CH2.ENABLE"] = True
    b.step(2)
    assert b["CH2.ERRORID"] == E["NodeIdInUse"]
    b["CALLCH1"] = False
    b.step(5)
    assert b["CH2.READY"] and b.fb("CA2").run(CURVEID=1, INFO=curve_info(1, 10), DATASIZE=40).done
    b["CALLCH1"] = True
    b.step(2)
    assert b["CH1.ERRORID"] == E["NodeIdInUse"] and not b["AX1.READY"]
