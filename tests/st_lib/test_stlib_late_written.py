"""Issue 24 section 3 (a): a late "written" must never confirm a refused retry. The channel's
re-synchronisation (test_stlib_resync.py) keeps a late answer out as long as the drive's answers stay in
order; here the first answer is delayed without keeping the order (the simulated bus's plain `delay`: later
frames of the drive overtake it), so it can arrive while the retry's own answer is awaited. The write to an
object whose earlier write timed out is therefore read back (docs/st-library.md section 3.5)."""

from __future__ import annotations

from linmot_st.protocol.errors import BY_NAME
from stbench import Bench, exchanges

E = {name: e.value for name, e in BY_NAME.items()}
MS, US = 1_000_000, 1_000
LIVE = 0x1005                  # Max Current Limit: live, 100..2500 (data/e1100_parameters.csv)
GOOD, REFUSED = 1500, 3000     # the drive refuses 3000 with abort 06090030h


def write_answer(f) -> bool:
    """the drive's answer to a RAM+ROM write of node 1 (sub-index 06h)"""
    return f.can_id == 0x581 and len(f.data) == 8 and f.data[3] == 0x06


def timed_out_write_then_retry(delay_ns: int, retry_value: int, echo: bool = True) -> dict:
    """Write 1005h := 1500 (RAM+ROM) with the drive's answer delayed by delay_ns, out of order; when the
    write fails, retry at once with retry_value. Returns both outcomes and the drive's values."""
    b = Bench(nodes=1, echo=echo)
    b.bus.delay(write_answer, delay_ns, count=1, fifo=False)
    wr = b.fb("WR")
    first = wr.run(UPID=LIVE, VALUE=GOOD, MEM="LM_RAM_ROM", max_scans=5000)
    retry = None
    if first.error:
        retry = wr.run(UPID=LIVE, VALUE=retry_value, MEM="LM_RAM_ROM", max_scans=5000)
        b.step(3000)                   # let every late frame arrive
    return dict(first=first, retry=retry, ram=b.drive.ram(LIVE), rom=b.drive.rom(LIVE), bench=b)


# The first answer would come 0.38 ms after the write (24 ms into the run); the write times out at
# 1024 ms, the sync exchange follows, the retry is on the bus at 1026.0..1026.23 ms and the drive's
# refusal at 1026.38..1026.62 ms. A late answer that ends between the two lands in the window: measured
# before the fix, delays 1002.01..1002.38 ms made the refused retry report Done (drive: 1500 in RAM/ROM).
SWEEP_NS = [1001_800 * US + k * 10 * US for k in range(71)]        # 1001.80 .. 1002.50 ms, 10 us steps


def test_a_late_written_never_confirms_a_refused_retry():
    outcomes = set()
    for d in SWEEP_NS:
        o = timed_out_write_then_retry(d, REFUSED)
        first, retry = o["first"], o["retry"]
        assert first.error_id == E["SdoTimeout"], d
        assert retry.error and not retry.done, d
        # either the drive's own refusal, or the late "written" taken and the read-back found the old value
        assert retry.error_id in (E["SdoAbort"], E["WriteNotConfirmed"]), d
        assert (o["ram"], o["rom"]) == (GOOD, GOOD), d
        outcomes.add(retry.error_id)
    # the sweep crossed the window: some steps took the late answer for the retry's (Done on main)
    assert outcomes == {E["SdoAbort"], E["WriteNotConfirmed"]}


def test_the_late_written_of_an_accepted_retry_is_confirmed_by_the_read_back():
    """The retry's value is accepted: Done, whichever "written" it took, and the drive holds the value;
    the read-back cleared the suspicion, so the next write has the normal single exchange."""
    for d in (1002_000 * US, 1002_150 * US, 1500 * MS):
        o = timed_out_write_then_retry(d, 1800)
        assert o["retry"].done and (o["ram"], o["rom"]) == (1800, 1800), d
        b = o["bench"]
        since = b.bus.now
        nxt = b.fb("WR").run(UPID=LIVE, VALUE=1700, MEM="LM_RAM_ROM", max_scans=5000)
        assert nxt.done and b.drive.ram(LIVE) == 1700
        assert exchanges(b.sdo_trace(since_ns=since)) == 1, d


def test_the_read_back_costs_nothing_on_the_normal_path():
    """Without a timeout a write is one exchange (E1100), as before."""
    b = Bench(nodes=1)
    r = b.fb("WR").run(UPID=LIVE, VALUE=GOOD, MEM="LM_RAM_ROM", max_scans=5000)
    assert r.done and exchanges(b.sdo_trace()) == 1


def test_after_a_timed_out_write_the_next_write_reads_ram_and_rom_back():
    """The retry of a RAM+ROM write: the write, then RAM and ROM read back (sub-indices 01h, 02h)."""
    o = timed_out_write_then_retry(1500 * MS, 1800)
    b = o["bench"]
    reqs = [(e.frame.data[0], e.frame.data[3]) for e in b.sdo_trace() if e.frame.can_id == 0x601
            and e.frame.data[1:3] == bytes([0x05, 0x30])]
    # the first write, its abort, the retry, RAM read back, ROM read back
    assert reqs == [(0x23, 0x06), (0x80, 0x06), (0x23, 0x06), (0x40, 0x01), (0x40, 0x02)]


def test_b1100_the_write_after_a_timeout_selects_and_reads_back():
    """B1100 (every access through 2000h: select C0h, RAM 01h, ROM 02h), against the emulated B1100: after a
    timed-out RAM write, the next RAM write is select + write + select + read; a value that reads back the same
    is Done, and the write after that is select + write again."""
    from linmot_st.emulator import DriveTimings
    from linmot_st.emulator.models import make_drive

    b = Bench(nodes=0, enable=False)
    drive = make_drive("B1100", 63, timings=DriveTimings.fast())
    b.bus.attach(drive, "b1100")
    drive.power_on(0)
    b["CH1.NODEID"] = 63
    b["CH1.DRIVE"] = "LM_B1100"
    b["CH1.ENABLE"] = True
    b.sim.run_until(lambda: b["AX1.BOOTCOUNT"] >= 1, max_scans=1000)
    b.step(2)

    def requests() -> list[bytes]:
        return [bytes(e.frame.data) for e in b.sdo_trace(63) if e.frame.can_id == 0x63F]

    upid = 0xE19C                     # Max Current (CANopen manual p.33's example UPID of the B1100)
    b.bus.drop(lambda f: f.can_id == 0x5BF and f.data[0] == 0x60 and f.data[3] == 0x01, count=1)
    wr = b.fb("WR")
    assert wr.run(UPID=upid, VALUE=2000, MEM="LM_RAM", max_scans=5000).error_id == E["SdoTimeout"]
    before = len(requests())
    r = wr.run(UPID=upid, VALUE=2200, MEM="LM_RAM", max_scans=5000)
    assert r.done and drive.ram(upid) == 2200
    sent = [(d[0], d[3]) for d in requests()[before:]]
    assert sent == [(0x23, 0xC0), (0x23, 0x01), (0x23, 0xC0), (0x40, 0x01)]     # select, write; select, read
    before = len(requests())
    assert wr.run(UPID=upid, VALUE=2400, MEM="LM_RAM", max_scans=5000).done
    assert len(requests()) - before == 2                    # confirmed once: select + write again
