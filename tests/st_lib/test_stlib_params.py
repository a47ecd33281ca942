"""Parameter services of the ST library against the emulated E1100: round trips, drive refusals, input
errors, strings as stringlets, set-to-default, UPID lists, firmware layers."""

from __future__ import annotations

import json

import pytest

from linmot_st.protocol.errors import BY_NAME
from stbench import VECTORS, exchanges

E = {name: e.value for name, e in BY_NAME.items()}
ABORT_READ_ONLY, ABORT_RANGE, ABORT_NO_OBJECT, ABORT_UNSUPPORTED = 0x06010002, 0x06090030, 0x06020000, 0x06010000

LIVE = 0x1005          # Max Current Limit: live UINT16 100..2500, default 2000
NON_LIVE = 0x101A      # Motor Supply Voltage Error Low Level: non-live UINT16 0..1000, default 180
READ_ONLY = 0x1B62     # State Var: a variable


def test_write_then_read_back_every_memory(b):
    wr, rd = b.fb("WR"), b.fb("RD")
    r = wr.run(UPID=LIVE, VALUE=1234, MEM="LM_RAM")
    assert r.done and not r.error and r.scans == 2
    assert (b.drive.ram(LIVE), b.drive.rom(LIVE)) == (1234, 2000)
    assert rd.run(UPID=LIVE, MEM="LM_RAM")["VALUE"] == 1234
    assert rd.run(UPID=LIVE, MEM="LM_ROM")["VALUE"] == 2000

    assert wr.run(UPID=LIVE, VALUE=1500, MEM="LM_ROM").done
    assert (b.drive.ram(LIVE), b.drive.rom(LIVE)) == (1234, 1500)
    assert rd.run(UPID=LIVE, MEM="LM_ROM")["VALUE"] == 1500

    assert wr.run(UPID=LIVE, VALUE=999, MEM="LM_RAM_ROM").done
    assert (b.drive.ram(LIVE), b.drive.rom(LIVE)) == (999, 999)
    assert rd.run(UPID=LIVE, MEM="LM_RAM")["VALUE"] == 999

    assert rd.run(UPID=LIVE, MEM="LM_MIN")["VALUE"] == 100
    assert rd.run(UPID=LIVE, MEM="LM_MAX")["VALUE"] == 2500
    assert rd.run(UPID=LIVE, MEM="LM_DEFAULT")["VALUE"] == 2000


def test_signed_values(b):
    upid = 0x1040      # SINT16 -400..900
    assert b.fb("WR").run(UPID=upid, VALUE=-321, MEM="LM_RAM_ROM").done
    assert b.fb("RD").run(UPID=upid, MEM="LM_ROM")["VALUE"] == -321
    assert b.fb("RD").run(UPID=upid, MEM="LM_MIN")["VALUE"] == -400


def test_one_exchange_per_access_in_one_scan(b):
    t0 = b.plc.time_ns
    r = b.fb("RD").run(UPID=LIVE)
    trace = b.sdo_trace(since_ns=t0)
    assert exchanges(trace) == 1 and len(trace) == 2
    assert r.scans == 2          # request in the Execute scan, answer consumed in the next


@pytest.mark.parametrize("upid,value,mem,abort", [
    (READ_ONLY, 1, "LM_RAM_ROM", ABORT_READ_ONLY),      # read-only variable
    (LIVE, 5000, "LM_RAM", ABORT_RANGE),                # above max
    (LIVE, 50, "LM_ROM", ABORT_RANGE),                  # below min
    (NON_LIVE, 200, "LM_RAM", ABORT_READ_ONLY),         # RAM of a non-live parameter: not over the bus
    (0x3FFE, 1, "LM_RAM", ABORT_NO_OBJECT),             # no such UPID
])
def test_drive_refusals_end_in_sdo_abort(b, upid, value, mem, abort):
    before = (b.drive.params[upid].ram, b.drive.params[upid].rom) if upid in b.drive.params else None
    r = b.fb("WR").run(UPID=upid, VALUE=value, MEM=mem)
    assert r.error and not r.done and r.error_id == E["SdoAbort"]
    assert r["ABORTCODE"] == abort
    assert b.fb("WR")["ABORTCODE"] == 0                     # reset with the other outputs after Execute fell
    if before is not None:
        assert (b.drive.params[upid].ram, b.drive.params[upid].rom) == before


