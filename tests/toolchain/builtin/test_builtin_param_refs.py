"""FB parameters passed by reference (toolchain/builtin/param_refs.py): which ones, the same values as
MatIEC's copy-in/copy-out, a forced actual, and plc_project's mailbox, axis and steps passed without copies.

The cases where a pointer would differ from the copies (and the builtin keeps copies) are conformance
cases compared with MatIEC: pou_fb_inout_alias, pou_fb_inout_global, pou_fb_input_alias."""

from __future__ import annotations

import pytest

from linmot_st.plc import Plc
from linmot_st.resources import library_tree
from linmot_st.toolchain.builtin import check_text, codegen
from linmot_st.toolchain.builtin.checker import Checker
from linmot_st.toolchain.builtin.loader import load
from linmot_st.toolchain.builtin.param_refs import by_reference
from linmot_st.toolchain.testing import build_text

# Parameters of every kind the analysis decides: arrays of structs, elements whose index moves between
# calls, a pointer passed on two levels down, an FB skipped by EN, a FUNCTION's in-out inside the body.
SRC = """
TYPE t_pt : STRUCT x : INT; hist : ARRAY[0..3] OF DINT; END_STRUCT; t_pts : ARRAY[1..4] OF t_pt; END_TYPE
FUNCTION f_add : INT
  VAR_IN_OUT p : t_pt; END_VAR
  VAR_INPUT d : INT; END_VAR
  p.x := p.x + d;
  f_add := p.x;
END_FUNCTION
FUNCTION_BLOCK fb_leaf
  VAR_IN_OUT p : t_pt; n : INT; END_VAR
  VAR_OUTPUT got : INT; END_VAR
  n := n + 1;
  p.hist[n MOD 4] := p.hist[n MOD 4] + INT_TO_DINT(p.x);
  got := f_add(p, n);
END_FUNCTION_BLOCK
FUNCTION_BLOCK fb_mid
  VAR_IN_OUT pts : t_pts; n : INT; END_VAR
  VAR_INPUT k : INT; END_VAR
  VAR_OUTPUT sum : INT; END_VAR
  VAR leaf : fb_leaf; i : INT; END_VAR
  leaf(p := pts[k], n := n, got => sum);
  i := 1;
  WHILE i <= 4 DO
    sum := sum + pts[i].x;
    i := i + 1;
  END_WHILE;
END_FUNCTION_BLOCK
FUNCTION_BLOCK fb_sum
  VAR_INPUT pts : t_pts; END_VAR
  VAR_IN_OUT acc : t_pt; END_VAR
  VAR_OUTPUT total : INT; END_VAR
  VAR i : INT; END_VAR
  acc.x := acc.x + 1;
  total := 0;
  i := 1;
  WHILE i <= 4 DO
    total := total + pts[i].x;
    i := i + 1;
  END_WHILE;
END_FUNCTION_BLOCK
FUNCTION_BLOCK fb_sum2
  VAR_INPUT pts : t_pts; END_VAR
  VAR_IN_OUT acc : t_pt; END_VAR
  VAR_OUTPUT total : INT; END_VAR
  VAR i : INT; END_VAR
  acc.x := acc.x + 1;
  total := 0;
  i := 1;
  WHILE i <= 4 DO
    total := total + pts[i].x;
    i := i + 1;
  END_WHILE;
END_FUNCTION_BLOCK
FUNCTION_BLOCK fb_scratch
  VAR_INPUT p : t_pt; END_VAR
  VAR_OUTPUT x : INT; END_VAR
  p.x := p.x * 2 + 1;
  x := p.x;
END_FUNCTION_BLOCK
FUNCTION_BLOCK fb_twice
  VAR_IN_OUT a, b : INT; END_VAR
  a := a + 1;
  b := b + 10;
END_FUNCTION_BLOCK
FUNCTION_BLOCK fb_glob
  VAR_IN_OUT a : INT; END_VAR
  VAR_EXTERNAL g : INT; END_VAR
  a := a + g;
END_FUNCTION_BLOCK
PROGRAM p_main
  VAR_EXTERNAL g : INT; END_VAR
  VAR
    pts : t_pts; n, k, s1, s2, x, y : INT; mi : fb_mid; mi2 : fb_mid; tw : fb_twice; gl : fb_glob;
    skip : BOOL; su : fb_sum; su2 : fb_sum2; sc : fb_scratch; a1 : t_pt; t1, t2, t3 : INT;
  END_VAR
  k := k MOD 4 + 1;
  mi(pts := pts, n := n, k := k, sum => s1);
  mi2(EN := NOT skip, pts := pts, n := n, k := 5 - k, sum => s2);
  skip := NOT skip;
  tw(a := x, b := y);
  tw(a := x, b := x);
  gl(a := y);
  su(pts := pts, acc := a1, total => t1);
  su2(pts := pts, acc := pts[2], total => t2);
  sc(p := pts[3], x => t3);
END_PROGRAM
CONFIGURATION c0
  RESOURCE r0 ON PLC
    VAR_GLOBAL g : INT := 3; END_VAR
    TASK t(INTERVAL := T#1ms, PRIORITY := 0);
    PROGRAM main WITH t : p_main;
  END_RESOURCE
END_CONFIGURATION
"""

