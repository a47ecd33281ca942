"""Replays the shared SDO test vectors (tests/vectors/sdo_frames.json) against the emulated drive twice:

- through the sans-I/O API in virtual time (DirectLink): every request gets exactly the response bytes listed,
  at the time listed;
- as an independent client would see it: the drive served in real time on python-can's `virtual` bus
  (`drive.attach`), hand-built raw frames sent from another Bus object on the same channel. Every response is
  checked byte for byte; only the virtual-time timing checks are left out (the drive runs with short timings).

Both replays must exercise every service, result code and abort code the emulator uses.
"""

from __future__ import annotations

import functools
import json
import time

import pytest

import repo_paths
from linmot_st.bus import Frame
from linmot_st.emulator import DriveTimings, E1100Drive, ErrorEntry, ErrorLog, build_entry, load_profile
from linmot_st.emulator.testing import DirectLink, ServedDrive
from shared_vectors import seed_curve

VECTORS = json.loads((repo_paths.VECTORS / "sdo_frames.json").read_text())
S = 1_000_000_000
MS = 1_000_000
TOLERANCE_NS = 1_000_000



def make_drive(kind: str, timings: DriveTimings | None = None) -> E1100Drive:
    if kind == "default":
        return E1100Drive(1, timings=timings)
    if kind == "error_log_example":
        entries = [ErrorEntry(0x20 + k, 1000 * k, 900 + k) for k in range(21)]
        entries[5] = ErrorEntry(0x64, 10433, 920)
        profile = load_profile().with_defaults({0x1194: 2})
        return E1100Drive(1, profile, timings, error_log=ErrorLog(21, entries, occurred=52))
    if kind == "seed_curve_23_in_flash":
        d = E1100Drive(1, timings=timings)
        d.curves.flash[23] = seed_curve(23)
        return d
    if kind == "ct_entry_5_in_flash":
        d = E1100Drive(1, timings=timings)
        params = (500000).to_bytes(4, "little", signed=True) + (1000000).to_bytes(4, "little") * 3
        d.ct.flash[5] = build_entry(0x0101, params, name="GoTo50mm")
        return d
    if kind == "long_device_name":
        return E1100Drive(1, load_profile().with_identity(device_name="LinMot E1100-CO-HC"), timings)
    raise AssertionError(f"unknown drive setup {kind}")


def expected_exchanges(vector) -> list[tuple[bytes, bytes | None]]:
    return [(bytes.fromhex(s["request"]), None if s["response"] is None else bytes.fromhex(s["response"]))
            for s in vector["steps"] if "request" in s]


def coverage(exchanges) -> tuple[set[int], set[int], set[int]]:
    """(services answered without an abort, result codes in byte 6 of 60h answers, abort codes) of
    (request, response) pairs. Sub-index 0 ("number of entries") is not a service."""
    services, results, aborts = set(), set(), set()
    for req, resp in exchanges:
        if resp is None:
            continue
        if len(req) >= 4 and 0x2000 <= req[1] | req[2] << 8 <= 0x5FFF and req[3] and resp[0] in (0x60, 0x43):
            services.add(req[3])
        if resp[0] == 0x60:
            results.add(resp[6])
        if resp[0] == 0x80:
            aborts.add(int.from_bytes(resp[4:8], "little"))
    return services, results, aborts


def emulator_codes() -> tuple[set[int], set[int], set[int]]:
    from linmot_st.emulator.linmot.manufacturer import E1100_SERVICES
    from linmot_st.protocol import codes

    return {s.sub for s in E1100_SERVICES}, set(codes.RESULT_NAMES), set(codes.DRIVE_ABORTS)


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
    exchanges = [x for v in VECTORS["vectors"] for x in expected_exchanges(v)]
    assert coverage(exchanges) == emulator_codes()


# --- the same vectors over python-can's virtual bus, from an independent raw client --------------------------

# Short timings so that the replay takes seconds; the flash save stays long enough (250 ms) for the vectors'
# "busy" polls that follow its start, and short enough for their 0.4 s wait, on a loaded machine.
BUS_TIMINGS = DriveTimings.fast(boot_ns=2 * MS, flash_base_ns=250 * MS, flash_per_kib_ns=0)
ANSWER_TIMEOUT_S = 5.0      # generous: the server thread may be delayed on a loaded 2-core machine
NO_ANSWER_S = 0.1           # how long "no answer" is waited for; a late answer would fail the next step


def replay_on_virtual_bus(vector) -> list[tuple[bytes, bytes | None]]:
    """Serve the vector's drive on a fresh virtual channel and replay the steps with raw frames; returns the
    (request, response) pairs observed. Raises AssertionError when an expected frame does not come."""
    observed = []
    with ServedDrive(make_drive(vector["drive"], BUS_TIMINGS)) as served:
        client = served.client
        for n, step in enumerate(vector["steps"]):
            if "nmt" in step:
                client.send(0x000, step["nmt"])
            elif "wait_s" in step:
                time.sleep(step["wait_s"])
            elif "expect_frame" in step:
                want = (int(step["expect_frame"], 16), bytes.fromhex(step["data"]))
                got = client.wait_for(lambda m: (m.arbitration_id, bytes(m.data)) == want,
                                      step["after_s"] + ANSWER_TIMEOUT_S)
                assert got is not None, f"step {n}: no {step['expect_frame']}#{step['data']}"
            else:
                timeout = NO_ANSWER_S if step["response"] is None else ANSWER_TIMEOUT_S
                answer = client.exchange(step["request"], timeout)
                if step.get("virtual_time") == "bytes 4..7" and answer is not None:
                    # a time stamp in ms of the drive's own clock (here the wall clock since attach): check it
                    # lies in the run so far, then compare the rest of the frame with the vector's
                    ms = int.from_bytes(answer[4:8], "little")
                    assert BUS_TIMINGS.boot_ns // MS <= ms <= 60_000, f"step {n}: time stamp {ms} ms"
                    answer = answer[:4] + bytes.fromhex(step["response"])[4:8]
                observed.append((bytes.fromhex(step["request"]), answer))
    return observed


@functools.cache
def bus_replay() -> dict[str, tuple[list, str | None]]:
    """Every vector replayed once per test process: name -> (observed pairs, problem or None)."""
    results = {}
    for vector in VECTORS["vectors"]:
        try:
            results[vector["name"]] = (replay_on_virtual_bus(vector), None)
        except Exception as exc:  # noqa: BLE001 - reported by the vector's test
            results[vector["name"]] = ([], f"{type(exc).__name__}: {exc}")
    return results


@pytest.mark.parametrize("vector", VECTORS["vectors"], ids=lambda v: v["name"])
def test_vector_on_the_virtual_bus(vector):
    observed, problem = bus_replay()[vector["name"]]
    assert problem is None, problem
    expected = expected_exchanges(vector)
    for (req, want), (_, got) in zip(expected, observed):
        assert got == want, f"{req.hex(' ')}: got {got.hex(' ') if got else got}, want {want.hex(' ') if want else want}"
    assert len(observed) == len(expected)


def test_the_virtual_bus_replay_exercises_every_service_result_and_abort_code():
    observed = [x for pairs, _ in bus_replay().values() for x in pairs]
    assert coverage(observed) == emulator_codes()
