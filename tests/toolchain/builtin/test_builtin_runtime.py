"""Run-time behaviour of code from the builtin compiler that the conformance suite cannot compare with
MatIEC: fault kinds, forcing through VAR_IN_OUT, the manifest, located variables from Python."""

from __future__ import annotations

import json

import pytest

from linmot_st.plc import Plc, PlcFault
from linmot_st.toolchain.testing import build_text

SRC = """
TYPE t_arr : ARRAY[-1..1] OF INT; t_pt : STRUCT x : INT; s : STRING; END_STRUCT; END_TYPE
FUNCTION f_bump : INT
  VAR_IN_OUT v : INT; END_VAR
  v := v + 1;
  f_bump := v;
END_FUNCTION
FUNCTION_BLOCK fb_div
  VAR_INPUT a, b : DINT; END_VAR
  VAR_OUTPUT q : DINT; END_VAR
  q := a / b;
END_FUNCTION_BLOCK
PROGRAM p_main
  VAR
    x, y, r : INT; mode : INT; d : DINT := -2147483647; arr : t_arr; pt : t_pt; anon : ARRAY[0..1] OF BYTE;
    fd : fb_div; m : INT := -32768; w : INT;
  END_VAR
  VAR
    io AT %IW3 : INT;
  END_VAR
  VAR
    led AT %QX1.2 : BOOL;
  END_VAR
  x := x + 1;
  r := f_bump(y);
  led := io > 10;
  CASE mode OF
    1: d := d - 1; d := d / -1;
    2: fd(a := 1, b := 0);
    3: w := m / -1;
  END_CASE;
END_PROGRAM
CONFIGURATION c0
  RESOURCE r0 ON PLC
    TASK t(INTERVAL := T#5ms, PRIORITY := 0);
    PROGRAM main WITH t : p_main;
  END_RESOURCE
END_CONFIGURATION
"""


@pytest.fixture(scope="module")
def build(tmp_path_factory):
    return build_text(SRC, tmp_path_factory.mktemp("rt"), "builtin")


def test_manifest(build):
    m = json.loads(build.manifest.read_text())
    assert m["backend"] == "builtin" and m["schema"] == 1 and m["tick_ns"] == 5_000_000
    assert [r["path"] for r in m["roots"]] == ["C0.R0.MAIN", "%IW3", "%QX1.2"]
    assert m["types"]["T_ARR"] == {"kind": "array", "elem": "INT", "dims": [[-1, 1]]}
    assert m["types"]["T_PT"]["fields"] == [{"name": "X", "type": "INT"}, {"name": "S", "type": "STRING"}]
    main = {f["name"]: f["type"] for f in m["types"]["P_MAIN"]["fields"]}
    assert main["X"] == "var:INT" and main["FD"] == "FB_DIV" and main["IO"] == "ptr:INT"
    assert main["ANON"].startswith("var:__ARRAY") and m["types"][main["ANON"][4:]]["dims"] == [[0, 1]]
    fb = [f["name"] for f in m["types"]["FB_DIV"]["fields"]]
    assert fb == ["EN", "ENO", "A", "B", "Q"]
    assert m["pous"]["P_MAIN"]["line"] == 12 and m["pous"]["F_BUMP"]["kind"] == "FUNCTION"


def test_located_variables_are_roots(build):
    plc = Plc(build)
    plc["%IW3"] = 11
    plc.step(1)
    assert plc["%QX1.2"] is True and plc["MAIN.LED"] is True and plc["MAIN.IO"] == 11


def test_force_blocks_program_writes(build):
    plc = Plc(build)
    plc.force("MAIN.X", 7)
    plc.step(3)
    assert plc["MAIN.X"] == 7
    plc.unforce("MAIN.X")
    plc.step(1)
    assert plc["MAIN.X"] == 8


def test_forced_in_out_actual_is_not_written(build):
    plc = Plc(build)
    plc.force("MAIN.Y", 3)
    plc.step(2)
    assert plc["MAIN.Y"] == 3 and plc["MAIN.R"] == 4    # the function worked on a copy
    plc.unforce("MAIN.Y")
    plc.step(1)
    assert plc["MAIN.Y"] == 4


def test_dint_overflow_by_division_is_the_division_fault(build):
    """DINT MIN / -1 is kind 1, as MatIEC's code reports it (SIGFPE, FPE_INTDIV on x86)."""
    plc = Plc(build)
    plc["MAIN.MODE"] = 1
    with pytest.raises(PlcFault) as info:
        plc.step(1)
    assert info.value.kind == 1 and info.value.pou == "P_MAIN" and info.value.line == 27
    assert "integer division by zero or overflow" in str(info.value)


def test_int_min_divided_by_minus_one_wraps(build):
    plc = Plc(build)
    plc["MAIN.MODE"] = 3
    plc.step(1)
    assert plc["MAIN.W"] == -32768


def test_fault_inside_a_function_block_names_it(build):
    plc = Plc(build)
    plc["MAIN.MODE"] = 2
    with pytest.raises(PlcFault) as info:
        plc.step(1)
    f = info.value
    assert (f.kind, f.pou, f.line) == (1, "FB_DIV", 10) and f.file.endswith("prog.st")
    with pytest.raises(PlcFault):
        plc.step(1)                 # stays stopped until reset
    plc.reset()
    plc["MAIN.MODE"] = 0
    plc.step(2)
    assert plc["MAIN.X"] == 2
