"""Commissioning a B1100 (issue 23): `linmot-st commission` on the B1100 example file and on a mixed bus (an
E1100 file on node 1, the B1100 file on node 2), each node's emulated drive of the series its file is for.
Checked in the CAN trace: every B1100 parameter access is a selection (2000h sub C0h) followed by sub 01h/02h,
no B1100 frame addresses 2000h + UPID, and a string's first stringlet lands at UPID + 0 on the B1100 and at
UPID + 1 on the E1100 in the same run."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from linmot_st.cli import main
from repo_paths import EXAMPLES

B1100_FILE, E1100_FILE = EXAMPLES / "b1100_axis.pvl", EXAMPLES / "two_axes.pvl"


def sdo_requests(log: Path, node: int) -> list[bytes]:
    """The data of every SDO request to `node` in a candump trace, in bus order."""
    out = []
    for line in log.read_text().splitlines():
        can_id, _, data = line.split()[2].partition("#")
        if int(can_id, 16) == 0x600 + node:
            out.append(bytes.fromhex(data))
    return out


def index_sub(req: bytes) -> tuple[int, int]:
    return int.from_bytes(req[1:3], "little"), req[3]


def assert_selection_protocol(requests: list[bytes]) -> int:
    """Every access to 2000h sub 01h/02h follows a selection; nothing else of 2000h..5FFFh but 0Bh. Returns
    how many accesses there were."""
    selected, accesses = None, 0
    for req in requests:
        index, sub = index_sub(req)
        if index < 0x2000:
            continue                                           # 1017h (the NMT check)
        assert index == 0x2000, f"a B1100 frame addresses {index:04X}h: {req.hex(' ')}"
        if sub == 0xC0:
            selected = int.from_bytes(req[4:6], "little")
        elif sub in (0x01, 0x02):
            assert selected is not None, f"access without a selection: {req.hex(' ')}"
            accesses += 1
            selected = None                                    # the FB selects before every access
        else:
            assert sub == 0x0B, f"a B1100 request to sub {sub:02X}h: {req.hex(' ')}"
    return accesses


def run(tmp_path: Path, *args: str) -> dict:
    report = tmp_path / "report"
    assert main(["commission", *map(str, args), "--drive-timings", "fast", "--backend", "builtin", "-q",
                 "--report", str(report)]) == 0
    return json.loads((report / "report.json").read_text()) | {"_log": report / "can.log"}


def test_a_b1100_is_commissioned_from_its_file_through_the_selection(tmp_path):
    rep = run(tmp_path, B1100_FILE, "--node-ids", "63")
    requests = sdo_requests(rep["_log"], 63)
    accesses = assert_selection_protocol(requests)
    # 2 layers x 3 identity reads, then per parameter row: compare (ROM read), the writes, verify (ROM read)
    assert accesses >= 6 + 2 * 26
    assert sum(1 for r in requests if index_sub(r) == (0x2000, 0xC0)) == accesses


def test_mixed_bus_strings_at_upid_plus_0_and_plus_1(tmp_path):
    rep = run(tmp_path, E1100_FILE, "--axes", "2", "--pvl", f"2={B1100_FILE}")
    e1100, b1100 = sdo_requests(rep["_log"], 1), sdo_requests(rep["_log"], 2)
    assert_selection_protocol(b1100)
    # User Comment: E1100 string 03F2h, its first stringlet 03F3h ("X Ax"); B1100 string 7078h ("Y Ax")
    assert bytes.fromhex("23 F3 23 02 58 20 41 78") in e1100 or bytes.fromhex("23 F3 23 06 58 20 41 78") in e1100
    select = bytes.fromhex("23 00 20 C0 78 70 00 00")
    writes = [b for a, b in zip(b1100, b1100[1:]) if a == select and b[0] == 0x23]
    assert writes == [bytes.fromhex("23 00 20 02 59 20 41 78")]      # ROM write of stringlet 1 at 7078h
    assert not any(0x2001 <= index_sub(r)[0] <= 0x5FFF for r in b1100)


def test_drive_option_overrides_the_series_of_the_file(tmp_path, capsys):
    """`--drive 1=E1100` on a B1100 file: the series check refuses before any write, naming both."""
    code = main(["commission", str(B1100_FILE), "--drive", "1=E1100", "--drive-timings", "fast", "-q",
                 "--backend", "builtin"])
    assert code != 0
    err = capsys.readouterr().err
    assert "for a B1100" in err and "is an E1100" in err


@pytest.mark.parametrize("bad", ["1", "x=B1100", "1=B9"])
def test_drive_option_refuses_bad_values(bad, capsys):
    with pytest.raises(SystemExit):
        main(["commission", str(B1100_FILE), "--drive", bad])
    assert "--drive" in capsys.readouterr().err


def test_the_report_bound_counts_the_selection_exchanges(tmp_path):
    """A full write (--force) of the B1100 file: 2 layers x 3 reads, 26 ROM writes, 26 verify reads, each a
    selection and an access: the transfer phases make exactly the necessary exchanges."""
    from linmot_st.pvl import load_pvl
    from linmot_st.pvl.dataset import expected_exchanges, from_pvl

    ds = from_pvl(load_pvl(B1100_FILE))
    assert ds.drive == "B1100" and len(ds.params) == 26 and len(ds.layers) == 2
    assert expected_exchanges(ds) == 2 * (6 + 26 + 26)
    rep = run(tmp_path, B1100_FILE, "--force")
    assert rep["transfer"]["exchanges"] == rep["transfer"]["necessary_exchanges"] == expected_exchanges(ds)
    assert rep["run"]["necessary_exchanges"] == expected_exchanges(ds) + 1        # + the reset request


def test_motion_moves_an_e1100_and_a_b1100_on_one_bus(tmp_path, capsys):
    """`linmot-st motion` with per-node files: both axes are commissioned, set up, powered, homed, moved to
    50 mm and stopped; the E1100's curves and command table are not run (the B1100 has none), and say so."""
    report = tmp_path / "report"
    assert main(["motion", str(E1100_FILE), "--axes", "2", "--pvl", f"2={B1100_FILE}", "--backend", "builtin",
                 "-q", "--report", str(report)]) == 0
    out = capsys.readouterr().out
    assert "motion job: PASSED: 2 axis/axes, 6 steps each" in out
    assert "not run: curve 1 MinJerk_100mm_400ms: not on every axis" in out
    assert "node 2: parameters ROM 26/26, parameters RAM 26/26: OK" in out
    motion = json.loads((report / "motion.json").read_text())
    b1100 = sdo_requests(report / "can.log", 2)
    assert_selection_protocol(b1100)
    assert motion


