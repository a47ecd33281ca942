"""The ST encoder F_LmMotionEncode (st_lib/motion/codec_gen.st, generated from the catalogue) encodes every row
of issue 20 section 3 as the Python codec does: each row with extreme field values (sign and width of every
field), and the hand-written vectors tests/vectors/motion_commands_vai.json."""

from __future__ import annotations

import json

import pytest

from catalogue_programs import NEW_ROWS, encoder_program
from linmot_st.protocol import commands as C
from repo_paths import VECTORS
from stbench import available_backends

# the extremes of each IEC type that the encoder's DINT inputs can carry
EXTREMES = {"INT": (-32768, 32767), "UINT": (0, 65535), "DINT": (-2**31, 2**31 - 1), "UDINT": (0, 2**31 - 1)}


def _cases() -> list[tuple[int, int, dict]]:
    cases = []
    for i, cid in enumerate(NEW_ROWS):
        fields = C.COMMANDS[cid].fields
        for pick in (0, 1):
            cases.append((cid, (i + pick) % 16, {f.name: EXTREMES[f.type][(pick + k) % 2] for k, f in
                                                  enumerate(fields)}))
    vectors = json.loads((VECTORS / "motion_commands_vai.json").read_text())["vectors"]
    cases += [(int(v["cid"], 16), v["count"], v["fields"]) for v in vectors]
    return cases


@pytest.mark.parametrize("backend", available_backends() or ["none"])
def test_the_library_encoder_encodes_every_new_row(tmp_path, backend):
    if backend == "none":
        pytest.skip("no ST backend")
    from linmot_st import toolchain
    from linmot_st.plc import Plc

    plc = Plc(toolchain.build(str(encoder_program(tmp_path)), backend=backend, root=tmp_path))
    for cid, count, fields in _cases():
        expected = C.encode(cid, count, **fields)
        plc["ENC.CID"], plc["ENC.COUNT"] = cid, count
        for name, value in zip("ABCD", list(fields.values()) + [0] * 4):
            plc[f"ENC.{name}"] = value
        plc.step(1)
        assert plc["ENC.NBYTES"] == len(expected) - 2, f"{cid:03X}h {fields}"
        assert bytes(plc["ENC.IMG"])[:len(expected)] == expected, f"{cid:03X}h {fields}"
