"""ST coverage (docs/coverage.md): a program whose paths are known, run on coverage builds, gives exact line
and branch counts; the reports (Cobertura XML read back, HTML) say the same; `pytest --linmot-cov` works
end to end; the backends agree where MatIEC is installed."""

from __future__ import annotations

import textwrap
from pathlib import Path

import lxml.html
import pytest
from lxml import etree

from linmot_st.plc import Plc
from linmot_st.plc import coverage as collect
from linmot_st.stcov import arms, report
from linmot_st.toolchain import build
from linmot_st.toolchain.testing import BACKEND_PARAMS, requires_matiec, write_st

# Line numbers matter: the assertions below name them.
PROGRAM = """\
FUNCTION_BLOCK FB_Pick
  VAR_INPUT
    Mode : INT;
  END_VAR
  VAR_OUTPUT
    Out : INT;
  END_VAR
  CASE Mode OF
    1:
      Out := 10;
    2, 3:
      Out := 20;
  ELSE
    Out := 0;
  END_CASE;
END_FUNCTION_BLOCK

PROGRAM Main
  VAR
    A : BOOL;
    B : BOOL;
    N : INT;
    Chooser : FB_Pick;
  END_VAR
  IF A THEN
    N := N + 1;
  ELSIF B THEN
    N := N + 2;
  END_IF;
  IF N > 100 THEN
    N := 0;
  END_IF;
  Chooser(Mode := N);
END_PROGRAM

CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK Main_Task(INTERVAL := T#1ms, PRIORITY := 0);
    PROGRAM Inst0 WITH Main_Task : Main;
  END_RESOURCE
END_CONFIGURATION
"""

# Two PLC instances of one build (they share the .gcda): 3 scans idle, 2 with A (N = 1, 2), then the
# second instance 1 scan with B (N = 2). CASE: N = 0 three times (ELSE), 1 once, 2 twice.
LINES = {8: 6, 10: 1, 12: 2, 14: 3,                 # FB_Pick: CASE, its three arms
         25: 6, 26: 2, 27: 4, 28: 1,                # IF A (6), THEN (2), ELSIF B tested 4 times, taken once
         30: 6, 31: 0, 33: 6}                       # IF N > 100 never taken; the FB call
ARMS = {8: [1, 2, 3],          # CASE 1, CASE 2, 3, ELSE
        25: [2, 1, 3],         # THEN, ELSIF, the ELSE not written (6 - 2 - 1)
        30: [0, 6]}            # THEN, the ELSE not written


def run_known_paths(folder: Path, backend: str) -> dict:
    src = write_st(PROGRAM, folder / "src")
    res = build(src, backend=backend, cache_dir=folder / "cache", coverage=True)
    first = Plc(res)
    first.step(3)
    first["CONFIG0.RES0.INST0.A"] = True
    first.step(2)
    second = Plc(res)
    second["CONFIG0.RES0.INST0.B"] = True
    second.step(1)
    collect.dump(folder / "data")
    return report.read(folder / "data")


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_known_paths_give_exact_counts(backend, tmp_path):
    files = run_known_paths(tmp_path, backend)
    (cov,) = files.values()
    assert cov.path.name == "prog.st"
    assert cov.lines == LINES
    assert {d.line: counts for d, counts in cov.branches()} == ARMS
    t = cov.totals()
    assert (t.lines, t.lines_hit, t.branches, t.branches_hit) == (11, 10, 8, 7)
    fb, main = cov.totals("FB_Pick"), cov.totals("Main")
    assert (fb.lines, fb.lines_hit, fb.branches, fb.branches_hit) == (4, 4, 3, 3)
    assert (main.lines, main.lines_hit, main.branches, main.branches_hit) == (7, 6, 5, 4)
    table = report.summary(files, tmp_path / "src")
    assert "prog.st" in table and "PROGRAM Main" in table
    assert table.splitlines()[-1].split()[1:] == ["10/11", "90.9%", "7/8", "87.5%"]


