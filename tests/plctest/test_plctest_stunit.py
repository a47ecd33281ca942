"""Tests written in ST: the assertion library on both backends, and the plugin's ST items (discovery, budgets,
the file and line of a failed assertion, JUnit XML), run by pytest in a project of their own."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import xml.etree.ElementTree as ET

import pytest

from linmot_st.plc import Plc
from linmot_st.plctest import stunit_lib
from linmot_st.plctest.stunit import assertion_lines, discover, st_string
from linmot_st.toolchain.testing import BACKEND_PARAMS, build_text


def test_the_assertion_library_is_generated_from_its_table():
    assert stunit_lib.check() == []


# one assertion per line: (call, holds, failure text)
CASES = [
    ("AssertTrue(StUnit, X = 3, 'm')", True, None),
    ("AssertTrue(StUnit, X = 4, 'm')", False, "AssertTrue: the condition is FALSE"),
    ("AssertFalse(StUnit, X = 3, 'm')", False, "AssertFalse: the condition is TRUE"),
    ("AssertEqual_DINT(StUnit, 3, X, 'm')", True, None),
    ("AssertEqual_DINT(StUnit, -7, X, 'm')", False, "AssertEqual_DINT: expected -7, actual 3"),
    ("AssertEqual_SINT(StUnit, SINT#-128, SINT#127, 'm')", False, "AssertEqual_SINT: expected -128, actual 127"),
    ("AssertEqual_ULINT(StUnit, ULINT#18446744073709551615, ULINT#0, 'm')", False,
     "AssertEqual_ULINT: expected 18446744073709551615, actual 0"),
    ("AssertEqual_BYTE(StUnit, 16#F0, B, 'm')", True, None),
    ("AssertEqual_WORD(StUnit, 16#0503, WORD#16#0502, 'm')", False, "AssertEqual_WORD: expected 16#503, actual 16#502"),
    ("AssertEqual_BOOL(StUnit, TRUE, FALSE, 'm')", False, "AssertEqual_BOOL: expected TRUE, actual FALSE"),
    ("AssertEqual_STRING(StUnit, 'abc', S, 'm')", True, None),
    ("AssertEqual_STRING(StUnit, 'abd', S, 'm')", False, "AssertEqual_STRING: expected 'abd', actual 'abc'"),
    ("AssertEqual_TIME(StUnit, T#15ms, Tm, 'm')", True, None),
    ("AssertEqual_LREAL(StUnit, 0.5, LREAL#0.25, 'm')", False, "AssertEqual_LREAL: expected 0.5, actual 0.25"),
    ("AssertWithin_REAL(StUnit, 1.4, R, 0.2, 'm')", True, None),
    ("AssertWithin_REAL(StUnit, 1.0, R, 0.25, 'm')", False, "AssertWithin_REAL: expected 1.0, actual 1.5, tolerance 0.25"),
    ("AssertWithin_UDINT(StUnit, 10, UDINT#7, 3, 'm')", True, None),      # unsigned: 10 - 7, never 7 - 10
    ("AssertWithin_UDINT(StUnit, 7, UDINT#11, 3, 'm')", False, "AssertWithin_UDINT: expected 7, actual 11, tolerance 3"),
    ("AssertWithin_TIME(StUnit, T#10ms, Tm, T#5ms, 'm')", True, None),
    ("AssertWithin_TIME(StUnit, T#10ms, Tm, T#4ms, 'm')", False,
     "AssertWithin_TIME: expected T#10ms, actual T#15ms, tolerance T#4ms"),
    ("AssertWithin_INT(StUnit, -5, INT#5, 10, 'm')", True, None),
    ("AssertEqual_Bytes(StUnit, E, A, 2, 'm')", True, None),
    ("AssertEqual_Bytes(StUnit, E, A, 3, 'm')", False,
     "AssertEqual_Bytes: byte 3 of 3 differs: expected 01 02 03, actual 01 02 07"),
    ("AssertEqual_Bytes(StUnit, E, A, 65, 'm')", False, "AssertEqual_Bytes: Count 65 is outside 0..64"),
]

PROGRAM = """
{{#include "st_lib/stunit/stunit.st"}}
PROGRAM Main
  VAR
    StUnit : T_StUnit;
    Ok : BOOL;
    X : DINT := 3;
    B : BYTE := 16#F0;
    R : REAL := 1.5;
    Tm : TIME := T#15ms;
    S : STRING := 'abc';
    E : T_StBytes := [1, 2, 3];
    A : T_StBytes := [1, 2, 7];
    Which : INT;
  END_VAR
  CASE Which OF
{cases}
  END_CASE;
END_PROGRAM
CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK Cyclic(INTERVAL := T#1ms, PRIORITY := 0);
    PROGRAM Inst0 WITH Cyclic : Main;
  END_RESOURCE
END_CONFIGURATION
"""


@pytest.fixture(scope="module", params=BACKEND_PARAMS)
def assertions(request, tmp_path_factory):
    cases = "\n".join(f"    {k}: Ok := {call};" for k, (call, _, _) in enumerate(CASES, 1))
    return build_text(PROGRAM.format(cases=cases), tmp_path_factory.mktemp("stunit"), request.param)


@pytest.mark.parametrize("k", range(1, len(CASES) + 1), ids=[c[0].split("(")[0] + f"-{i}" for i, c in enumerate(CASES, 1)])
def test_each_assertion_holds_or_records_its_failure(assertions, k):
    call, holds, text = CASES[k - 1]
    plc = Plc(assertions)
    plc["INST0.WHICH"] = k
    plc.step(1)
    rec = plc["INST0.STUNIT"]
    assert plc["INST0.OK"] is holds and rec["ASSERTS"] == 1 and rec["FAILURES"] == (0 if holds else 1), call
    if not holds:
        assert rec["MSG"] == "m" and stunit_lib.describe_failure(rec) == text


def test_discovery_and_the_line_of_an_assertion():
    text = textwrap.dedent("""\
        (* FUNCTION_BLOCK Test_Commented is no test *)
        FUNCTION_BLOCK Test_A
          Ok := AssertEqual_DINT(StUnit, 1,
                                 F(2), 'it is $'one$'');
          Ok := AssertTrue(StUnit, X, 'two');   (* 'two' *)
        END_FUNCTION_BLOCK
        PROGRAM TestB
          Ok := AssertTrue(StUnit, X, 'two');
        END_PROGRAM
        FUNCTION_BLOCK Helper
        END_FUNCTION_BLOCK
        """)
    assert [(t.name, t.kind, t.line) for t in discover(text)] == [("Test_A", "FUNCTION_BLOCK", 2),
                                                                  ("TestB", "PROGRAM", 7)]
    assert assertion_lines(text, "it is 'one'") == [3]          # the call's line; $' in the literal
    assert assertion_lines(text, st_string("two")) == [5, 8]
    assert st_string("a'$b") == "a$'$$b"


# ---- the plugin's ST items, in a project of their own, run by pytest as a user runs it ------------------

TESTS_ST = """\
{#include "st_lib/linmot.st"}

FUNCTION_BLOCK Test_Passes
  VAR
    StUnit : T_StUnit;
    Ok : BOOL;
  END_VAR
  Ok := AssertEqual_INT(StUnit, 4, 2 + 2, 'arithmetic');
END_FUNCTION_BLOCK

FUNCTION_BLOCK Test_FailsAtItsLine
  VAR_OUTPUT
    Done : BOOL;
  END_VAR
  VAR
    StUnit : T_StUnit;
    Ok : BOOL;
    N : INT;
  END_VAR
  N := N + 1;
  Ok := AssertTrue(StUnit, N < 5,
                   'fewer than five scans');
  Done := N >= 100;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Test_RunsOutOfTime
  VAR_OUTPUT
    Done : BOOL;
  END_VAR
  VAR
    StUnit : T_StUnit;
    Timeout : TIME := T#25ms;
  END_VAR
  Done := FALSE;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Test_TalksToTheDrive
  (* the channel of node 1 hears the emulated drive's boot-up message on CAN0 *)
  VAR_EXTERNAL
    CAN0 : T_CanMailbox;
  END_VAR
  VAR_OUTPUT
    Done : BOOL;
  END_VAR
  VAR
    StUnit : T_StUnit;
    MaxScans : UDINT := 500;
    Ok : BOOL;
    Ax : T_LmAxis;
    Ch : FB_LmChannel;
  END_VAR
  Ch(Enable := TRUE, NodeId := 1, Axis := Ax, Box := CAN0);
  Done := Ax.BootCount > 0;
  IF Done THEN
    Ok := AssertEqual_UINT(StUnit, 1, Ax.BootCount, 'one boot-up message');
  END_IF;
END_FUNCTION_BLOCK

FUNCTION_BLOCK Test_WithoutRecord
  VAR
    N : INT;
  END_VAR
  N := N + 1;
END_FUNCTION_BLOCK

PROGRAM Test_AsAProgram
  VAR
    StUnit : T_StUnit;
    Ok : BOOL;
    Done : BOOL;
    N : INT;
  END_VAR
  N := N + 1;
  Done := N = 3;
  Ok := AssertTrue(StUnit, N <= 3, 'a program runs scan by scan');
END_PROGRAM
"""

EXPECTED = {"Test_Passes": "passed", "Test_FailsAtItsLine": "failed", "Test_RunsOutOfTime": "failed",
            "Test_TalksToTheDrive": "passed", "Test_WithoutRecord": "failed", "Test_AsAProgram": "passed"}


def run_pytest(folder, *args):
    env = {k: v for k, v in os.environ.items() if k != "PYTEST_ADDOPTS"}
    return subprocess.run([sys.executable, "-m", "pytest", "-q", *args],
                          cwd=folder, env=env, capture_output=True, text=True, timeout=600)


@pytest.fixture(scope="module")
def st_project(tmp_path_factory):
    folder = tmp_path_factory.mktemp("st_project")
    (folder / "pytest.ini").write_text("[pytest]\nlinmot_st_timings = fast\nlinmot_st_backend = builtin\n")
    (folder / "tests").mkdir()
    (folder / "tests" / "test_things.st").write_text(TESTS_ST)
    proc = run_pytest(folder, "--junitxml=report.xml")
    return folder, proc


def test_each_st_test_is_a_pytest_item_with_its_outcome(st_project):
    folder, proc = st_project
    cases = {c.get("name"): c for c in ET.parse(folder / "report.xml").getroot().iter("testcase")}
    outcome = {n: "failed" if c.find("failure") is not None or c.find("error") is not None else
               "skipped" if c.find("skipped") is not None else "passed" for n, c in cases.items()}
    assert outcome == EXPECTED, proc.stdout
    assert {c.get("classname") for c in cases.values()} == {"tests.test_things.st"}


def test_a_failed_assertion_names_its_file_line_scan_and_values(st_project):
    folder, proc = st_project
    assert ("tests/test_things.st:21: Test_FailsAtItsLine failed at scan 5 (PLC time 0.005000 s)\n"
            "  'fewer than five scans': AssertTrue: the condition is FALSE") in proc.stdout, proc.stdout


def test_a_test_out_of_budget_and_one_without_a_record_say_so(st_project):
    _, proc = st_project
    assert "Test_RunsOutOfTime: Done not reached within its Timeout of 25 ms (25 scans)" in proc.stdout
    assert "PLC time 0.025000 s, scan 25" in proc.stdout
    assert "Test_WithoutRecord declares no local `StUnit : T_StUnit`" in proc.stdout
    assert "3 failed, 3 passed" in proc.stdout.splitlines()[-1]