def test_mixed_bus_on_pythons_can_virtual_bus(tmp_path):
    """The same mixed run in real time on python-can's virtual bus (fast drive timings)."""
    import uuid
    rep = run(tmp_path, E1100_FILE, "--axes", "2", "--pvl", f"2={B1100_FILE}",
              "--bus", f"virtual:linmot-st-b1100-{uuid.uuid4().hex[:8]}")
    assert rep["result"]["passed"]
    assert_selection_protocol(sdo_requests(rep["_log"], 2))


def test_rig_with_a_model_per_node():
    """The plctest rig builds node 1 an E1100 and node 2 a B1100 ({node: model})."""
    from linmot_st.plctest.rig import model_of

    models = {2: "B1100"}
    assert (model_of(models, 1), model_of(models, 2), model_of("B1100", 5)) == ("E1100", "B1100", "B1100")


def test_ram_and_rom_through_one_selection_with_live_ram(tmp_path):
    """--live-ram on a B1100 (no 06h): each parameter is selected, then written to RAM (01h) and ROM (02h); with
    --no-reset the RAM holds the file's values at once."""
    from linmot_st.pvl import load_pvl
    from linmot_st.pvl.dataset import expected_exchanges, from_pvl

    ds = from_pvl(load_pvl(B1100_FILE))
    rep = run(tmp_path, B1100_FILE, "--force", "--live-ram", "--no-reset")
    assert rep["transfer"]["exchanges"] == expected_exchanges(ds, live_ram=True) == 2 * (6 + 26 + 26) + 26
    requests = sdo_requests(rep["_log"], 1)
    writes = [k for k, r in enumerate(requests) if r[0] == 0x23 and index_sub(r) == (0x2000, 0x01)]
    assert len(writes) == 26
    for k in writes:
        assert index_sub(requests[k - 1]) == (0x2000, 0xC0)
        assert index_sub(requests[k + 1]) == (0x2000, 0x02) and requests[k + 1][4:8] == requests[k][4:8]
