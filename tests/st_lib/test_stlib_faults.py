"""Error paths that need a misbehaving bus or drive: malformed or unexpected answers (injected with the
simulated bus's fault hooks), a full mailbox, an axis without a channel, a full drive, a flash save that
fails after the MC software was stopped, a UPID list longer than the PLC holds."""

from __future__ import annotations

import json

import pytest

from linmot_st.bus import Frame
from linmot_st.protocol.errors import BY_NAME
from stbench import MAILBOX, VECTORS, Bench

E = {name: e.value for name, e in BY_NAME.items()}
MS = 1_000_000
SEED = json.loads((VECTORS / "curve_info.json").read_text())["curves"][0]
SEED_INFO = list(bytes.fromhex(SEED["info_block"]))


def answer_to(sub: int, node: int = 1):
    return lambda f: f.can_id == 0x580 + node and len(f.data) == 8 and f.data[3] == sub


def patched(**at):
    """A payload mutation: byte index -> new value."""
    def mutate(f: Frame) -> Frame:
        d = bytearray(f.data)
        for k, v in at.items():
            d[int(k[1:])] = v
        return Frame(f.can_id, bytes(d))
    return mutate


def add_seed(b: Bench):
    b.set_setpoints(SEED["setpoints"])
    return b.fb("CA").run(CURVEID=23, INFO=SEED_INFO, DATASIZE=40)


def test_axis_without_a_channel_is_not_ready():
    b = Bench(nodes=1)
    r = b.fb("RDNONE").run(UPID=0x1005)
    assert r.error and r.error_id == E["NotReady"] and r.scans == 1


def test_full_mailbox_defers_the_request_to_the_next_scan():
    # 32 axes on one mailbox fill Tx in one scan: the request waits in the axis, nothing is lost or failed
    b = Bench(nodes=1)
    for i in range(1, 33):
        b.plc[f"{MAILBOX}.TX[{i}].ID"] = 0x7FF
        b.plc[f"{MAILBOX}.TX[{i}].DLC"] = 0
    b.fb("RD").start(UPID=0x1005)
    b.plc[f"{MAILBOX}.TXCOUNT"] = 32            # another user of the mailbox filled it in this scan
    lost = b.plc[f"{MAILBOX}.TXLOST"]
    sent = b.sim.frames_sent
    b.step(1)
    assert not b.fb("RD")["ERROR"] and b.fb("RD")["BUSY"]
    assert b.sim.frames_sent - sent == 32       # the other user's frames only
    assert b.plc[f"{MAILBOX}.TXLOST"] == lost
    b.step(1)
    assert b.sim.frames_sent - sent == 33         # the request: sent by the channel in the next scan
    r = b.fb("RD").run(UPID=0x1005)               # its answer (behind the other user's 32 frames on the bus)
    assert r.done and b.plc[f"{MAILBOX}.TXLOST"] == lost


def test_mailbox_that_stays_full_ends_in_the_timeout():
    b = Bench(nodes=1)
    b.fb("RD").start(UPID=0x1005)
    errors = set()
    for _ in range(1200):                         # SdoTimeout 1 s at 1 ms scans
        b.plc[f"{MAILBOX}.TXCOUNT"] = 32
        b.step(1)
        if b.fb("RD")["ERROR"]:
            errors.add(b.fb("RD")["ERRORID"])
            break
    assert errors == {E["SdoTimeout"]}


def test_segmented_answer_is_a_protocol_error():
    b = Bench(nodes=1)
    b.bus.mutate_payload(answer_to(0x01), patched(d0=0x41), count=1)
    r = b.fb("RD").run(UPID=0x1005)
    assert r.error and r.error_id == E["SdoProtocol"]


def test_download_answered_as_upload_is_a_protocol_error():
    b = Bench(nodes=1)
    b.bus.mutate_payload(answer_to(0x06), patched(d0=0x43), count=1)
    r = b.fb("WR").run(UPID=0x1005, VALUE=1000, MEM="LM_RAM_ROM")
    assert r.error and r.error_id == E["SdoProtocol"]


