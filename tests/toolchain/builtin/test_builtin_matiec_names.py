"""Names the builtin takes because MatIEC builds them: the words iec2c reads as plain identifiers
(checker.MATIEC_IDENTIFIERS: LTIME, CHAR, LDT, METHOD...) in every place a name goes, and user FUNCTIONs
named like a standard function (stdfuncs.USER_NAMEABLE: MULTIME...), whose calls MatIEC sends to its own
standard function. Where iec2c is installed it is asked again."""

from __future__ import annotations

import subprocess

import pytest
from test_builtin_names import PLACES, source

from linmot_st.plc import Plc
from linmot_st.toolchain import CompileError
from linmot_st.toolchain.builtin import BuiltinCompileError, check_text
from linmot_st.toolchain.builtin import stdfuncs as SF
from linmot_st.toolchain.builtin.checker import MATIEC_IDENTIFIERS
from linmot_st.toolchain.testing import BACKEND_PARAMS, build_text, requires_matiec

# refused as a FUNCTION name although standard: operators to iec2c, or its C does not compile
NOT_NAMEABLE = sorted(set(SF.FAMILIES) - SF.USER_NAMEABLE)

CONFIG = """CONFIGURATION sn_cfg
  RESOURCE sn_res ON PLC
    TASK sn_task(INTERVAL := T#10ms, PRIORITY := 0);
    PROGRAM sn_inst WITH sn_task : sn_main;
  END_RESOURCE
END_CONFIGURATION
"""
# every nameable standard function declared as a user FUNCTION; the calls get the standard results
SHADOWING = "".join(f"FUNCTION {n} : INT\n  VAR_INPUT a : INT; END_VAR\n  {n} := 99;\nEND_FUNCTION\n"
                    for n in sorted(SF.USER_NAMEABLE)) + """PROGRAM sn_main
  VAR x : INT := -3; l : INT; m : INT; t : TIME; END_VAR
  x := ABS(x);
  l := LEN('abcd');
  m := MAX(x, 2);
  t := MULTIME(T#2s, x);
END_PROGRAM
""" + CONFIG


def _iec2c_accepts(text, tmp_path) -> bool:
    from linmot_st.toolchain import matiec
    tool = matiec.find()
    (tmp_path / "n.st").write_text(text)
    (tmp_path / "out").mkdir(exist_ok=True)
    argv = [str(tool.iec2c), *matiec.flags(tool.iec2c), "-I", str(tool.lib), "-T", "out", "n.st"]
    return subprocess.run(argv, cwd=tmp_path, capture_output=True, timeout=60).returncode == 0


@pytest.mark.parametrize("place", PLACES)
@pytest.mark.parametrize("name", sorted(MATIEC_IDENTIFIERS))
def test_matiec_identifiers_name_anything(name, place):
    check_text(source(place, name))


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_user_functions_named_like_standard_ones_are_not_called(backend, tmp_path):
    plc = Plc(build_text(SHADOWING, tmp_path, backend))
    plc.step(1)
    assert [plc[f"SN_INST.{v}"] for v in ("X", "L", "M", "T")] == [3, 4, 3, 6_000_000_000]


@pytest.mark.parametrize("name", NOT_NAMEABLE)
def test_operators_and_clashing_names_stay_refused(name):
    with pytest.raises(BuiltinCompileError) as info:
        check_text(source("function", name))
    message = info.value.diagnostics[0].message
    assert "standard function" in message or "reserved word" in message


@requires_matiec
@pytest.mark.matiec
@pytest.mark.parametrize("place", PLACES)
@pytest.mark.parametrize("name", ["LTIME", "CHAR", "LDT", "METHOD", "REF_TO"])
def test_iec2c_takes_these_identifiers(name, place, tmp_path):
    assert _iec2c_accepts(source(place, name), tmp_path)


@requires_matiec
@pytest.mark.matiec
@pytest.mark.parametrize("name", NOT_NAMEABLE)
def test_matiec_does_not_build_the_refused_function_names(name, tmp_path):
    text = source("function", name).replace("PROGRAM tn_main", "PROGRAM sn_main").replace("END_PROGRAM\n", "END_PROGRAM\n" + CONFIG)
    with pytest.raises(CompileError):
        build_text(text, tmp_path, "matiec")
