"""Curve services of the ST library against the emulated E1100: download then upload byte-identical,
exchange and scan counts from the bus trace, drive refusals, input errors, delete, flash save."""

from __future__ import annotations

import json
import struct

import pytest

from linmot_st.protocol.errors import BY_NAME
from stbench import VECTORS, exchanges

E = {name: e.value for name, e in BY_NAME.items()}
CURVES = json.loads((VECTORS / "curve_info.json").read_text())["curves"]
SEED = CURVES[0]                       # the seeds' PVL curve 23, 10 setpoints


def info_of(vec) -> list[int]:
    return list(bytes.fromhex(vec["info_block"]))


def make_curve(curve_id: int, n: int, name: str = "PLC curve") -> tuple[list[int], list[int]]:
    """(info block, setpoints) of a position/time curve of n setpoints, laid out as seeds table 6."""
    setpoints = [(-1) ** k * (k * 7919 % 100_000) for k in range(n)]
    info = struct.pack("<HHHH22sHIHHH28s", 70, 3, n, 4, name.encode(), curve_id, 100 * n, 0x1A, 0x05, 0, b"")
    return list(info), setpoints


def add(b, curve_id, info, setpoints, data_size=None, two_byte=False, fb="CA"):
    b.set_setpoints(setpoints)
    return b.fb(fb).run(CURVEID=curve_id, INFO=info, DATASIZE=4 * len(setpoints) if data_size is None else data_size,
                        TWOBYTE=two_byte)


@pytest.mark.parametrize("two_byte", [False, True], ids=["4-byte", "2-byte"])
def test_seed_curve_add_then_get_byte_identical(b, two_byte):
    info, setpoints = info_of(SEED), SEED["setpoints"]
    n = len(setpoints)
    t0 = b.plc.time_ns
    r = add(b, 23, info, setpoints, two_byte=two_byte)
    assert r.done and not r.error, r
    trace = b.sdo_trace(since_ns=t0)
    expected = 1 + 35 + 2 * n if two_byte else 1 + 18 + n
    assert exchanges(trace) == expected == r["EXCHANGES"]
    assert r.scans == expected + 1            # one scan per exchange, plus the Execute scan
    curve = b.drive.curves.ram[23]
    assert list(curve.info) == info and curve.setpoints == setpoints

    t0 = b.plc.time_ns
    g = b.fb("CG").run(CURVEID=23)
    assert g.done, g
    assert exchanges(b.sdo_trace(since_ns=t0)) == 1 + 18 + n == g["EXCHANGES"]
    assert g.scans == 1 + 18 + n + 1
    assert g["INFO"] == info
    assert b["SPGET"][:n] == setpoints
    assert (g["NUMSETPOINTS"], g["DATASIZE"], g["NAME"]) == (10, 40, "Example_Curve")
    assert g["HEADER"]["CURVEID"] == 23 and g["HEADER"]["XLENGTH"] == 20000


def test_large_curve_1000_setpoints_exchange_count(b):
    info, setpoints = make_curve(7, 1000)
    t0 = b.plc.time_ns
    r = add(b, 7, info, setpoints)
    assert r.done, r
    trace = b.sdo_trace(since_ns=t0)
    assert exchanges(trace) == 1 + 18 + 1000
    assert r.scans == 1 + 18 + 1000 + 1
    # one request per scan: consecutive requests are exactly one task interval apart
    starts = [e.start_ns for e in trace if e.frame.can_id == 0x601]
    assert {b2 - a for a, b2 in zip(starts, starts[1:])} == {b.plc.tick_ns}
    assert b.drive.curves.ram[7].setpoints == setpoints
    g = b.fb("CG").run(CURVEID=7)
    assert g.done and b["SPGET"] == setpoints and g["INFO"] == info


def test_cam_curve_vector(b):
    vec = CURVES[1]
    r = add(b, vec["fields"]["curve_id"], info_of(vec), vec["setpoints"])
    assert r.done, r
    g = b.fb("CG").run(CURVEID=vec["fields"]["curve_id"])
    assert g["INFO"] == info_of(vec) and b["SPGET"][: len(vec["setpoints"])] == vec["setpoints"]


def test_add_from_fields(b):
    vec = CURVES[1]            # generated cam, no wizard fields: the library builds the same block
    f = vec["fields"]
    b.set_setpoints(vec["setpoints"])
    r = b.fb("CAF").run(CURVEID=f["curve_id"], NAME=f["name"], OBJECTTYPE=f["object_type"], XLENGTH=f["x_length"],
                        NUMSETPOINTS=f["setpoints"])
    assert r.done, r
    assert r["INFO"] == info_of(vec)
    assert list(b.drive.curves.ram[f["curve_id"]].info) == info_of(vec)
    assert r["EXCHANGES"] == 1 + 18 + f["setpoints"]


def test_drive_refuses_existing_and_absent_curves(b):
    info, setpoints = info_of(SEED), SEED["setpoints"]
    assert add(b, 23, info, setpoints).done
    t0 = b.plc.time_ns
    r = add(b, 23, info, setpoints)
    assert r.error and r.error_id == E["ResultObjectState"]            # D4h: curve already exists
    assert exchanges(b.sdo_trace(since_ns=t0)) == 1
    r = b.fb("CG").run(CURVEID=24)
    assert r.error and r.error_id == E["ResultObjectState"]            # D4h: not present
    assert b.fb("CDA").run().done
    assert b.drive.curves.ram == {}
    assert b.fb("CG").run(CURVEID=23).error_id == E["ResultObjectState"]


