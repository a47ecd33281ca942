"""The ST side of the commissioning and the Python side agree: the ErrorIDs (in the library's one table),
the dataset format constants (T_LmDsFormat vs linmot_st.pvl.dataset), and the library's rules for
MatIEC (no FOR loop, every file included by st_lib/linmot.st)."""

from __future__ import annotations

import re

from linmot_st.protocol import errors
from linmot_st.pvl import dataset as dsf
from repo_paths import REPO

ST = REPO / "st_lib" / "commission"


def test_commissioning_error_ids_are_in_the_library_table():
    # one table for every ErrorID (tests/protocol/test_protocol_generate.py checks the generated ST and docs against it)
    assert errors.describe(0x0603).startswith("16#0603 read-back differs")
    assert errors.name_of(0x0602) == "ResetNeedsFlash"
    assert {"DatasetInvalid", "ResetNeedsFlash", "VerifyMismatch"} <= set(errors.BY_NAME)
    body = "\n".join(f.read_text() for f in sorted(ST.glob("*.st")))
    for e in errors.ERRORS:  # the FB and its phases name their ErrorIDs (E.<Name>), never write their numbers
        assert not re.search(rf"(Err|ErrorID)\s*:=\s*16#{e.value:04X}\b", body, re.I), e.name


def test_dataset_format_constants_agree():
    text = (ST / "types.st").read_text()
    fmt = dict(re.findall(r"^\s*(\w+)\s*:\s*\w+\s*:=\s*(16#[0-9A-Fa-f]+|\d+);", text.split("T_LmDsFormat")[1].split("END_STRUCT")[0], re.M))
    value = {k: int(v.replace("16#", ""), 16) if v.startswith("16#") else int(v) for k, v in fmt.items()}
    assert value == {
        "Magic": dsf.MAGIC, "Version": dsf.VERSION, "HeaderWords": dsf.HEADER_WORDS,
        "TagLayer": dsf.TAG_LAYER, "TagParam": dsf.TAG_PARAM, "TagCurve": dsf.TAG_CURVE, "TagEntry": dsf.TAG_ENTRY,
        "TagEnd": dsf.TAG_END, "InfoWords": dsf.INFO_WORDS, "EntryWords": dsf.ENTRY_WORDS,
        "MaxSetpoints": dsf.MAX_SETPOINTS,
    }


def test_matiec_rules():
    entry = (REPO / "st_lib" / "linmot.st").read_text()
    for f in sorted(ST.glob("*.st")):
        assert f'{{#include "st_lib/commission/{f.name}"}}' in entry
        code = re.sub(r"\(\*.*?\*\)", "", f.read_text(), flags=re.S)
        assert not re.search(r"\bFOR\b", code), f"{f.name}: FOR loops miscompile in MatIEC HEAD (spec/matiec.md 7)"
        assert not re.search(r"\bSTEP\b", code, re.I), f"{f.name}: STEP is an SFC keyword"
    for f in sorted((REPO / "plc_project").glob("*.st")):
        code = re.sub(r"\(\*.*?\*\)", "", f.read_text(), flags=re.S)
        assert not re.search(r"\bFOR\b", code)


def test_one_file_per_phase_of_the_commissioning_fb():
    """FB_LmCommission is the sequencer (commission.st); each phase of E_LmComPhase but IDLE and DONE is one file
    phase_<name>.st of FUNCTIONs F_LmCom<Phase>..., and docs/commissioning.md's phase table names it."""
    types = re.sub(r"\(\*.*?\*\)", "", (ST / "types.st").read_text(), flags=re.S)
    enum = re.search(r"E_LmComPhase\s*:\s*\((.*?)\)", types, re.S).group(1)
    phases = [p.strip()[len("LM_COM_"):] for p in enum.split(",")]
    assert phases[0] == "IDLE" and phases[-1] == "DONE"
    phases = phases[1:-1]
    assert len(phases) == 11
    files = {f.name for f in ST.glob("phase_*.st")}
    assert files == {f"phase_{p.lower()}.st" for p in phases}
    docs = (REPO / "docs" / "commissioning.md").read_text()
    for p in phases:
        assert f"| {p} | `phase_{p.lower()}.st` |" in docs, p
        code = (ST / f"phase_{p.lower()}.st").read_text()
        pous = re.findall(r"^(FUNCTION_BLOCK|FUNCTION)\s+(\w+)", code, re.M)
        assert pous and all(kind == "FUNCTION" and name.startswith("F_LmCom") for kind, name in pous), (p, pous)
    sequencer = (ST / "commission.st").read_text()
    assert re.findall(r"^FUNCTION_BLOCK\s+(\w+)", sequencer, re.M) == ["FB_LmCommission"]
    assert not re.findall(r"^FUNCTION\s", sequencer, re.M)


def test_pvl_docs_and_help_name_every_module_and_command(capsys):
    """docs/pvl.md's module table lists every module of linmot_st.pvl (dataset.py and to_st.py included), and
    `linmot-st pvl --help` every command."""
    import pytest

    from linmot_st.cli import main
    from linmot_st.pvl.cli import COMMANDS

    table = (REPO / "docs" / "pvl.md").read_text().split("## Modules", 1)[1]
    for module in sorted((REPO / "harness" / "linmot_st" / "pvl").glob("*.py")):
        if module.name != "__init__.py":
            assert f"| `{module.name}` |" in table, module.name
    assert "will be one more entry" not in (REPO / "docs" / "pvl.md").read_text()
    with pytest.raises(SystemExit):
        main(["pvl", "--help"])
    help_text = capsys.readouterr().out
    for name, *_ in COMMANDS:
        assert f"    {name} " in help_text, name
    with pytest.raises(SystemExit):
        main(["--help"])
    top = " ".join(capsys.readouterr().out.split())
    assert "LinMot PVL files: show a summary, generate the PLC's dataset (to-st)" in top
