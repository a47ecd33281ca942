"""The ErrorID numbers: one table (linmot_st.protocol.errors) from which st_lib/types/errors.st and the table
in docs/st-library.md are generated (tests/protocol/test_protocol_generate.py checks that they are current); this test
checks the numbers the compiled library actually holds."""

from __future__ import annotations

from linmot_st.protocol import errors, generate
from stbench import bench_build


def test_st_file_holds_every_number():
    parsed = generate.parse_st((generate.REPO / "st_lib/types/errors.st").read_text())
    assert parsed == {e.name: e.value for e in errors.ERRORS}


def test_numbers_and_names_unique():
    values = [e.value for e in errors.ERRORS]
    assert len(values) == len(set(values))
    names = [e.name.upper() for e in errors.ERRORS]        # ST identifiers are case-insensitive
    assert len(names) == len(set(names))
    for e in errors.ERRORS:
        assert 0 <= e.value <= 0xFFFF and e.value >> 8 in (0, 1, 2, 3, 4, 5, 6, 7), e


def test_compiled_library_holds_the_same_numbers():
    from linmot_st.plc import Plc
    plc = Plc(bench_build())
    compiled = plc["BENCH.RD.E"]                           # T_LmErrorIds of an FB instance
    assert {k.upper(): v for k, v in compiled.items()} == {e.name.upper(): e.value for e in errors.ERRORS}


def test_describe():
    assert errors.describe(0x0104).startswith("16#0104 curve ID outside 1..100")
    assert "D4h" in errors.describe(0x04D4)
    assert errors.describe(0x04AB) == "16#04AB E1100 result code ABh"
    assert "06010002h attempt to write a read only object" in errors.describe(0x0302, 0x06010002)
    assert errors.name_of(0x04AB) == "ResultABh"
    assert errors.describe(0x7777).startswith("unknown")


def test_drive_error_table_generates_the_st_constants():
    """T_LmDriveErrors / F_LmDriveErrorText come from the drive's error table (emulator/data), which the emulator
    answers its error texts from and takes its fatal codes from: one table for the drive and the library."""
    from linmot_st.emulator import load_profile
    from linmot_st.protocol import words

    text = (generate.REPO / "st_lib/motion/drive_errors.st").read_text()
    assert text == generate.render_drive_st()
    for d in errors.DRIVE_ERRORS:
        assert f"{d.name.ljust(1)}" in text and f"16#{d.code:04X}" in text
    assert load_profile().error_texts == {d.code: d.text for d in errors.DRIVE_ERRORS}
    assert words.FATAL_ERRORS == {d.code for d in errors.DRIVE_ERRORS if d.fatal}
    assert {0x000B, 0x0062, 0x0080, 0x0081, 0x0086, 0x0089, 0x008A} <= set(errors.DRIVE_ERRORS_BY_CODE)
