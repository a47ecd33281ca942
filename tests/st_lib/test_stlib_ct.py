"""Command-table services of the ST library against the emulated E1100."""

from __future__ import annotations

import pytest

from linmot_st.emulator import build_entry
from linmot_st.protocol.errors import BY_NAME
from stbench import exchanges

E = {name: e.value for name, e in BY_NAME.items()}
PARS = bytes(range(0x10, 0x30))


def test_write_then_read_back(b):
    block = build_entry(0x0901, PARS, name="GoTo50mm", link=0xFFFF)
    t0 = b.plc.time_ns
    r = b.fb("CTWR").run(ENTRY=5, BLOCK=list(block))
    assert r.done, r
    trace = b.sdo_trace(since_ns=t0)
    assert exchanges(trace) == 1 + 32 == r["EXCHANGES"]
    assert r.scans == 1 + 32 + 1
    assert b.drive.ct.ram[5] == block

    t0 = b.plc.time_ns
    g = b.fb("CTRD").run(ENTRY=5)
    assert g.done, g
    assert exchanges(b.sdo_trace(since_ns=t0)) == 1 + 32 == g["EXCHANGES"]
    assert g.scans == 1 + 32 + 1
    assert bytes(g["BLOCK"]) == block
    f = g["FIELDS"]
    assert (f["LINK"], f["HEADER"], bytes(f["PARS"])) == (0xFFFF, 0x0901, PARS)
    assert g["NAME"] == "GoTo50mm"


def test_write_from_fields(b):
    r = b.fb("CTWRF").run(ENTRY=200, LINK=201, HEADER=0x0103, PARS=list(PARS), NAME="Sixteen chars ok")
    assert r.done, r
    assert r["EXCHANGES"] == 33
    expected = build_entry(0x0103, PARS, link=201)[:38] + b"Sixteen chars ok" + bytes(10)
    assert b.drive.ct.ram[200] == expected == bytes(r["BLOCK"])
    assert b.fb("CTRD").run(ENTRY=200)["NAME"] == "Sixteen chars ok"


def test_presence_delete_and_delete_all(b):
    for entry in (0, 31, 32, 255):
        assert b.fb("CTWRF").run(ENTRY=entry, HEADER=0x0103, NAME=f"e{entry}").done
    p = b.fb("CTPRES").run()
    assert p.done and p["COUNT"] == 4
    assert p["LIST"] == [b.drive.ct.presence(k) for k in range(8)]
    assert p["LIST"][0] == 0xFFFFFFFF & ~(1 | 1 << 31)
    assert b.fb("CTDEL").run(ENTRY=31).done
    assert 31 not in b.drive.ct.ram
    assert b.fb("CTPRES").run()["COUNT"] == 3
    assert b.fb("CTRD").run(ENTRY=31).error_id == E["ResultObjectState"]     # D4h: entry not present
    assert b.fb("CTDELALL").run().done
    assert b.drive.ct.ram == {}
    assert b.fb("CTPRES").run()["LIST"] == [0xFFFFFFFF] * 8


@pytest.mark.parametrize("fb,inputs,error", [
    ("CTWR", dict(ENTRY=256, BLOCK=list(build_entry(1))), "InvalidCtEntry"),
    ("CTWR", dict(ENTRY=1, BLOCK=[0] * 64), "CtVersion"),
    ("CTWR", dict(ENTRY=1, BLOCK=list(build_entry(1, link=300))), "CtLink"),
    ("CTWRF", dict(ENTRY=1, NAME="Seventeen chars!!"), "NameTooLong"),
    ("CTWRF", dict(ENTRY=1, NAME="caf\xe9"), "InvalidChar"),
    ("CTWRF", dict(ENTRY=1000, NAME="x"), "InvalidCtEntry"),
    ("CTWRF", dict(ENTRY=1, NAME="x", LINK=256), "CtLink"),
    ("CTRD", dict(ENTRY=256), "InvalidCtEntry"),
    ("CTDEL", dict(ENTRY=256), "InvalidCtEntry"),
])
def test_invalid_inputs_fail_before_any_frame(b, fb, inputs, error):
    t0 = b.plc.time_ns
    r = b.fb(fb).run(**inputs)
    assert r.error and r.error_id == E[error] and r.scans == 1
    assert b.sdo_trace(since_ns=t0) == []


def test_save_command_table_only(b):
    assert b.fb("CTWRF").run(ENTRY=9, HEADER=0x0103, NAME="kept").done
    t0 = b.plc.time_ns
    r = b.fb("FS").run(CURVES=False, COMMANDTABLE=True, POLLINTERVAL=0)
    assert r.done, r
    subs = [e.frame.data[3] for e in b.sdo_trace(since_ns=t0) if e.frame.can_id == 0x601]
    assert subs[:2] == [0x35, 0x80] and set(subs[2:-1]) == {0x80} and subs[-1] == 0x36   # no 40h / 42h
    assert r["POLLS"] == len(subs) - 3 >= 1
    assert b.drive.ct.flash == {9: b.drive.ct.ram[9]} and b.drive.curves.flash == {}
    assert b.drive.mc_phase == "running"


def test_save_to_flash_with_curves_in_one_run(b):
    assert b.fb("CTWRF").run(ENTRY=9, HEADER=0x0103, NAME="kept").done
    r = b.fb("FS").run(CURVES=True, COMMANDTABLE=True, POLLINTERVAL=0)
    assert r.done, r
    assert 9 in b.drive.ct.flash
    assert b.fb("CTDELALL").run().done
    assert b.fb("RST").run().done
    assert b.fb("CTRD").run(ENTRY=9)["NAME"] == "kept"


def test_aborted_write_leaves_the_entry_absent_until_written_again(b):
    assert b.fb("CTWRF").run(ENTRY=3, HEADER=0x0103, NAME="old").done
    block = build_entry(0x0901, PARS, name="new")
    wr = b.fb("CTWR")
    wr.start(ENTRY=3, BLOCK=list(block))
    b.step(6)
    wr["ABORT"] = True
    b.step(1)
    assert wr["COMMANDABORTED"]
    wr.set(EXECUTE=False, ABORT=False)
    b.step(1)
    assert 3 not in b.drive.ct.ram
    assert b.fb("CTRD").run(ENTRY=3).error_id == E["ResultObjectState"]      # D4h: not present
    assert wr.run(ENTRY=3, BLOCK=list(block)).done
    assert b.drive.ct.ram[3] == block
