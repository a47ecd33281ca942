"""The builtin compiler's front end: syntax errors, the checker's rejections, diagnostics and includes.

These run the parser and checker only (no C compiler). Cases that MatIEC must reject as well live in
tests/conformance/cases (reject_*), where they run on both backends.
"""

from __future__ import annotations

import re
import textwrap
from pathlib import Path

import pytest

from linmot_st.toolchain.builtin import BuiltinCompileError, check_text, compile_to_c
from repo_paths import CONFORMANCE_CASES, REPO

DIAG = re.compile(r"^(?P<file>[^:]+):(?P<line>\d+):(?P<col>\d+): error: (?P<msg>.+)$")


def errors(src: str, name: str = "t.st") -> list[str]:
    with pytest.raises(BuiltinCompileError) as info:
        check_text(textwrap.dedent(src), name)
    lines = str(info.value).splitlines()
    for line in lines:
        assert DIAG.match(line), f"not file:line:col: error: message -> {line!r}"
    assert [str(d) for d in info.value.diagnostics] == lines
    return lines


def one_error(src: str) -> str:
    errs = errors(src)
    return errs[0]


def prog(body: str, decls: str = "", vars_: str = "i : INT; d : DINT;") -> str:
    return f"{decls}\nPROGRAM pp\n  VAR {vars_} END_VAR\n{body}\nEND_PROGRAM\n"


def test_accepts_a_small_program():
    check_text(prog("  i := i + 1;\n  d := INT_TO_DINT(i) * 2;"))


# ---------------------------------------------------------------- syntax

def test_syntax_error_position():
    e = one_error("PROGRAM pp\n  VAR i : INT; END_VAR\n  i := ;\nEND_PROGRAM\n")
    assert e.startswith("t.st:3:8: error: syntax error")


def test_unterminated_comment():
    e = one_error("PROGRAM pp\n  VAR i : INT; END_VAR\n  (* no end\n  i := 1;\nEND_PROGRAM\n")
    assert e == "t.st:3:3: error: unterminated comment: '(*' has no matching '*)'"


def test_unexpected_end_of_file():
    assert "unexpected end of file" in one_error("PROGRAM pp\n  VAR i : INT; END_VAR\n  i := 1;\n")


def test_reserved_word_in_declaration():
    assert "reserved word" in one_error(prog("  i := 1;", vars_="i : INT; then : INT;"))


def test_nested_comments_are_not_supported():
    # MatIEC without -n: the first *) ends the comment, the rest is a syntax error
    assert "syntax error" in one_error("PROGRAM pp\n  VAR i : INT; END_VAR\n  (* a (* b *) c *)\n  i := 1;\nEND_PROGRAM\n")


# ---------------------------------------------------------------- typing

@pytest.mark.parametrize("stmt, message", [
    ("i := d;", "type mismatch, expected INT, found DINT; convert explicitly, e.g. DINT_TO_INT(...)"),
    ("i := 40000;", "the value 40000 does not fit INT (-32768..32767)"),
    ("i := 1.5;", "expected INT, found real literal"),
    ("i := TRUE;", "expected INT, found BOOL"),
    ("i := i + 1.0;", "type mismatch: INT + real literal"),
    ("d := 3 / 0;", "division by zero"),
    ("i := 2 ** 3;", "'**' needs a REAL or LREAL base"),
    ("i := NOT i;", "NOT needs a bit string"),
    ("i := SQRT(4);", "SQRT needs a REAL or LREAL"),
    ("i := LEN(i);", "argument of LEN: type mismatch, expected STRING, found INT"),
    ("i := MAX(i, d);", "MAX: arguments of different types (INT and DINT)"),
    ("i := ADD_INT(i, d);", "argument of ADD_INT: type mismatch, expected INT, found DINT"),
    ("i := INT_TO_DINT(i);", "type mismatch, expected INT, found DINT"),
    ("i := SEL(i, 1, 2);", "G of SEL: type mismatch, expected BOOL, found INT"),
    ("i := MUX(1.0, 1, 2);", "K of MUX must be an integer"),
    ("i := LIMIT(0, i);", "LIMIT takes 3 arguments, 2 given"),
    ("i := FOO(1);", "unknown function 'FOO'"),
    ("i := SIZEOF(i);", "SIZEOF is outside the supported subset"),
    ("i := TON(1);", "'TON' is a function block, not a function"),
    ("IF i THEN i := 1; END_IF;", "IF condition: type mismatch, expected BOOL, found INT"),
    ("WHILE 1.0 DO i := 1; END_WHILE;", "expected BOOL, found real literal"),
    ("FOR d := 1 TO i DO i := 1; END_FOR;", "FOR end value: type mismatch, expected DINT, found INT"),
    ("CASE i OF 1..0: i := 1; END_CASE;", "empty CASE range 1..0"),
    ("CONTINUE;", "CONTINUE outside a loop"),
    ("i := %IW3;", "use a located variable"),
    ("i := i.3;", "bit access (x.3) is outside the supported subset"),
    ("i := 'abc';", "expected INT, found STRING"),
    ("d := T#1s;", "expected DINT, found TIME"),
    ("i := EN;", "'EN' is not declared in pp"),
])
def test_type_errors(stmt, message):
    e = one_error(prog("  " + stmt))
    assert message in e, e
    assert e.startswith("t.st:4:")


