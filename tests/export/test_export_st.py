"""`linmot-st export st`: the library as one ST file that Beremiz and OpenPLC accept.

The exported file must hold no include pragma, start with a header comment (version, sources), keep every
source line in include order, and compile to the same thing as the library: the same manifest with the
builtin backend, and byte-identical C from MatIEC's iec2c (where it is installed).
"""

from __future__ import annotations

import json
import re
import subprocess
import textwrap
from pathlib import Path

import pytest

from linmot_st.cli import main as cli_main
from linmot_st.export import ExportError, export_st, read_library
from linmot_st.export.st import package_version
from linmot_st.toolchain import build, sources
from linmot_st.toolchain import matiec as matiec_mod
from linmot_st.toolchain.testing import MATIEC_MISSING
from repo_paths import REPO

LIBRARY = REPO / "st_lib" / "linmot.st"
MATIEC = matiec_mod.find()
requires_iec2c = pytest.mark.skipif(MATIEC is None, reason=MATIEC_MISSING)

# the flags each tool passes to iec2c (docs: ../shared/spec/matiec.md section 8)
BEREMIZ_FLAGS = ["-f", "-l", "-p"]
OPENPLC_FLAGS = ["-f", "-l", "-p", "-r", "-R", "-a"]


@pytest.fixture(scope="module")
def exported(tmp_path_factory):
    result = export_st()
    path = tmp_path_factory.mktemp("export") / "linmot_lib.st"
    path.write_text(result.text)
    return result, path


def expected_lines(path: Path, root: Path) -> list[str]:
    """The source lines in include order, include pragmas left out (an oracle independent of st.py)."""
    out = []
    for line in path.read_text().splitlines():
        names = sources.find_includes(line)
        if names and line.strip().startswith("{"):
            for name in names:
                out += expected_lines(root / name, root)
        else:
            out.append(line)
    return out


def test_no_include_pragma_is_left(exported):
    result, _ = exported
    assert "#include" not in sources.COMMENT.sub(" ", result.text)
    assert sources.find_includes(result.text) == []


def test_header_comment_names_version_and_sources(exported):
    result, _ = exported
    head = result.text[:result.text.index("*)") + 2]
    assert result.text.startswith("(*")
    assert f"linmot-st {package_version()}" in head
    for name in result.library.names:
        assert name in head
    assert "(*" not in head[2:]                      # MatIEC rejects nested comments


def test_every_source_line_is_kept_in_include_order(exported):
    result, _ = exported
    want = expected_lines(LIBRARY, REPO)
    got = result.text.splitlines()
    it = iter(got)
    missing = [line for line in want if not any(line == g for g in it)]
    assert missing == []
    extra = len(got) - len(want)
    # only the header comment, the blank line after it and a begin/end marker per include were added
    header_lines = result.text[:result.text.index("*)")].count("\n") + 1
    assert extra == header_lines + 1 + 2 * (len(result.library.files) - 1)


def test_export_is_deterministic(exported):
    assert export_st().text == exported[0].text


def manifest(path: Path, backend: str, cache: Path) -> dict:
    res = build(path, backend=backend, cache_dir=cache)
    return json.loads(Path(res.manifest).read_text())


def test_builds_with_builtin_to_the_same_layout(exported, tmp_path):
    _, path = exported
    mine = manifest(path, "builtin", tmp_path / "cache")
    lib = manifest(LIBRARY, "builtin", tmp_path / "cache")
    assert mine["types"] == lib["types"]
    assert set(mine["pous"]) == set(lib["pous"])
    c = read_library().counts
    assert len(mine["pous"]) == c["functions"] + c["function_blocks"] + c["programs"]
    assert all(v["file"] == path.name or v["file"].endswith(path.name) for v in mine["pous"].values())


def run_iec2c(st_file: Path, out: Path, flags: list[str], cwd: Path) -> subprocess.CompletedProcess:
    out.mkdir(parents=True, exist_ok=True)
    return subprocess.run([str(MATIEC.iec2c), *flags, "-I", str(MATIEC.lib), "-T", str(out), str(st_file)],
                          cwd=cwd, capture_output=True, text=True, timeout=120)


@requires_iec2c
@pytest.mark.matiec
@pytest.mark.parametrize("tool,flags", [("beremiz", BEREMIZ_FLAGS), ("openplc", OPENPLC_FLAGS)])
def test_iec2c_accepts_it_and_generates_the_same_c_as_the_library(exported, tmp_path, tool, flags):
    _, path = exported
    mine = run_iec2c(path, tmp_path / "export", flags, cwd=tmp_path)
    assert mine.returncode == 0, mine.stderr
    lib = run_iec2c(LIBRARY.relative_to(REPO), tmp_path / "library", flags, cwd=REPO)
    assert lib.returncode == 0, lib.stderr
    for name in ("POUS.h", "POUS.c"):
        assert (tmp_path / "export" / name).read_bytes() == (tmp_path / "library" / name).read_bytes(), name


@requires_iec2c
@pytest.mark.matiec
def test_openplc_style_program_file_compiles(exported, tmp_path):
    """OpenPLC uploads one .st file: the library followed by the user's program and configuration."""
    result, _ = exported
    program = textwrap.dedent("""
        PROGRAM PlcMain
          VAR
            Box : T_CanMailbox;
            Axis : T_LmAxis;
            Channel : FB_LmChannel;
          END_VAR
          Channel(Enable := TRUE, NodeId := 1, Axis := Axis, Box := Box);
        END_PROGRAM

        CONFIGURATION Config0
          RESOURCE Res0 ON PLC
            TASK Main(INTERVAL := T#1ms, PRIORITY := 0);
            PROGRAM Inst0 WITH Main : PlcMain;
          END_RESOURCE
        END_CONFIGURATION
        """)
    prog = tmp_path / "prog.st"
    prog.write_text(result.text + program)
    proc = run_iec2c(prog, tmp_path / "out", OPENPLC_FLAGS, cwd=tmp_path)
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "out" / "Config0.c").is_file() and (tmp_path / "out" / "Res0.c").is_file()


