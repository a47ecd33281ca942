"""The benchmark client (RequestLoop) and the emulator benchmark's reporting (best of several runs, load)."""

import pytest

from linmot_st.bus import Frame
from linmot_st.emulator import E1100Drive
from linmot_st_bench.bus import EchoSdoServer, RequestLoop, run_loop

READ = Frame(0x601, bytes.fromhex("40 A2 33 01 00 00 00 00"))
WRITE = Frame(0x601, bytes.fromhex("23 A2 33 01 64 00 00 00"))


def test_request_loop_keeps_one_request_outstanding_against_the_drive():
    drive = E1100Drive(1)
    drive.power_on(0)
    client = RequestLoop([READ, WRITE], 0x581, 6, expect=(0x43, 0x60), keep=True)
    run_loop(drive, client, settle_ns=drive.timings.boot_ns + 10_000_000)
    assert [a[0] for a in client.kept] == [0x43, 0x60] * 3
    assert client.kept[2] == bytes.fromhex("43 A2 33 01 64 00 00 00")     # the write landed before the next read
    assert client.start_ns == drive.timings.boot_ns + 10_000_000 and client.end_ns > client.start_ns


def test_a_broken_loop_is_an_error():
    silent = E1100Drive(1)                                               # never powered on: answers nothing
    with pytest.raises(RuntimeError, match="0/3 answers"):
        run_loop(silent, RequestLoop([READ], 0x581, 3))
    with pytest.raises(RuntimeError, match="3 unexpected"):
        run_loop(EchoSdoServer(1), RequestLoop([READ], 0x581, 3, expect=(0x60,)))


def test_emulator_bench_reports_the_best_run_and_the_load(monkeypatch):
    from linmot_st_bench import emulator as bench

    rates = iter([30_000.0, 70_000.0, 50_000.0, 20_000.0, 60_000.0])
    monkeypatch.setattr(bench, "measure_bus_exchanges", lambda: next(rates))
    monkeypatch.setattr(bench, "measure_direct", lambda: 1.0)
    monkeypatch.setattr(bench.os, "getloadavg", lambda: (1.5, 1.0, 0.5))
    rows = {r["name"].split(",")[0]: r for r in bench.run()}
    top = rows["emulator on the simulated bus (500 kbit/s): expedited parameter read/write exchanges"]
    assert top["value"] == 70_000 and "best of 5 runs" in top["name"] and top["target"] == ">= 50000"
    load = next(r for n, r in rows.items() if "load average" in n)
    assert load["value"] == 1.5