def test_every_error_of_a_body_is_reported():
    errs = errors(prog("  i := d;\n  d := i;\n  i := zz;"))
    assert [DIAG.match(e)["line"] for e in errs] == ["4", "5", "6"]


def test_literals_take_the_type_of_their_context():
    check_text(prog("  b := 16#FF;\n  w := 2#1010 OR 16#F0;\n  x := 1;\n  r := 1.0 / 3.0;\n  l := -9223372036854775808;",
                    vars_="b : BYTE; w : WORD; x : BOOL; r : REAL; l : LINT;"))


def test_a_signed_literal_fits_while_a_negated_one_does_not():
    check_text(prog("  i := -32768;"))
    assert "does not fit INT" in one_error(prog("  i := -(32768);"))


# ---------------------------------------------------------------- declarations

def test_declaration_before_use():
    e = one_error("PROGRAM pp\n  VAR x : later; END_VAR\n  x.a := 1;\nEND_PROGRAM\n"
                  "TYPE later : STRUCT a : INT; END_STRUCT; END_TYPE\n")
    assert "unknown type 'later' (types must be declared before they are used)" in e


def test_duplicate_variable():
    assert "duplicate declaration of 'i'" in one_error(prog("  i := 1;", vars_="i : INT; i : DINT;"))


def test_variable_with_the_name_of_a_pou():
    src = "FUNCTION f : INT\n  VAR_INPUT a : INT; END_VAR\n  f := a;\nEND_FUNCTION\n" + prog("  f := 1;", vars_="f : INT;")
    assert "has the name of a POU" in one_error(src)


def test_function_needs_a_return_type():
    assert "needs a return type" in one_error("FUNCTION f\n  VAR_INPUT a : INT; END_VAR\n  a := 1;\nEND_FUNCTION\n")


def test_function_cannot_hold_fb_instances():
    assert "cannot hold function block instances" in one_error(
        "FUNCTION f : INT\n  VAR t : TON; END_VAR\n  f := 1;\nEND_FUNCTION\n")


def test_array_bounds_must_be_literals():
    assert "array bounds must be integer literals" in one_error(prog("  i := 1;", vars_="a : ARRAY[0..N] OF INT; i : INT;"))


def test_array_index_literal_out_of_range():
    assert "index 5 is outside 0..3" in one_error(prog("  a[5] := 1;", vars_="a : ARRAY[0..3] OF INT;"))


def test_wrong_number_of_indices():
    assert "has 2 dimension(s), 1 index(es) given" in one_error(prog("  a[1] := 1;", vars_="a : ARRAY[0..3, 0..1] OF INT;"))


def test_too_many_initial_values():
    assert "too many initial values: 3 for 2 elements" in one_error(
        prog("  a[0] := 1;", vars_="a : ARRAY[0..1] OF INT := [1, 2, 3];"))