def test_non_live_rom_write_is_accepted(b):
    assert b.fb("WR").run(UPID=NON_LIVE, VALUE=200, MEM="LM_ROM").done
    assert (b.drive.ram(NON_LIVE), b.drive.rom(NON_LIVE)) == (180, 200)


@pytest.mark.parametrize("fb,inputs,error", [
    ("WR", dict(UPID=0x4000, VALUE=1, MEM="LM_RAM"), "InvalidUpid"),
    ("RD", dict(UPID=0xFFFF, MEM="LM_RAM"), "InvalidUpid"),
    ("RD", dict(UPID=LIVE, MEM="LM_RAM_ROM"), "InvalidMem"),
    ("WR", dict(UPID=LIVE, VALUE=1, MEM="LM_MIN"), "InvalidMem"),
    ("WR", dict(UPID=LIVE, VALUE=1, MEM="LM_DEFAULT"), "InvalidMem"),
    ("SRD", dict(UPID=0x03E8, COUNT=0), "InvalidStringletCount"),
    ("SRD", dict(UPID=0x03E8, COUNT=33), "InvalidStringletCount"),
    ("SRD", dict(UPID=0x3FF0, COUNT=16), "InvalidUpid"),
    ("SWR", dict(UPID=0x03E8, COUNT=2, TEXT="too long text"), "TextTooLong"),
    ("SWR", dict(UPID=0x03E8, COUNT=8, TEXT="tab\there"), "InvalidChar"),
    ("SWR", dict(UPID=0x03E8, COUNT=8, TEXT="ok", MEM="LM_MAX"), "InvalidMem"),
    ("DEF", dict(LAYER=0), "InvalidLayer"),
    ("DEF", dict(LAYER=5), "InvalidLayer"),
    ("UL", dict(STARTUPID=0x2000, ENDUPID=0x1000), "InvalidUpidRange"),
    ("LC", dict(LAYER=7), "InvalidLayer"),
    ("SDO", dict(INDEX=0x0100, SUBINDEX=1), "InvalidSdoCommand"),
])
def test_invalid_inputs_fail_before_any_frame(b, fb, inputs, error):
    t0 = b.plc.time_ns
    r = b.fb(fb).run(**inputs)
    assert r.error and r.error_id == E[error] and r.scans == 1
    assert b.sdo_trace(since_ns=t0) == []


def test_string_parameter_round_trip_and_vectors(b):
    vec = json.loads((VECTORS / "stringlets.json").read_text())["strings"]
    for v in (v for v in vec if v.get("drive", "E1100") == "E1100"):     # the emulated drive is an E1100
        upid = int(v["string_upid"], 16)
        t0 = b.plc.time_ns
        r = b.fb("SWR").run(UPID=upid, COUNT=v["count"], TEXT=v["text"], MEM="LM_RAM_ROM")
        assert r.done, r
        assert exchanges(b.sdo_trace(since_ns=t0)) == v["count"]
        for s in v["stringlets"]:                  # what the drive holds, stringlet by stringlet
            assert b.drive.rom(int(s["upid"], 16)) & 0xFFFFFFFF == int(s["value"], 16)
        assert b.drive.string(upid, "rom") == v["text"]
        got = b.fb("SRD").run(UPID=upid, COUNT=v["count"], MEM="LM_ROM")
        assert got.done and got["TEXT"] == v["text"]
        assert [x & 0xFFFFFFFF for x in got["STRINGLETS"][: v["count"]]] == [int(s["value"], 16) for s in v["stringlets"]]


