"""The files generated from the protocol catalogue (linmot_st/protocol/generate.py): `python -m linmot_st.protocol
--check` passes on the repository and fails, naming the file, on a copy where one generated file was edited."""

from __future__ import annotations

import shutil
import subprocess
import sys

from linmot_st.protocol import generate


def _check(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "linmot_st.protocol", "--check", *args],
                          capture_output=True, text=True, timeout=120)


def test_every_generated_file_is_current():
    r = _check()
    assert r.returncode == 0, r.stderr


def test_an_edited_generated_file_fails_the_check(tmp_path):
    for a in generate.ARTEFACTS:
        (tmp_path / a.path).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(generate.REPO / a.path, tmp_path / a.path)
    assert _check("--root", str(tmp_path)).returncode == 0          # the copy as it is: current
    codec = tmp_path / "st_lib/motion/codec_gen.st"
    text = codec.read_text()
    assert "N := 16;" in text
    codec.write_text(text.replace("N := 16;", "N := 14;"))          # a hand edit of the generated encoder
    r = _check("--root", str(tmp_path))
    assert r.returncode == 1
    assert "st_lib/motion/codec_gen.st" in r.stderr and "errors.st" not in r.stderr


def test_an_edited_docs_table_fails_the_check(tmp_path):
    for a in generate.ARTEFACTS:
        (tmp_path / a.path).parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(generate.REPO / a.path, tmp_path / a.path)
    doc = tmp_path / "docs/st-library.md"
    doc.write_text(doc.read_text().replace("| 16#0101 |", "| 16#0111 |", 1))
    assert generate.check(tmp_path) == [f"docs/st-library.md: differs from the catalogue (run {generate.COMMAND})"]
    assert generate.write(tmp_path) == ["docs/st-library.md"]      # --write repairs it
    assert generate.check(tmp_path) == []