def test_answer_for_another_object_is_ignored_until_the_timeout():
    b = Bench(nodes=1)
    b["CH1.SDOTIMEOUT"] = 30 * MS
    b.bus.mutate_payload(answer_to(0x01), patched(d3=0x02), count=1)
    r = b.fb("RD").run(UPID=0x1005)
    assert r.error and r.error_id == E["SdoTimeout"]
    assert b["AX1.STRAYS"] == 1


def test_duplicated_answer_is_a_stray_not_a_reply():
    b = Bench(nodes=1)
    b.bus.duplicate(answer_to(0x01), count=1)
    assert b.fb("RD").run(UPID=0x1005)["VALUE"] == 2000
    assert b.fb("RD2").run(UPID=0x1018)["VALUE"] == 400
    assert b["AX1.STRAYS"] == 1


def test_drive_finishing_a_block_early_is_a_sequence_error():
    b = Bench(nodes=1)
    b.bus.mutate_payload(answer_to(0x54), patched(d6=0x00), count=1)   # first info step answers "finished"
    r = add_seed(b)
    assert r.error and r.error_id == E["Sequence"] and r["EXCHANGES"] == 2


def test_drive_not_finished_at_the_end_is_a_sequence_error():
    b = Bench(nodes=1)
    b.bus.mutate_payload(lambda f: answer_to(0x84)(f) and f.data[6] == 0x00, patched(d6=0x04), count=1)
    r = b.fb("CTWRF").run(ENTRY=1, HEADER=0x0103, NAME="x")
    assert r.error and r.error_id == E["Sequence"] and r["EXCHANGES"] == 33


def test_other_result_code_in_a_block_step():
    b = Bench(nodes=1)
    b.bus.mutate_payload(answer_to(0x53), patched(d6=0xD0), count=1)
    r = add_seed(b)
    assert r.error and r.error_id == E["ResultBlockFinished"]


def test_full_drive_refuses_a_curve_with_size_error():
    b = Bench(nodes=1, drive_kwargs=dict(curve_capacity_bytes=100))
    r = add_seed(b)                                  # 70 + 40 bytes do not fit
    assert r.error and r.error_id == E["ResultBlockSize"] and r["EXCHANGES"] == 1


def test_curve_upload_size_checks():
    b = Bench(nodes=1)
    assert add_seed(b).done
    b.bus.mutate_payload(answer_to(0x60), patched(d5=72), count=1)
    assert b.fb("CG").run(CURVEID=23).error_id == E["UploadBlockSize"]
    b.bus.mutate_payload(answer_to(0x60), patched(d6=0xA4, d7=0x0F), count=1)     # 4004 bytes
    assert b.fb("CG").run(CURVEID=23).error_id == E["UploadTooBig"]
    b.bus.mutate_payload(answer_to(0x60), patched(d6=36), count=1)                # 9 setpoints, info says 10
    r = b.fb("CG").run(CURVEID=23)
    assert r.error_id == E["UploadInconsistent"] and r["EXCHANGES"] == 1 + 18 + 9
    assert b.fb("CG").run(CURVEID=23).done


def test_ct_read_block_size_and_result_checks():
    b = Bench(nodes=1)
    assert b.fb("CTWRF").run(ENTRY=2, HEADER=0x0103, NAME="x").done
    b.bus.mutate_payload(answer_to(0x85), patched(d6=32), count=1)
    assert b.fb("CTRD").run(ENTRY=2).error_id == E["UploadBlockSize"]
    b.bus.mutate_payload(answer_to(0x86), patched(d4=0xC2), count=1)
    assert b.fb("CTRD").run(ENTRY=2).error_id == E["ResultRangeError"]
    assert b.fb("CTRD").run(ENTRY=2).done


def sent_subs(b: Bench, t0: int) -> list[int]:
    """Sub-indices of the services' requests (not the channel's abort and sync request after a timeout)."""
    return [e.frame.data[3] for e in b.sdo_trace(since_ns=t0) if e.frame.can_id == 0x601
            and e.frame.data[0] != 0x80 and e.frame.data[1:3] != b"\x00\x10"]