@requires_iec2c
@pytest.mark.matiec
def test_builds_with_matiec(exported, tmp_path):
    _, path = exported
    mine = manifest(path, "matiec", tmp_path / "cache")
    lib = manifest(LIBRARY, "matiec", tmp_path / "cache")
    assert mine["backend"] == "matiec"
    assert set(mine["pous"]) == set(lib["pous"])


# ------------------------------------------------------------------ includes and errors, on small libraries

def make_lib(tmp_path: Path, files: dict[str, str]) -> Path:
    for name, text in files.items():
        p = tmp_path / name
        p.parent.mkdir(parents=True, exist_ok=True)
        p.write_text(textwrap.dedent(text).lstrip("\n"))
    return tmp_path / "st_lib" / "linmot.st"


def test_nested_includes_expand_in_order_and_commented_ones_stay(tmp_path):
    entry = make_lib(tmp_path, {
        "st_lib/linmot.st": """
            (* entry; this one is a comment: {#include "st_lib/nope.st"} *)
            {#include "st_lib/a.st"}
            FUNCTION F_Last : INT
              VAR_INPUT
                X : INT;
              END_VAR
              F_Last := F_A(X) + F_B(X);
            END_FUNCTION
            """,
        "st_lib/a.st": """
            {#include "st_lib/b.st"}
            FUNCTION F_A : INT
              VAR_INPUT
                X : INT;
              END_VAR
              F_A := X;
            END_FUNCTION
            """,
        "st_lib/b.st": """
            FUNCTION F_B : INT
              VAR_INPUT
                X : INT;
              END_VAR
              F_B := X + 2; (* comment kept *)
            END_FUNCTION
            """,
    })
    text = export_st(entry).text
    assert text.index("FUNCTION F_B") < text.index("FUNCTION F_A") < text.index("FUNCTION F_Last")
    assert '{#include "st_lib/nope.st"}' in text and "(* comment kept *)" in text
    assert sources.find_includes(text) == []
    out = tmp_path / "out.st"
    out.write_text(text)
    assert set(manifest(out, "builtin", tmp_path / "cache")["pous"]) == {"F_A", "F_B", "F_LAST"}


def test_missing_include_is_a_clear_error(tmp_path):
    entry = make_lib(tmp_path, {"st_lib/linmot.st": '{#include "st_lib/missing.st"}\n'})
    with pytest.raises(ExportError, match=r'st_lib/linmot.st:1:1: .*missing\.st'):
        export_st(entry)


def test_library_that_does_not_compile_is_refused(tmp_path):
    entry = make_lib(tmp_path, {"st_lib/linmot.st": """
        FUNCTION F_Bad : INT
          VAR_INPUT a : INT; END_VAR F_Bad := Undeclared;
        END_FUNCTION
        """})
    with pytest.raises(ExportError, match=r"does not compile:\n.*linmot.st:2:\d+: error: .*Undeclared"):
        export_st(entry)


# ------------------------------------------------------------------ the command

def test_cli_writes_the_file_and_reports_counts(tmp_path, capsys, exported):
    out = tmp_path / "lib.st"
    assert cli_main(["export", "st", str(out)]) == 0
    msg = capsys.readouterr().out
    c = exported[0].library.counts
    assert f"wrote {out}:" in msg
    assert f"{c['types']} data types, {c['functions']} functions, {c['function_blocks']} function blocks" in msg
    assert f"{out.stat().st_size:,} bytes" in msg
    assert out.read_text() == exported[0].text


def test_cli_stdout(capsys, exported):
    assert cli_main(["export", "st", "-"]) == 0
    cap = capsys.readouterr()
    assert cap.out == exported[0].text
    assert "wrote <stdout>" in cap.err


@pytest.mark.parametrize("target,message", [
    ("missing_dir/lib.st", "folder .*missing_dir does not exist"),
    (".", "is a folder"),
    ("afile/lib.st", "afile is not a folder"),
])
def test_cli_bad_output_paths(tmp_path, capsys, target, message):
    (tmp_path / "afile").write_text("x")
    assert cli_main(["export", "st", str(tmp_path / target)]) == 2        # checked before the export
    err = capsys.readouterr().err
    assert err.startswith("linmot-st export st: error: ")
    assert re.search(message, err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["afile"]      # nothing half-written


def test_cli_bad_entry(tmp_path, capsys):
    assert cli_main(["export", "st", str(tmp_path / "o.st"), "--entry", str(tmp_path / "none.st")]) == 1
    assert "none.st: no such file or folder" in capsys.readouterr().err
    assert not (tmp_path / "o.st").exists()


def test_cli_keeps_the_old_file_on_failure(tmp_path, capsys):
    out = tmp_path / "o.st"
    out.write_text("old")
    bad = make_lib(tmp_path / "lib", {"st_lib/linmot.st": "FUNCTION F : INT F := x; END_FUNCTION\n"})
    assert cli_main(["export", "st", str(out), "--entry", str(bad)]) == 1
    assert out.read_text() == "old"