WATCHED = ["MAIN.PTS", "MAIN.N", "MAIN.K", "MAIN.S1", "MAIN.S2", "MAIN.X", "MAIN.Y", "C0.R0.G",
           "MAIN.MI.LEAF.GOT", "MAIN.MI2.SUM", "MAIN.A1", "MAIN.T1", "MAIN.T2", "MAIN.T3"]


def test_which_in_outs_are_pointers():
    refs = by_reference(check_text(SRC))
    assert refs == {("FB_LEAF", "P"), ("FB_LEAF", "N"), ("FB_MID", "PTS"), ("FB_MID", "N"), ("FB_SUM", "PTS"),
                    ("FB_SUM", "ACC"), ("FB_SUM2", "ACC")}
    # fb_twice: one call binds x to both; fb_glob: it reads a global (it could be the actual); fb_sum2's
    # input: its call writes the same array through the in-out; fb_scratch writes its input


# What MatIEC evaluates between one parameter's copy-in and the body, or again after the body: a FUNCTION in
# another argument (copied in in the FB's declaration order) and the copy-out of an output or another in-out
# (conformance cases pou_fb_ref_side_effect, pou_fb_ref_copy_out_index).
SIDE_EFFECTS = """
TYPE t_a3 : ARRAY[0..2] OF INT; t_st : STRUCT x : INT; y : INT; END_STRUCT; END_TYPE
FUNCTION f_bump : INT
  VAR_IN_OUT x : INT; END_VAR
  x := x + 1;
  f_bump := x;
END_FUNCTION
FUNCTION_BLOCK fb_other
  VAR_IN_OUT a : INT; END_VAR
  VAR_INPUT k : INT; END_VAR
  a := a + k;
END_FUNCTION_BLOCK
FUNCTION_BLOCK fb_same
  VAR_IN_OUT a : INT; END_VAR
  VAR_INPUT k : INT; END_VAR
  a := a + k;
END_FUNCTION_BLOCK
FUNCTION_BLOCK fb_index
  VAR_IN_OUT a : INT; END_VAR
  VAR_INPUT k : INT; END_VAR
  a := a + k;
END_FUNCTION_BLOCK
FUNCTION_BLOCK fb_input
  VAR_INPUT v : t_st; k : INT; END_VAR
  VAR_OUTPUT o : INT; END_VAR
  o := v.x + k;
END_FUNCTION_BLOCK
FUNCTION_BLOCK fb_out_other
  VAR_OUTPUT o : INT; END_VAR
  VAR_IN_OUT a : INT; END_VAR
  a := a + 1;
  o := a;
END_FUNCTION_BLOCK
FUNCTION_BLOCK fb_out_same
  VAR_OUTPUT o : INT; END_VAR
  VAR_IN_OUT a : INT; END_VAR
  a := a + 1;
  o := a;
END_FUNCTION_BLOCK
FUNCTION_BLOCK fb_inout_index
  VAR_IN_OUT q : INT; p : INT; END_VAR
  p := p + 1;
  q := q + p;
END_FUNCTION_BLOCK
PROGRAM p_main
  VAR
    o : fb_other; s : fb_same; x : fb_index; u : fb_input; oo : fb_out_other; os : fb_out_same;
    t : fb_inout_index; v, w, i, j, m, r : INT; arr : t_a3; st : t_st;
  END_VAR
  o(a := v, k := f_bump(w));
  s(a := w, k := f_bump(w));
  x(a := arr[i], k := f_bump(i));
  u(v := st, k := f_bump(st.y), o => r);
  oo(a := j, o => arr[i]);
  os(a := m, o => arr[m]);
  t(q := arr[r], p := r);
END_PROGRAM
"""


