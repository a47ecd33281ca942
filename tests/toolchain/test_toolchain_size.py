"""Big programs built fast: a long body cut into part functions (builtin codegen) runs as the uncut one,
RETURN included; gcc's optimisation level follows the size of a unit (toolchain.cc.size_flags)."""

from __future__ import annotations

from linmot_st.toolchain import cc
from linmot_st.toolchain.testing import build_text

LONG_ST = """
FUNCTION_BLOCK FB_Acc
  VAR_INPUT In : DINT; END_VAR
  VAR_OUTPUT Sum : DINT; END_VAR
  Sum := Sum + In;
  IF Sum > 1000 THEN
    Sum := 0;
    RETURN;
  END_IF;
  Sum := Sum + 1;
END_FUNCTION_BLOCK

PROGRAM Long
  VAR
    x : DINT; y : DINT; i : INT; n : UDINT; tail : UDINT; a : ARRAY[0..9] OF DINT;
    acc : FB_Acc; t : TON; k : INT;
  END_VAR
  n := n + 1;
  x := x + 3;
  FOR i := 0 TO 9 DO
    a[i] := a[i] + x * INT_TO_DINT(i);
  END_FOR;
  acc(In := x);
  y := y + acc.Sum;
  CASE x MOD 4 OF
    0: y := y + 1;
    1, 2: y := y - 2;
  ELSE
    y := y * 2;
  END_CASE;
  t(IN := TRUE, PT := T#5ms);
  IF t.Q THEN
    t(IN := FALSE);
    k := k + 1;
  END_IF;
  IF n MOD 3 = 0 THEN
    RETURN;
  END_IF;
  x := x - 1;
  WHILE y > 100000 DO
    y := y / 3;
  END_WHILE;
  tail := tail + 1;
  a[n MOD 10] := a[(n + 3) MOD 10] - y;
END_PROGRAM

CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK Main(INTERVAL := T#1ms, PRIORITY := 0);
    PROGRAM Inst0 WITH Main : Long;
  END_RESOURCE
END_CONFIGURATION
"""

VARS = ["X", "Y", "N", "TAIL", "K", "A", "ACC.SUM"]


def _run(res, scans: int = 200) -> list:
    from linmot_st.plc import Plc
    plc = Plc(res)
    out = []
    for _ in range(scans):
        plc.step(1)
        out.append([plc[f"CONFIG0.RES0.INST0.{v}"] for v in VARS])
    return out


def test_a_body_cut_into_parts_runs_as_the_uncut_one(tmp_path, monkeypatch):
    from linmot_st.toolchain.builtin import codegen
    whole = build_text(LONG_ST, tmp_path / "whole", "builtin")
    monkeypatch.setattr(codegen, "BODY_PART_LINES", 4)
    cut = build_text(LONG_ST, tmp_path / "cut", "builtin")
    c = "".join(p.read_text() for p in sorted(cut.c_dir.glob("*.c")))
    assert "LONG_body__part3(" in c and "FB_ACC_body__part2(" in c
    runs = _run(whole), _run(cut)
    assert runs[0] == runs[1]
    assert runs[0][-1][3] < runs[0][-1][2]          # the RETURN skipped the tail in a third of the scans


def test_the_longest_function_of_a_c_text():
    text = "typedef struct {\n  int a;\n} S;\nstatic void f(S *d)\n{\n" + "  d->a++;\n" * 50 + "}\n" \
           "void g(void) {\n  return;\n}\n"
    assert cc.longest_function_lines(text) == 51


def test_large_units_are_compiled_at_O0(tmp_path, monkeypatch):
    small, large = tmp_path / "small.c", tmp_path / "large.c"
    small.write_text("void f(int *p)\n{\n" + "  *p += 1;\n" * 100 + "}\n")
    large.write_text("void f(int *p)\n{\n" + "  *p += 1;\n" * (cc.LONG_FUNCTION_LINES + 1) + "}\n")
    assert cc.size_flags(small) == [] and cc.size_flags(large)[0] == "-O0"
    monkeypatch.setattr(cc, "LARGE_UNIT_LINES", 50)
    assert cc.size_flags(small)[0] == "-O0"