def test_flash_timeout_starts_mc_again():
    b = Bench(nodes=1)
    assert add_seed(b).done
    t0 = b.plc.time_ns
    r = b.fb("FS").run(CURVES=True, POLLINTERVAL=0, FLASHTIMEOUT=2 * MS)
    assert r.error and r.error_id == E["FlashTimeout"]
    subs = sent_subs(b, t0)
    assert subs[:2] == [0x35, 0x40] and subs[-1] == 0x36          # MC start attempted before reporting
    # (the drive refuses it while its flash is still busy: the reported error stays FlashTimeout)


def test_flash_save_abort_after_stop_starts_mc_again_and_keeps_the_abort_code():
    b = Bench(nodes=1)
    b.bus.mutate_payload(answer_to(0x40), lambda f: Frame(f.can_id, bytes([0x80]) + f.data[1:4]
                                                            + (0x08000022).to_bytes(4, "little")), count=1)
    t0 = b.plc.time_ns
    r = b.fb("FS").run(CURVES=True)
    assert r.error and r.error_id == E["SdoAbort"] and r["ABORTCODE"] == 0x08000022
    assert sent_subs(b, t0) == [0x35, 0x40, 0x36]                 # MC start attempted before reporting


@pytest.mark.parametrize("lost", [0x35, 0x40, 0x42], ids=["stop", "save", "poll"])
def test_flash_save_lost_answer_starts_mc_again(lost):
    """A missing answer (SdoTimeout) once the MC may be stopped: the FB still starts the MC (36h) before it
    reports the timeout; the drive's MC runs again. (A lost answer to 35h: the drive may have stopped.)"""
    b = Bench(nodes=1)
    assert add_seed(b).done
    b["CH1.SDOTIMEOUT"] = 30 * MS
    b.bus.drop(answer_to(lost), count=1)
    t0 = b.plc.time_ns
    r = b.fb("FS").run(CURVES=True, POLLINTERVAL=0)
    assert r.error and r.error_id == E["SdoTimeout"] and r["ABORTCODE"] == 0
    subs = sent_subs(b, t0)
    assert subs[0] == 0x35 and subs[-1] == 0x36 and subs.count(0x36) == 1
    assert lost in subs and subs.index(lost) == len(subs) - 2        # the start follows the unanswered request
    assert b.drive.mc_phase == "running"


def test_mc_stop_refused():
    b = Bench(nodes=1)
    b.bus.mutate_payload(answer_to(0x35), patched(d6=0xD7), count=1)
    t0 = b.plc.time_ns
    r = b.fb("FS").run(CURVES=True)
    assert r.error and r.error_id == E["ResultMcNotStopped"]
    assert sent_subs(b, t0) == [0x35]              # MC was not stopped: nothing to start again


class EndlessUpidList:
    """A node whose UPID list never ends (to fill the PLC's list)."""

    def __init__(self, node_id):
        self.node_id, self.next = node_id, 0

    def on_frame(self, f, t):
        if f.can_id != 0x600 + self.node_id:
            return []
        d = f.data
        if d[3] == 0x20:
            self.next = int.from_bytes(d[6:8], "little")
            return [(t + 100_000, Frame(0x580 + self.node_id, bytes([0x60]) + d[1:4] + bytes([0, 0, 4, 0])))]
        upid, self.next = self.next, self.next + 1
        data = bytes([0x43]) + d[1:4] + (0x000D).to_bytes(2, "little") + upid.to_bytes(2, "little")
        return [(t + 100_000, Frame(0x580 + self.node_id, data))]

    def on_timer(self, t):
        return []

    def next_timer_ns(self):
        return None


def test_upid_list_longer_than_the_plc_holds():
    b = Bench(nodes=0, enable=False)
    b.bus.attach(EndlessUpidList(9), "endless")
    b["CH1.NODEID"] = 9
    b["CH1.ENABLE"] = True
    b.step(2)
    r = b.fb("UL").run(STARTUPID=0x0100, ENDUPID=0xFFFE)
    assert r.error and r.error_id == E["ListFull"] and r["COUNT"] == 2048
    assert b["UPIDS"][-1] == {"UPID": 0x0100 + 2047, "USAGE": 0x000D}
    assert b.fb("UL").run(STARTUPID=0x0100, ENDUPID=0x0110)["COUNT"] == 17