@requires_matiec
def test_backends_agree(tmp_path):
    builtin = run_known_paths(tmp_path / "builtin", "builtin")
    matiec = run_known_paths(tmp_path / "matiec", "matiec")
    (b,), (m,) = builtin.values(), matiec.values()
    assert m.lines == b.lines
    assert [c for _, c in m.branches()] == [c for _, c in b.branches()]


def test_reports_cobertura_and_html(tmp_path):
    files = run_known_paths(tmp_path, "builtin")
    written = report.write_reports(files, tmp_path / "out", tmp_path / "src")
    root = etree.parse(str(written["cobertura"])).getroot()
    assert root.tag == "coverage"
    assert (root.get("lines-valid"), root.get("lines-covered")) == ("11", "10")
    assert (root.get("branches-valid"), root.get("branches-covered")) == ("8", "7")
    (cls,) = root.iter("class")
    assert cls.get("filename") == "prog.st"
    assert {m.get("name") for m in cls.iter("method")} == {"FB_Pick", "Main"}
    hits = {int(x.get("number")): int(x.get("hits")) for x in cls.find("lines").iter("line")}
    assert hits == LINES
    ifline = next(x for x in cls.find("lines").iter("line") if x.get("number") == "25")
    assert ifline.get("branch") == "true" and ifline.get("condition-coverage") == "100% (3/3)"
    page = next(p for p in written["html"].parent.glob("index.prog.st.*.html"))
    rows = {}
    for tr in lxml.html.parse(str(page)).getroot().iter("tr"):
        cells = tr.findall("td")
        if len(cells) == 4:
            rows[int(cells[0].text_content())] = (cells[2].text_content().strip(), cells[3].text_content().strip())
    assert set(range(1, len(PROGRAM.splitlines()) + 1)) <= set(rows)  # the whole ST source, annotated
    assert rows[28] == ("1", "N := N + 2;") and rows[30] == ("6", "IF N > 100 THEN")
    assert rows[31] == ("\u2717", "N := 0;")                       # not run: gcovr marks it
    assert rows[2] == ("", "VAR_INPUT")                             # no code


def test_arms_of_one_line_if_and_empty_arms():
    st = arms.StFile(Path("x.st"), [], [])
    d = arms.Decision("IF", 5, "P", (arms.Arm("THEN", 5), arms.Arm("ELSE (none written)", None)))
    # the THEN's statement on the IF's line: its count is not the line's; with the ELSE not written both
    # are unknown, so they are left out
    assert d.counts({5: 4}) == [None, None]
    d = arms.Decision("IF", 5, "P", (arms.Arm("THEN", 6), arms.Arm("ELSE", None)))
    assert d.counts({5: 4, 6: 1}) == [1, 3]
    assert st.pou_at(1) is None


def test_coverage_build_is_keyed_and_mapped(tmp_path):
    src = write_st(PROGRAM, tmp_path / "src")
    plain = build(src, backend="builtin", cache_dir=tmp_path / "cache", coverage=False)
    cov = build(src, backend="builtin", cache_dir=tmp_path / "cache", coverage=True)
    assert plain.library != cov.library and cov.coverage and not plain.coverage
    assert list(cov.library.parent.glob("*.gcno")) and collect.is_coverage_build(cov.library.parent)
    assert not list(plain.library.parent.glob("*.gcno")) and not collect.is_coverage_build(plain.library.parent)
    assert "#line" not in "".join(p.read_text() for p in plain.c_dir.glob("*.c"))
    c = "".join(p.read_text() for p in cov.c_dir.glob("*.c"))
    assert f'#line 28 "{src}"' in c or '#line 28 "prog.st"' in c


PROJECT_TEST = '''
def test_runs(plc):
    plc.step(2)
    plc["CONFIG0.RES0.INST0.A"] = True
    plc.step(1)
    assert plc["CONFIG0.RES0.INST0.N"] == 1
'''


