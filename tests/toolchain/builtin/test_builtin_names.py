"""Names the builtin compiler refuses because MatIEC (with the build's -p) cannot take them, and the errors
it does not repeat: a rejected declaration adds no "not declared" for each use.

Where MatIEC is installed, the stored list of its library's identifiers (builtin/matiec_lib_names.json)
is derived again from its lib folder, and a sample is tried with iec2c.
"""

from __future__ import annotations

import re
import subprocess

import pytest

from linmot_st.toolchain.builtin import BuiltinCompileError, check_text
from linmot_st.toolchain.builtin import types as T
from linmot_st.toolchain.builtin.checker import KEYWORDS, matiec_library_names
from linmot_st.toolchain.testing import requires_matiec
from name_places import name_places

_ALL, MAIN, CONFIG, NAMES = name_places("tn")
# where a name goes (the places iec2c -p treats apart: below, the first four refuse its library's names)
PLACES = {k: _ALL[k] for k in ("function block", "function", "type", "configuration", "variable", "field",
                                "enumerated value", "resource", "task", "program instance")}
REFUSED = ("function block", "function", "type", "configuration")


def source(place: str, name: str) -> str:
    return PLACES[place].replace("{n}", name)


@pytest.mark.parametrize("name", ["P", "pt", "IN", "Cycle", "CURRENT_TIME", "XOUT"])
@pytest.mark.parametrize("place", PLACES)
def test_library_identifiers(place, name):
    """With -p, iec2c knows the POU, type and configuration names before it parses its library, whose
    variables then fail to parse: those names are refused there, and only there."""
    if place in REFUSED:
        with pytest.raises(BuiltinCompileError) as info:
            check_text(source(place, name))
        assert "it is a variable name in MatIEC's standard library" in str(info.value)
        assert "iec2c -p" in str(info.value)
    else:
        check_text(source(place, name))


def test_the_configuration_name_is_taken_everywhere():
    for place in ("variable", "field", "enumerated value", "resource", "task", "program instance"):
        src = source(place, "tn_cfg")
        with pytest.raises(BuiltinCompileError, match="is the name of the CONFIGURATION"):
            check_text(src + ("" if "CONFIGURATION" in src else CONFIG.format(**NAMES)))


def test_a_rejected_declaration_adds_no_follow_up_errors():
    src = """
TYPE tn_bad : ARRAY[0..tn_n] OF INT; END_TYPE
FUNCTION tn_fbad : tn_unknown
  VAR_INPUT a : INT; END_VAR
  tn_fbad := a;
END_FUNCTION
PROGRAM tn_main
  VAR
    x : tn_nope;
    y : INT := 100000;
    z : tn_bad;
    w : INT;
    q, q : INT;
  END_VAR
  x := x + 1;
  y := y + 1;
  z[1] := w;
  w := tn_fbad(1);
  IF x > 0 THEN w := 2; END_IF;
  q := q + 1;
  w := nothere;
END_PROGRAM
"""
    with pytest.raises(BuiltinCompileError) as info:
        check_text(src, "c.st")
    assert [f"{d.line}: {d.message.split(' (')[0]}" for d in info.value.diagnostics] == [
        "2: array bounds must be integer literals",
        "3: unknown type 'tn_unknown'",
        "9: unknown type 'tn_nope'",
        "10: the value 100000 does not fit INT",
        "13: duplicate declaration of 'q'",
        "21: 'nothere' is not declared in tn_main",     # a real error after them is still reported
    ]


# ---- MatIEC, where installed ----------------------------------------------------------------------------

def derive_library_names(lib) -> set[str]:
    """MatIEC's library identifiers that are neither keywords, types nor the library's POU names: the
    parameters and locals of its functions and FBs (lib/ieclib.txt and the files it includes)."""
    files, seen = ["ieclib.txt"], set()
    ids, pous = set(), set()
    while files:
        name = files.pop()
        if name in seen:
            continue
        seen.add(name)
        text = (lib / name).read_text(errors="replace")
        files += re.findall(r'\{\s*#include\s+"([^"]+)"\s*\}', text)
        text = re.sub(r"\(\*.*?\*\)", " ", text, flags=re.S)
        text = re.sub(r"\{[^}]*\}", " ", text)
        text = re.sub(r"'[^']*'", " ", text)
        text = re.sub(r"\b\w+#[\w.:-]+", " ", text)       # typed literals and durations
        pous |= {m.upper() for m in re.findall(r"\b(?:FUNCTION_BLOCK|FUNCTION)\s+(\w+)", text)}
        ids |= {w.upper() for w in re.findall(r"\b[A-Za-z_]\w*\b", text)}
    reserved = KEYWORDS | set(T.ELEMENTARY) | set(T.ELEMENTARY_ALIASES) | T.UNSUPPORTED_ELEMENTARY
    return ids - pous - reserved


@requires_matiec
@pytest.mark.matiec
def test_stored_library_names_are_matiecs():
    from linmot_st.toolchain import matiec
    assert derive_library_names(matiec.find().lib) == set(matiec_library_names())


@requires_matiec
@pytest.mark.matiec
@pytest.mark.parametrize("place", PLACES)
def test_iec2c_agrees_on_library_identifiers(place, tmp_path):
    from linmot_st.toolchain import matiec
    tool = matiec.find()
    src = tmp_path / "n.st"
    src.write_text(source(place, "PT"))
    (tmp_path / "out").mkdir()
    argv = [str(tool.iec2c), *matiec.flags(tool.iec2c), "-I", str(tool.lib), "-T", "out", src.name]
    accepted = subprocess.run(argv, cwd=tmp_path, capture_output=True, timeout=60).returncode == 0
    assert accepted == (place not in REFUSED)