def test_initial_value_must_be_a_literal():
    assert "an initial value must be a literal" in one_error(prog("  i := 1;", vars_="i : INT := 1 + 2;"))


def test_subrange_initial_value_out_of_range():
    assert "does not fit" in one_error(prog("  i := 1;", vars_="i : INT(0..10) := 11;"))


def test_external_without_global():
    src = prog("  g := 1;", vars_="i : INT;").replace("END_VAR\n", "END_VAR\n  VAR_EXTERNAL g : INT; END_VAR\n", 1) + \
        "CONFIGURATION c\n  RESOURCE r ON PLC\n    TASK t(INTERVAL := T#10ms, PRIORITY := 0);\n" \
        "    PROGRAM i1 WITH t : pp;\n  END_RESOURCE\nEND_CONFIGURATION\n"
    assert "VAR_EXTERNAL 'g' of pp has no VAR_GLOBAL in resource r" in one_error(src)


def test_external_of_a_constant_global_must_be_constant():
    src = prog("  i := g;").replace("END_VAR\n", "END_VAR\n  VAR_EXTERNAL g : INT; END_VAR\n", 1) + \
        "CONFIGURATION c\n  VAR_GLOBAL CONSTANT g : INT := 1; END_VAR\n  RESOURCE r ON PLC\n" \
        "    TASK t(INTERVAL := T#10ms, PRIORITY := 0);\n    PROGRAM i1 WITH t : pp;\n  END_RESOURCE\nEND_CONFIGURATION\n"
    assert "declare it VAR_EXTERNAL CONSTANT" in one_error(src)


def test_unknown_task():
    src = prog("  i := 1;") + "CONFIGURATION c\n  RESOURCE r ON PLC\n    TASK t(INTERVAL := T#10ms, PRIORITY := 0);\n" \
        "    PROGRAM i1 WITH nope : pp;\n  END_RESOURCE\nEND_CONFIGURATION\n"
    assert "unknown task 'nope'" in one_error(src)


def test_located_size_must_match():
    e = one_error("PROGRAM pp\n  VAR\n    w AT %IW2 : DINT;\n  END_VAR\n  VAR i : INT; END_VAR\n  i := 1;\nEND_PROGRAM\n")
    assert "the size of %IW2 does not match the type DINT" in e


def test_fb_call_argument_errors():
    assert "TON has no parameter 'XY'" in one_error(prog("  t(XY := TRUE);", vars_="t : TON;"))
    assert "'Q' is an output: use =>" in one_error(prog("  t(Q := x);", vars_="t : TON; x : BOOL;"))
    assert "mixes formal" in one_error(prog("  t(TRUE, PT := T#1s);", vars_="t : TON;"))
    assert "parameter 'PT' of TON: type mismatch, expected TIME, found INT" in one_error(
        prog("  t(PT := i);", vars_="t : TON; i : INT;"))


def test_in_out_needs_a_variable():
    src = "FUNCTION f : INT\n  VAR_IN_OUT v : INT; END_VAR\n  f := v;\nEND_FUNCTION\n" + prog("  i := f(v := i + 1);")
    assert "a variable is required here" in one_error(src)


def test_user_pou_cannot_redefine_a_standard_block():
    assert "is the name of a standard function block" in one_error(
        "FUNCTION_BLOCK TON\n  VAR x : INT; END_VAR\n  x := 1;\nEND_FUNCTION_BLOCK\n")


# ---------------------------------------------------------------- includes and file names

