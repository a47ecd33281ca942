"""The commissioning over a real Linux SocketCAN stack (vcan0): the emulated drive served by `linmot-st emulate`
in one process, the PLC in another (`linmot-st commission --bus socketcan:vcan0 --no-emulate`), can-utils'
candump recording the bus. Run inside a User-Mode Linux guest where this kernel has no vcan0
(linmot_st_vcan.pytest_plugin); docs/bus.md, "A real SocketCAN stack"."""

from __future__ import annotations

import pytest

from linmot_st.jobs.commission.runner import RunOptions
from linmot_st.jobs.commission.testing import EXAMPLE, commission, example
from linmot_st.jobs.commission.verify import drive_state, verify
from linmot_st_vcan.testing import Candump, EmulatedDrives, linmot_st, sdo_frames, without_busy_polls

pytestmark = pytest.mark.socketcan

# the command's defaults (flash, reset, verify): what `linmot-st commission` does unless told otherwise
COMMAND_OPTIONS = dict(flash=True, reset=True, verify=True, timings="fast", force=False)   # the CLI's defaults


def commission_over(bus: str, *args: str):
    return linmot_st("commission", str(EXAMPLE), "--bus", bus, "--no-emulate", "-q", *args)


def test_one_drive_served_by_another_process_is_commissioned_and_recorded_by_candump(tmp_path):
    with EmulatedDrives([1], tmp_path) as drives:
        with Candump(tmp_path / "bus.log") as dump:
            res = commission_over("socketcan:vcan0")
    assert res.returncode == 0 and "result: PASSED" in res.stdout, res.stdout + res.stderr
    assert drives.clean_exit() == ""
    pvl = example()
    verification = verify(pvl, drives.drives(), RunOptions(bus="socketcan:vcan0", **COMMAND_OPTIONS))
    assert verification.ok, [c for c in verification.checks if not c.ok]

    # the same dataset on the simulated bus: the same memory, and the same SDO frames in the same order
    sim = commission(**COMMAND_OPTIONS)
    assert sim.result.commissioned and sim.verification.ok
    assert drive_state(drives.drive(1)) == drive_state(sim.result.drives[1])
    recorded = without_busy_polls(sdo_frames(dump.messages(), 1))
    simulated = without_busy_polls(sdo_frames((e.frame for e in sim.result.trace if e.status == "ok"), 1))
    assert len(recorded) == len(simulated) > 2000
    first = next((k for k, (a, b) in enumerate(zip(recorded, simulated)) if a != b), None)
    assert first is None, f"frame {first}: candump {recorded[first]}, simulated bus {simulated[first]}"


def test_two_drives_on_one_bus_each_served_by_its_own_process(tmp_path):
    with EmulatedDrives([1, 2], tmp_path) as drives:
        res = commission_over("socketcan:vcan0", "--axes", "2")
    assert res.returncode == 0 and "result: PASSED (2 axes commissioned and verified)" in res.stdout, \
        res.stdout + res.stderr
    assert drives.clean_exit() == ""
    verification = verify(example(), drives.drives(), RunOptions(axes=2, bus="socketcan:vcan0", **COMMAND_OPTIONS))
    assert verification.ok and {c.node for c in verification.checks} == {1, 2}, \
        [c for c in verification.checks if not c.ok]
    sim = commission(axes=2, **COMMAND_OPTIONS)
    assert sim.verification.ok
    for node in (1, 2):
        assert drive_state(drives.drive(node)) == drive_state(sim.result.drives[node])


def test_the_motion_job_on_vcan0(tmp_path):
    """`linmot-st motion` over vcan0: commissioning, then power, home, moves, the curves, a command-table entry
    and the stop, every process-data frame (RxPDOs, TxPDOs) through the kernel's CAN stack in real time; the
    job's own checks (targets, the curves as written, on the emulated drive's trajectory) must pass."""
    with Candump(tmp_path / "bus.log") as dump:
        res = linmot_st("motion", str(EXAMPLE), "--bus", "socketcan:vcan0", "--drive-timings", "fast", "-q",
                        "--report", str(tmp_path / "report"))
    assert res.returncode == 0 and "PASSED" in res.stdout, res.stdout + res.stderr
    ids = {m.arbitration_id for m in dump.messages()}
    assert {0x181, 0x281, 0x201, 0x301, 0x401} <= ids, sorted(hex(i) for i in ids)   # the PDOs were on vcan0



def test_one_b1100_served_by_another_process_is_commissioned_through_the_selection(tmp_path):
    """`linmot-st emulate --drive B1100` at its default node ID 63; the PLC commissions it from the B1100 file
    (its axis' Drive from the file's series): every parameter access on the bus is 2000h sub C0h, then 01h/02h."""
    from pathlib import Path

    from linmot_st.pvl import load_pvl

    b1100_file = Path(EXAMPLE).with_name("b1100_axis.pvl")
    with EmulatedDrives([63], tmp_path, model="B1100") as drives:
        with Candump(tmp_path / "bus.log") as dump:
            res = linmot_st("commission", str(b1100_file), "--bus", "socketcan:vcan0", "--no-emulate", "-q",
                            "--node-ids", "63")
    assert res.returncode == 0 and "result: PASSED" in res.stdout, res.stdout + res.stderr
    assert drives.clean_exit() == ""
    verification = verify(load_pvl(b1100_file), drives.drives(),
                          RunOptions(bus="socketcan:vcan0", node_ids=[63], **COMMAND_OPTIONS))
    assert verification.ok, [c for c in verification.checks if not c.ok]
    requests = [data for cob, data in sdo_frames(dump.messages(), 63) if cob == 0x600 + 63]
    assert requests and all(data[1:3] == b"\x00\x20" or int.from_bytes(data[1:3], "little") < 0x2000
                            for data in requests)
    accesses = [k for k, data in enumerate(requests) if data[1:4] in (b"\x00\x20\x01", b"\x00\x20\x02")]
    assert accesses and all(requests[k - 1][1:4] == b"\x00\x20\xC0" for k in accesses)