def test_what_an_argument_or_a_copy_out_changes_keeps_a_copy():
    refs = by_reference(check_text(SIDE_EFFECTS))
    assert refs == {("FB_OTHER", "A"), ("FB_OUT_OTHER", "A")}
    # fb_same: the FUNCTION writes the in-out's variable; fb_index: the variable of its index; fb_input: a
    # member of the STRUCT input; fb_out_same: the output's index reads the in-out's variable;
    # fb_inout_index.p: q's index (copied out again after the body) reads it (q: p writes its index)

def _run(res, scans: int = 30, forced: int | None = None, paths: list[str] = WATCHED) -> list:
    plc = Plc(res)
    if forced is not None:
        plc.force("MAIN.N", forced)
    out = []
    for _ in range(scans):
        plc.step(1)
        out.append([plc[path] for path in paths])
    return out


@pytest.fixture(scope="module")
def builds(tmp_path_factory):
    """SRC as it compiles, and with every FB in-out copied in and out (MatIEC's way)."""
    folder = tmp_path_factory.mktemp("inout")
    with_refs = build_text(SRC, folder / "refs", "builtin")
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(codegen, "by_reference", lambda prog: set())
        copies = build_text(SRC, folder / "copies", "builtin")
    return with_refs, copies


def test_pointers_give_the_copies_values(builds):
    """The program's variables; an instance's in-out (MAIN.MI.N) reads its actual now, not the copy the
    last call left (docs/builtin-compiler.md)."""
    with_refs, copies = builds
    assert "ptr:T_PTS" in with_refs.manifest.read_text() and "ptr:T_PTS" not in copies.manifest.read_text()
    assert _run(with_refs) == _run(copies)


def test_a_forced_actual_is_not_written_and_the_fb_sees_it(builds):
    """The FBs work on a copy of the forced value that is dropped; what the instances' in-outs read after
    the scan is that copy, as with copy-in/copy-out (not a pointer into a stack gone)."""
    with_refs, copies = builds
    paths = WATCHED + ["MAIN.MI.N", "MAIN.MI.LEAF.N"]
    runs = _run(with_refs, 4, forced=40, paths=paths)
    assert runs == _run(copies, 4, forced=40, paths=paths)
    assert all(scan[WATCHED.index("MAIN.N")] == 40 for scan in runs)
    assert runs[-1][-2:] == [41, 41]              # MI.N, MI.LEAF.N: the copy, incremented once
    plc = Plc(with_refs)
    plc.force("MAIN.N", 40)
    plc.step(2)
    plc.unforce("MAIN.N")
    plc.step(1)
    assert plc["MAIN.N"] == 41 + (plc["MAIN.SKIP"] is True)    # written again: mi, and mi2 every other scan


def test_plc_project_passes_its_mailbox_and_axis_by_reference():
    root = library_tree()
    elements, _, names = load(root / "plc_project" / "plc.st", root)
    refs = by_reference(Checker().check(elements, names))
    for fb, param in [("FB_PLCAXIS", "BOX"), ("FB_PLCAXIS", "SUM"), ("FB_LMCHANNEL", "BOX"), ("FB_LMCHANNEL", "AXIS"),
                      ("FB_LMCOMMISSION", "BOX"), ("FB_LMCOMMISSION", "AXIS"), ("FB_PLCMOTION", "BOX"),
                      ("FB_PLCMOTION", "AXIS"), ("FB_PLCMOTION", "GATE"), ("FB_LMPDO", "MOTION"),
                      ("FB_PLCAXIS", "STEPS"), ("FB_PLCMOTION", "STEPS")]:
        assert (fb, param) in refs, f"{fb}.{param} is copied again"
