"""Replays the shared SDO test vectors (tests/vectors/sdo_frames.json) against the emulated drive, through the
sans-I/O API in virtual time: every request must get exactly the response bytes listed, at the time listed."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from linmot_st.bus import Frame
from linmot_st.emulator import Curve, E1100Drive, ErrorEntry, ErrorLog, build_entry, load_profile
from linmot_st.emulator.testing import DirectLink

VECTORS = json.loads((Path(__file__).parent / "vectors" / "sdo_frames.json").read_text())
S = 1_000_000_000
TOLERANCE_NS = 1_000_000

SEED_INFO_WORDS = [0x00030046, 0x0004000A, 0x6D617845, 0x5F656C70, 0x76727543, 0x00000065, 0x00000000,
                   0x00170000, 0x00004E20, 0x0005001A, 0x4E200301, 0x00000000, 0x42400000, 0x0000000F, 0, 0, 0, 0]
SEED_DATA_WORDS = [0x00000000, 0x000075CA, 0x0001C8F2, 0x0003D090, 0x00064DF8, 0x0008F448, 0x000B71B0,
                   0x000D794E, 0x000ECC76, 0x000F4240]


def seed_curve_23() -> Curve:
    info = b"".join(w.to_bytes(4, "little") for w in SEED_INFO_WORDS)[:70]
    return Curve(23, info, b"".join(w.to_bytes(4, "little") for w in SEED_DATA_WORDS))


def make_drive(kind: str) -> E1100Drive:
    if kind == "default":
        return E1100Drive(1)
    if kind == "error_log_example":
        entries = [ErrorEntry(0x20 + k, 1000 * k, 900 + k) for k in range(21)]
        entries[5] = ErrorEntry(0x64, 10433, 920)
        profile = load_profile().with_defaults({0x1194: 2})
        return E1100Drive(1, profile, error_log=ErrorLog(21, entries, occurred=52))
    if kind == "seed_curve_23_in_flash":
        d = E1100Drive(1)
        d.curves.flash[23] = seed_curve_23()
        return d
    if kind == "ct_entry_5_in_flash":
        d = E1100Drive(1)
        params = (500000).to_bytes(4, "little", signed=True) + (1000000).to_bytes(4, "little") * 3
        d.ct.flash[5] = build_entry(0x0101, params, name="GoTo50mm")
        return d
    if kind == "long_device_name":
        return E1100Drive(1, load_profile().with_identity(device_name="LinMot E1100-CO-HC"))
    raise AssertionError(f"unknown drive setup {kind}")


def test_every_vector_names_a_known_drive_setup():
    assert set(VECTORS["drives"]) == {v["drive"] for v in VECTORS["vectors"]} | {"default"}


@pytest.mark.parametrize("vector", VECTORS["vectors"], ids=lambda v: v["name"])
def test_vector(vector):
    link = DirectLink(make_drive(vector["drive"]))
    for n, step in enumerate(vector["steps"]):
        where = f"{vector['name']} step {n}: {step.get('note') or step}"
        if "nmt" in step:
            link.send(Frame(0x000, bytes.fromhex(step["nmt"])))
            link.advance(1_000_000)
        elif "wait_s" in step:
            link.advance(int(step["wait_s"] * S))
        elif "expect_frame" in step:
            t0, after = link.t, int(step["after_s"] * S)
            want = Frame(int(step["expect_frame"], 16), bytes.fromhex(step["data"]))
            got = link.wait_for(lambda f: f == want, after + TOLERANCE_NS)
            assert got == want, where
            assert abs(link.t - t0 - after) <= TOLERANCE_NS, where
        else:
            t0 = link.t
            answer = link.sdo(step["request"], timeout_ns=int(step.get("response_after_s", 0) * S) + 50_000_000)
            expected = None if step["response"] is None else bytes.fromhex(step["response"])
            assert answer == expected, f"{where}: got {answer.hex(' ') if answer else answer}"
            if "response_after_s" in step:
                assert abs(link.t - t0 - int(step["response_after_s"] * S)) <= TOLERANCE_NS, where


def test_vectors_cover_every_service_result_and_abort_code():
    from linmot_st.emulator import codes
    from linmot_st.emulator.manufacturer import SERVICES

    subs, results, aborts = set(), set(), set()
    for v in VECTORS["vectors"]:
        for s in v["steps"]:
            if "request" not in s:
                continue
            req = bytes.fromhex(s["request"])
            if len(req) >= 4 and 0x2000 <= req[1] | req[2] << 8 <= 0x5FFF:
                subs.add(req[3])
            if s["response"]:
                resp = bytes.fromhex(s["response"])
                if resp[0] == 0x60:
                    results.add(resp[6])
                if resp[0] == 0x80:
                    aborts.add(int.from_bytes(resp[4:8], "little"))
    assert set(SERVICES) <= subs
    assert set(codes.RESULT_NAMES) <= results
    assert set(codes.ABORT_NAMES) <= aborts