def info_with(**changes) -> list[int]:
    info = bytearray(bytes.fromhex(SEED["info_block"]))
    offsets = {"offset": (0, "<H"), "type": (2, "<H"), "n": (4, "<H"), "size": (6, "<H"), "id": (30, "<H")}
    for k, v in changes.items():
        if k == "name":
            info[8:30] = v
        else:
            o, fmt = offsets[k]
            struct.pack_into(fmt, info, o, v)
    return list(info)


@pytest.mark.parametrize("curve_id,info,data_size,error", [
    (0, info_with(id=0), 40, "InvalidCurveId"),
    (101, info_with(id=101), 40, "InvalidCurveId"),
    (23, info_with(n=1), 4, "TooFewSetpoints"),
    (23, info_with(n=1001), 4004, "TooManySetpoints"),
    (23, info_of(SEED), 44, "DataSizeMismatch"),
    (23, info_with(offset=72), 40, "InfoDataOffset"),
    (23, info_with(type=0x0002), 40, "InfoObjectType"),
    (23, info_with(size=2), 40, "InfoTypeSize"),
    (22, info_of(SEED), 40, "InfoCurveId"),
    (23, info_with(name=b"N" * 22), 40, "NameTooLong"),
])
def test_invalid_curve_inputs_fail_before_any_frame(b, curve_id, info, data_size, error):
    t0 = b.plc.time_ns
    r = add(b, curve_id, info, SEED["setpoints"], data_size=data_size)
    assert r.error and r.error_id == E[error] and r.scans == 1
    assert b.sdo_trace(since_ns=t0) == []


@pytest.mark.parametrize("inputs,error", [
    (dict(CURVEID=3, NAME="a name longer than 21 c", NUMSETPOINTS=10), "NameTooLong"),
    (dict(CURVEID=3, NAME="caf\xe9", NUMSETPOINTS=10), "InvalidChar"),
    (dict(CURVEID=3, NAME="ok", NUMSETPOINTS=1), "TooFewSetpoints"),
    (dict(CURVEID=300, NAME="ok", NUMSETPOINTS=10), "InvalidCurveId"),
    (dict(CURVEID=3, NAME="ok", NUMSETPOINTS=10, OBJECTTYPE=0x0203), "InfoObjectType"),
])
def test_invalid_field_inputs(b, inputs, error):
    t0 = b.plc.time_ns
    r = b.fb("CAF").run(**inputs)
    assert r.error and r.error_id == E[error] and r.scans == 1
    assert b.sdo_trace(since_ns=t0) == []
    assert b.fb("CG").run(CURVEID=400).error_id == E["InvalidCurveId"]


def test_flash_save_keeps_curves_over_a_reset(b):
    info, setpoints = info_of(SEED), SEED["setpoints"]
    assert add(b, 23, info, setpoints).done
    fs = b.fb("FS")
    t0 = b.plc.time_ns
    r = fs.run(CURVES=True, COMMANDTABLE=False, MANAGEMC=True, POLLINTERVAL=0)
    assert r.done, r
    assert 23 in b.drive.curves.flash and b.drive.mc_phase == "running"
    subs = [e.frame.data[3] for e in b.sdo_trace(since_ns=t0) if e.frame.can_id == 0x601]
    assert subs[0] == 0x35 and subs[1] == 0x40 and set(subs[2:-1]) == {0x42} and subs[-1] == 0x36
    assert r["POLLS"] == len(subs) - 3 >= 1

    assert b.fb("CDA").run().done
    assert b.drive.curves.ram == {}
    assert b.fb("RST").run().done
    assert list(b.drive.curves.ram[23].info) == info


def test_flash_save_refused_while_mc_runs(b):
    r = b.fb("FS").run(CURVES=True, MANAGEMC=False)
    assert r.error and r.error_id == E["ResultMcNotStopped"]          # D7h


def test_flash_save_needs_a_selection(b):
    r = b.fb("FS").run(CURVES=False, COMMANDTABLE=False)
    assert r.error and r.error_id == E["NothingSelected"] and r.scans == 1


def test_aborted_download_blocks_the_curve_id_until_delete_all(b):
    """An aborted download leaves the curve open on the drive: the ID answers D4h (ResultObjectState) to a new
    add, and is not present for a get, until "delete all curves" (41h); then the download works again."""
    info, setpoints = info_of(SEED), SEED["setpoints"]
    b.set_setpoints(setpoints)
    ca = b.fb("CA")
    ca.start(CURVEID=23, INFO=info, DATASIZE=40)
    b.step(5)
    ca["ABORT"] = True
    b.step(1)
    assert ca["COMMANDABORTED"]
    ca.set(EXECUTE=False, ABORT=False)
    b.step(1)
    assert add(b, 23, info, setpoints).error_id == E["ResultObjectState"]
    assert b.fb("CG").run(CURVEID=23).error_id == E["ResultObjectState"]
    assert b.fb("CDA").run().done                                       # the recovery: delete all ...
    assert add(b, 23, info, setpoints).done                              # ... and download again
    assert b.drive.curves.ram[23].setpoints == setpoints