@pytest.mark.parametrize("workers", [[], ["-n", "2"]], ids=["one process", "xdist"])
def test_pytest_option_end_to_end(pytester, workers):
    pytester.makefile(".st", prog=PROGRAM)
    pytester.makepyfile(test_prog=textwrap.dedent(PROJECT_TEST))
    pytester.makeini("[pytest]\nlinmot_st_entry = prog.st\nlinmot_st_backend = builtin\n")
    result = pytester.runpytest_subprocess("--linmot-cov", "-p", "no:cacheprovider", *workers)
    result.assert_outcomes(passed=1)
    # 3 scans: the THEN once, the ELSIF tested twice and never taken (line 28 not run), N > 100 never;
    # CASE: 0 (ELSE) twice, 1 once, 2/3 never (line 12). Arms: 2 of 3, 1 of 2, 2 of 3
    result.stdout.fnmatch_lines(["*linmot-st: ST coverage*", "prog.st * 8/11 * 72.7% * 5/8 * 62.5%*",
                                 "*FUNCTION_BLOCK FB_Pick * 3/4 * 2/3 *", "*PROGRAM Main * 5/7 * 3/5 *",
                                 "TOTAL * 8/11 *", "cobertura: *coverage.xml"])
    assert (pytester.path / "build" / "st-coverage" / "html" / "index.html").is_file()


# The C iec2c writes for MAIN's body with `-O l` (the shape of generate_c_st.cc: a directive per statement
# of a statement list, none for `} else if`), FB call on two C lines
MATIEC_C = """\
void MAIN_body__(MAIN *data__) {
#line 25 "prog.st"
  if (__GET_VAR(data__->A,)) {
#line 26 "prog.st"
    __SET_VAR(data__->,N,,(__GET_VAR(data__->N,) + 1));
  } else if (__GET_VAR(data__->B,)) {
#line 28 "prog.st"
    __SET_VAR(data__->,N,,(__GET_VAR(data__->N,) + 2));
  }
#line 33 "prog.st"
  __SET_VAR(data__->CHOOSER.,MODE,,__GET_VAR(data__->N,));
  FB_PICK_body__(&data__->CHOOSER);
  goto __end;
}
"""


def test_matiec_line_directives_made_exact(tmp_path):
    from linmot_st.toolchain.matiec import line_map
    src = write_st(PROGRAM, tmp_path)
    assert line_map.elsif_lines(src) == [27]
    out = line_map.exact_lines(MATIEC_C, line_map.elsif_table(tmp_path, [src]), "POUS.c").split("\n")
    at = {line.strip(): out[k - 1] for k, line in enumerate(out) if not line.startswith("#")}
    assert at["} else if (__GET_VAR(data__->B,)) {"] == '#line 27 "prog.st"'          # the ELSIF's own line
    assert at["FB_PICK_body__(&data__->CHOOSER);"] == '#line 33 "prog.st"'           # not 34
    assert at["goto __end;"] == '#line 33 "prog.st"'
    # after the function: the C file's own numbering (the directive numbers the line after it)
    assert out[-2] == f'#line {len(out)} "POUS.c"' and out[-3] == "}"
    # a directive only where a statement starts: never inside a call spread over lines
    multi = '#line 5 "prog.st"\n  F(a,\n    b);\n  x = 1;\n'
    macro = '#line 5 "prog.st"\n  x = 1;\n#define M(a) \\\n  f(a); \\\n  g(a);\n  y = 2;\n'
    assert line_map.exact_lines(macro, lambda name: [], "POUS.c").split("\n") == [
        '#line 5 "prog.st"', "  x = 1;", "#define M(a) \\", "  f(a); \\", "  g(a);", '#line 5 "prog.st"',
        "  y = 2;", ""]
    assert line_map.exact_lines(multi, lambda name: [], "POUS.c").split("\n") == [
        '#line 5 "prog.st"', "  F(a,", "    b);", '#line 5 "prog.st"', "  x = 1;", ""]