def test_longer_text_is_cleared_by_a_shorter_one(b):
    assert b.fb("SWR").run(UPID=0x03F2, COUNT=8, TEXT="A" * 32).done
    assert b.fb("SWR").run(UPID=0x03F2, COUNT=8, TEXT="B").done
    assert b.drive.string(0x03F2, "rom") == "B"
    assert b.fb("SRD").run(UPID=0x03F2, COUNT=8, MEM="LM_RAM")["TEXT"] == "B"


def test_set_layer_default(b):
    assert b.fb("WR").run(UPID=LIVE, VALUE=777, MEM="LM_RAM_ROM").done
    r = b.fb("DEF").run(LAYER=2)
    assert r.done, r
    assert b.drive.rom(LIVE) == 2000
    assert b.fb("RD").run(UPID=LIVE, MEM="LM_ROM")["VALUE"] == 2000


def test_upid_list_and_modified_list(b):
    ul = b.fb("UL")
    t0 = b.plc.time_ns
    r = ul.run(MODIFIED=False, STARTUPID=0x1000, ENDUPID=0x1EFF)
    assert r.done, r
    n = r["COUNT"]
    lst = b["UPIDS"][:n]
    got = [e["UPID"] for e in lst]
    assert got == [u for u in b.drive.params.upids() if 0x1000 <= u <= 0x1EFF] and n > 5
    assert exchanges(b.sdo_trace(since_ns=t0)) == 1 + n + 1
    usage = {e["UPID"]: e["USAGE"] for e in lst}
    assert usage == {u: b.drive.params[u].address_usage for u in got}
    assert usage[0x13A2] == 0x010F                          # the LinRS example UPID 13A2h

    assert b.fb("WR").run(UPID=LIVE, VALUE=1111, MEM="LM_RAM_ROM").done
    assert b.fb("SWR").run(UPID=0x03F2, COUNT=8, TEXT="hello").done
    r = ul.run(MODIFIED=True, STARTUPID=0, ENDUPID=0xFFFE)
    assert r.done
    mod = [e["UPID"] for e in b["UPIDS"][: r["COUNT"]]]
    assert LIVE in mod and 0x03F3 in mod and 0x03F4 in mod
    assert NON_LIVE not in mod


def test_layer_check(b):
    lc = b.fb("LC")
    r = lc.run(LAYER=2, CHECK=True, SOURCE={"TREEID": 4612, "MAINVERSION": 3, "SUBVERSION": 0})
    assert r.done and r["COMPATIBLE"] and r["MISMATCH"] == 0
    assert r["DRIVE"] == {"TREEID": 4612, "MAINVERSION": 3, "SUBVERSION": 0}
    r = lc.run(LAYER=3, CHECK=True, SOURCE={"TREEID": 8194, "MAINVERSION": 3, "SUBVERSION": 3})
    assert r.done and not r["COMPATIBLE"] and r["MISMATCH"] == E["SubVersionNewer"]
    assert r["DRIVE"] == {"TREEID": 8194, "MAINVERSION": 3, "SUBVERSION": 2}
    r = lc.run(LAYER=1, CHECK=True, SOURCE={"TREEID": 4612, "MAINVERSION": 3, "SUBVERSION": 0})
    assert r.done and r["MISMATCH"] == E["TreeIdMismatch"]
    r = lc.run(LAYER=1, CHECK=True, SOURCE={"TREEID": 1, "MAINVERSION": 2, "SUBVERSION": 0})
    assert r.done and r["MISMATCH"] == E["MainVersionMismatch"]


def test_raw_sdo(b):
    sdo = b.fb("SDO")
    r = sdo.run(INDEX=0x1018, SUBINDEX=1, WRITE=False)
    assert r.done and r["VALUEREAD"] == 0x00000156                  # vendor ID
    r = sdo.run(INDEX=0x2000 + LIVE, SUBINDEX=1, WRITE=True, VALUE=1212)
    assert r.done and r["RESULT"] == 0 and b.drive.ram(LIVE) == 1212
    r = sdo.run(INDEX=0x2000, SUBINDEX=0x99, WRITE=False)
    assert r.error and r.error_id == E["SdoAbort"] and r["ABORTCODE"] == 0x06090011
