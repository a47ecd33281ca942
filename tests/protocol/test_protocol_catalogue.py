"""The motion-command catalogue (linmot_st/protocol/commands/): its rows are consistent, and a command of an
existing kind is one row: added here (in the test only), the emulated drive executes it and the regenerated ST
encoder encodes it as the Python codec does."""

from __future__ import annotations

import json

import pytest

from catalogue_programs import encoder_program
from linmot_st.emulator import DriveTimings, E1100Drive, load_profile
from linmot_st.emulator.linmot.motion.interpreter import HANDLERS
from linmot_st.emulator.testing import MotionLink
from linmot_st.protocol import commands as C
from linmot_st.protocol import generate
from linmot_st.protocol import words as W
from repo_paths import VECTORS
from stbench import available_backends

MS = 1_000_000
MM = 10_000

# 0E0xh Sin VA Go To Pos ([MC] 4.3.130, spec/linmot-motion-commands.md 1b: target, vmax, acc), a command the
# catalogue does not have; run here as a trapezoid of an existing kind (dec = acc), only to show the mechanism
NEW_ROW = C.CommandDef(0x0E0, "Sin VA Go To Pos", C.COMMANDS[C.VAI_DEC_ACC_GO_TO_POS].fields, C.Kind.VAI_DEC_ACC,
                       needs_homing=True, target=C.Target.ABSOLUTE, source="[MC] 4.3.130")


def test_rows_are_consistent():
    for cid, c in C.COMMANDS.items():
        assert cid == c.cid and 0 <= cid <= 0xFFF
        assert c.kind in HANDLERS, f"{cid:03X}h: no handler for {c.kind}"
        assert len(c.fields) <= 5 and len(set(c.field_names)) == len(c.fields)
        assert c.states and c.states <= C.IN_ANY_STATE and c.drives
        assert c.source.startswith(("[MC] 4.3.", "seed 004 4.3."))     # 004xh: in the seed only
    # system commands run in every state, motion only in Operation Enabled (seed 004 3.7)
    assert {cid for cid, c in C.COMMANDS.items() if c.states == C.IN_ANY_STATE} == {
        C.NOP, C.WRITE_CONTROL_WORD, C.WRITE_LIVE_PARAMETER, C.SELECT_POSITION_CONTROLLER_SET, C.RESET,
        C.WRITE_X4_OUTPUTS, C.WRITE_X6_OUTPUTS, C.CLEAR_EVENT_EVALUATION}
    assert C.COMMANDS[C.VAI_GO_TO_POS].transport is C.Transport.COMMAND_TABLE      # 16 bytes: only in a CT entry
    assert C.COMMANDS[C.VAI16_GO_TO_POS].transport is C.Transport.RXPDO3          # 8 bytes
    assert C.COMMANDS[C.PREDEF_VAI_GO_TO_POS].transport is C.Transport.RXPDO2     # 4 bytes


def test_the_python_codec_against_the_shared_vectors():
    """The vectors the ST encoder is checked against (test_motion_fbs.py) hold for the catalogue's codec too."""
    vectors = json.loads((VECTORS / "motion_commands.json").read_text())["vectors"]
    for v in vectors:
        cid, image = int(v["cid"], 16), bytes.fromhex(v["image"])
        assert C.encode(cid, v["count"], **v["fields"]) == image, v["name"]
        row, fields = C.decode(int.from_bytes(image[:2], "little"), image[2:])
        assert row is C.COMMANDS[cid] and fields == v["fields"], v["name"]
    assert {int(v["cid"], 16) for v in vectors} <= set(C.COMMANDS)


def _homed_link() -> MotionLink:
    d = E1100Drive(1, load_profile().with_defaults({0x1194: 2, 0x2041: 2}), timings=DriveTimings.fast())
    link = MotionLink(d)
    link.enable()
    link.home()
    link.advance(MS)
    return link


MOVE = dict(target=10 * MM, vmax=100_000, acc=100_000)     # 10 mm, 0.1 m/s, 1 m/s^2


def test_without_its_row_the_drive_refuses_0e0h():
    assert 0x0E0 not in C.COMMANDS
    link = _homed_link()
    link.command(0x0E0)                  # the header alone: the catalogue has no layout for it
    link.advance(10 * MS)
    assert link.drive.mc.state == W.ERROR and link.drive.mc.error_code == W.ERR_UNKNOWN_MOTION_CMD


def test_a_new_row_is_executed_by_the_emulated_drive(monkeypatch):
    monkeypatch.setitem(C.COMMANDS, NEW_ROW.cid, NEW_ROW)
    link = _homed_link()
    mc = link.drive.mc
    t0 = link.t
    link.command(0x0E0, **MOVE)
    link.advance(400 * MS)               # a triangle: 2 sqrt(d / a) = 200 ms
    assert mc.state == W.OPERATION_ENABLED and mc.error_code == 0
    assert [h >> 4 for t, h, _ in mc.executed if t >= t0] == [0x0E0]
    assert abs(mc.axis.position - 10 * MM) <= 1000 and mc.in_target
    moving = [s for s in mc.trajectory.between(t0) if s.status_word & W.SW_MOTION_ACTIVE]
    assert 150 * MS <= moving[-1].t_ns - moving[0].t_ns <= 250 * MS


@pytest.mark.parametrize("backend", available_backends() or ["none"])
def test_the_regenerated_st_encoder_encodes_a_new_row(monkeypatch, tmp_path, backend):
    if backend == "none":
        pytest.skip("no ST backend")
    from linmot_st import toolchain
    from linmot_st.plc import Plc

    monkeypatch.setitem(C.COMMANDS, NEW_ROW.cid, NEW_ROW)
    assert "224, " not in (generate.REPO / "st_lib/motion/codec_gen.st").read_text()   # the library has no 0E0h
    plc = Plc(toolchain.build(str(encoder_program(tmp_path)), backend=backend, root=tmp_path))
    cases = [(0x0E0, 5, dict(target=-1234, vmax=100, acc=2_000_000_000)),
             (C.VAI16_GO_TO_POS, 7, dict(target=32767, vmax=1, acc=2, dec=3)),
             (C.TIME_CURVE_OFFSET_TIME_AMP, 3, dict(curve_id=2, offset=-50000, curve_time=12345, amplitude=-1000))]
    for cid, count, fields in cases:
        expected = C.encode(cid, count, **fields)
        plc["ENC.CID"], plc["ENC.COUNT"] = cid, count
        for name, value in zip("ABCDE", list(fields.values()) + [0] * 5):
            plc[f"ENC.{name}"] = value
        plc.step(1)
        assert plc["ENC.NBYTES"] == len(expected) - 2, hex(cid)
        assert bytes(plc["ENC.IMG"])[:len(expected)] == expected, hex(cid)


def test_the_b1100_has_exactly_the_commands_the_seeds_overview_marks():
    """Seed 004 4.2's B1100 column (spec/linmot-b1100.md 3.1): X for every command of master IDs 00h..03h in the
    seed but 004xh; nothing later can be read from the seed, so no later row lists the B1100."""
    from linmot_st.protocol.commands.row import seed_drives
    for cid, row in C.COMMANDS.items():
        assert row.drives == seed_drives(cid), f"{cid:03X}h: {sorted(row.drives)}"
    b1100 = {cid for cid, row in C.COMMANDS.items() if C.B1100 in row.drives}
    assert {0x003, 0x008, 0x01A, 0x02E, 0x030, 0x03F} <= b1100 and not b1100 & {0x004, 0x033, 0x040, 0x090, 0x100}