def test_included_files_keep_their_names_and_lines(tmp_path: Path):
    (tmp_path / "lib").mkdir()
    (tmp_path / "lib" / "types.st").write_text("TYPE t_ok : INT; END_TYPE\n")
    (tmp_path / "lib" / "bad.st").write_text("(* a comment *)\nFUNCTION f : INT VAR_INPUT a : INT; END_VAR\n  f := zz;\nEND_FUNCTION\n")
    entry = tmp_path / "main.st"
    entry.write_text('{#include "lib/types.st"}\n{#include "lib/bad.st"}\nPROGRAM pp\n  VAR i : t_ok; END_VAR\n'
                     '  i := q;\nEND_PROGRAM\n')
    with pytest.raises(BuiltinCompileError) as info:
        compile_to_c(entry, tmp_path, tmp_path / "out")
    assert [str(d) for d in info.value.diagnostics] == [
        "lib/bad.st:3:8: error: 'zz' is not declared in f",
        "main.st:5:8: error: 'q' is not declared in pp",
    ]


def test_missing_include(tmp_path: Path):
    entry = tmp_path / "main.st"
    entry.write_text('(* x *)\n{#include "nope.st"}\n')
    with pytest.raises(BuiltinCompileError) as info:
        compile_to_c(entry, tmp_path, tmp_path / "out")
    assert str(info.value).startswith('main.st:2:1: error: cannot find included file "nope.st"')


def test_include_cycle(tmp_path: Path):
    (tmp_path / "a.st").write_text('{#include "b.st"}\n')
    (tmp_path / "b.st").write_text('{#include "a.st"}\n')
    with pytest.raises(BuiltinCompileError) as info:
        compile_to_c(tmp_path / "a.st", tmp_path, tmp_path / "out")
    assert "include cycle" in str(info.value)


def test_sources_lists_every_file_read(tmp_path: Path):
    (tmp_path / "inc.st").write_text("TYPE t_i : INT; END_TYPE\n")
    entry = tmp_path / "main.st"
    entry.write_text('{#include "inc.st"}\n')
    out = compile_to_c(entry, tmp_path, tmp_path / "out")
    assert out.sources == [entry, tmp_path / "inc.st"]
    assert out.manifest.is_file() and out.header.is_file() and all(p.is_file() for p in out.c_files)


def test_other_pragmas_are_rejected():
    e = one_error("{attribute 'hide'}\nTYPE t_a : INT; END_TYPE\n")
    assert "pragma \"{attribute 'hide'}\" is outside the supported subset" in e
    assert "{disable code generation} and {enable code generation} are supported" in e


def test_code_generation_pragmas_are_matiecs_spelling_in_any_case():
    check_text("{Disable Code Generation}\nTYPE t_a : INT; END_TYPE\n{ENABLE CODE GENERATION}\n")
    assert "pragma" in one_error("{disable  code generation}\nTYPE t_a : INT; END_TYPE\n")


def test_the_library_passes_the_checker():
    root = REPO
    from linmot_st.toolchain.builtin.checker import Checker
    from linmot_st.toolchain.builtin.loader import load
    elements, files, names = load(root / "st_lib" / "linmot.st", root)
    prog_ = Checker().check(elements, names)
    assert len(files) > 10 and any(p.kind == "FUNCTION_BLOCK" for p in prog_.pous)


def test_mutated_sources_never_crash_the_compiler():
    """Random token deletions, duplications and swaps in the conformance cases: the compiler either
    generates C or reports diagnostics; it never fails with another exception."""
    import random

    from linmot_st.toolchain.builtin.checker import Checker
    from linmot_st.toolchain.builtin.codegen import CodeGen
    from linmot_st.toolchain.builtin.parser import parse
    rng = random.Random(61131)
    cases = sorted((CONFORMANCE_CASES).glob("*.st"))
    assert cases
    for path in cases:
        toks = re.findall(r"\w+|[^\w\s]+|\s+", path.read_text())
        for _ in range(8):
            t = list(toks)
            i, j = rng.randrange(len(t)), rng.randrange(len(t))
            op = rng.random()
            if op < 0.4:
                del t[i]
            elif op < 0.7:
                t.insert(i, t[j])
            else:
                t[i], t[j] = t[j], t[i]
            text = "".join(t)
            try:
                CodeGen(Checker().check(parse(text, "m.st"), ["m.st"]), "test").generate()
            except BuiltinCompileError as exc:
                assert exc.diagnostics and all(DIAG.match(str(d)) for d in exc.diagnostics), text
