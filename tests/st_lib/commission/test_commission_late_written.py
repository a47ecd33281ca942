"""Issue 24 section 3 (a) for FB_LmCommission's own parameter writes (they bypass FB_LmParamWrite): a run
fails because the answer to its write of 1005h timed out; the next run, started at once with a value the
drive refuses (the pre-flight off, which would have refused it before writing), must not take the first
run's late "written", delivered out of order, for its own answer (docs/st-library.md section 3.5)."""

from __future__ import annotations

from test_commission_plcopen import INSTANCE, ComBench

from linmot_st.protocol.errors import BY_NAME

E = {name: e.value for name, e in BY_NAME.items()}
MS, US = 1_000_000, 1_000
ROM_WRITE_1005 = bytes([0x05, 0x30, 0x02])     # 2000h + 1005h (Max Current Limit), sub 02h: ROM
VALUE_WORD = 42        # plc_project's Ds: 4 header words, 2 layers, 16 string rows, then 1005h := 1500
GOOD, REFUSED = 1500, 3000


def write_answer(f) -> bool:
    return f.can_id == 0x581 and f.data[0] == 0x60 and bytes(f.data[1:4]) == ROM_WRITE_1005


def until_end(b: ComBench, com, scans: int = 20_000) -> None:
    for _ in range(scans):
        b.step(1)
        if com["DONE"] or com["ERROR"]:
            return
    raise AssertionError("no end")


def two_runs(delay_ns: int) -> dict:
    b = ComBench()
    com = b.fb("COM")
    b.plc[f"{INSTANCE}.PREFLIGHT"] = False
    com.set(FORCE=True)                                  # every row written (RUN: no verify, flash, reset)
    b.bus.delay(write_answer, delay_ns, count=1, fifo=False)
    com.start()
    until_end(b, com)
    first = (bool(com["DONE"]), com["ERRORID"])
    com["EXECUTE"] = False
    b.step(1)
    b.plc[f"{INSTANCE}.DS[{VALUE_WORD}]"] = REFUSED
    com.start()
    until_end(b, com)
    second = dict(done=bool(com["DONE"]), error_id=com["ERRORID"], item=com["FAILITEM"],
                  expected=com["FAILEXPECTED"], actual=com["FAILACTUAL"])
    com["EXECUTE"] = False
    b.step(3000)                                         # every late frame arrives
    return dict(first=first, second=second, rom=b.drive.rom(0x1005), ram=b.drive.ram(0x1005))


# The first run's write leaves at 48 ms, the second run's at 1074 ms, the drive's refusal 0.39 ms later.
# Measured before the fix (10 us steps from 1025.70 ms): delays 1026.01..1026.37 ms made the second run
# report Done with 1500 in the drive's ROM (the late "written" arrived between its write and the refusal).
SWEEP_NS = [1025_800 * US + k * 20 * US for k in range(41)]      # 1025.80 .. 1026.60 ms, 20 us steps


def test_a_late_written_never_confirms_the_next_runs_refused_parameter_write():
    outcomes = set()
    for d in SWEEP_NS:
        o = two_runs(d)
        assert o["first"] == (False, E["SdoTimeout"]), d
        s = o["second"]
        assert not s["done"], d
        assert s["error_id"] in (E["SdoAbort"], E["WriteNotConfirmed"]), d
        if s["error_id"] == E["WriteNotConfirmed"]:
            assert (s["item"], s["expected"], s["actual"]) == (0x1005, REFUSED, GOOD), d
        assert o["rom"] == GOOD, d
        outcomes.add(s["error_id"])
    assert outcomes == {E["SdoAbort"], E["WriteNotConfirmed"]}        # the sweep crossed the window
