"""What MatIEC refuses and the builtin compiler once took (issue 13, part A), in the places the conformance
cases (tests/conformance/cases/reject_*) do not reach: each kind of block, each place a name can take, a
library without a CONFIGURATION, and one error for one problem (parser and checker only). Where MatIEC is
installed, iec2c + gcc show the same in each place, and the stored lists (C macros, MatIEC's own blocks) are
derived again from its headers and library.
"""

from __future__ import annotations

import pytest

from linmot_st.toolchain.builtin import BuiltinCompileError, check_text, stdfb
from linmot_st.toolchain.builtin.matiec_c_macros import names as c_macro_names
from linmot_st.toolchain.testing import requires_matiec
from name_places import name_places

PLACES, MAIN, CONFIG, NAMES = name_places("rf")
# where iec2c's C holds the name as it is (tests/test_builtin_c_macros.py shows it with iec2c + gcc)
C_NAMED = {"function block", "function", "program", "type", "variable", "output", "field", "task"}
# where MatIEC refuses the name of one of its library's blocks (everywhere but a field)
BLOCK_NAMED = set(PLACES) - {"field"}


def source(place: str, name: str) -> str:
    src = PLACES[place].replace("{n}", name)
    return src if "CONFIGURATION" in src else src + CONFIG.format(**NAMES)


def diagnostics(src: str) -> list[str]:
    with pytest.raises(BuiltinCompileError) as info:
        check_text(src, "rf.st")
    return [str(d) for d in info.value.diagnostics]


@pytest.mark.parametrize("place", PLACES)
def test_c_macro_names_are_refused_where_matiecs_c_holds_them(place):
    for name in ("Nan", "M_PI", "EOF"):
        if place in C_NAMED:
            (msg,) = diagnostics(source(place, name))
            assert "it is a C macro of the headers MatIEC's generated C includes" in msg
        else:
            check_text(source(place, name))


def test_the_c_macro_list_holds_the_well_known_ones():
    assert {"NAN", "INFINITY", "EOF", "INT_MAX", "HUGE_VAL", "M_PI", "FLT_MAX", "BUFSIZ", "RAND_MAX",
            "CHAR_BIT"} <= c_macro_names()
    assert not {"INT", "TON", "X", "SPEED"} & c_macro_names()


@pytest.mark.parametrize("block", sorted(stdfb.NON_STANDARD))
@pytest.mark.parametrize("place", PLACES)
def test_matiecs_own_blocks_cannot_name_things(place, block):
    src = source(place, block.lower())
    if place in BLOCK_NAMED:
        (msg,) = diagnostics(src)
        assert "of MatIEC's own library" in msg
    else:
        check_text(src)


@pytest.mark.parametrize("kind", ["FUNCTION_BLOCK", "PROGRAM"])
@pytest.mark.parametrize("block", ["VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR", "VAR_TEMP"])
def test_a_variable_named_like_its_own_pou(kind, block):
    src = (f"{kind} rf_self\n  VAR_INPUT a : INT; END_VAR\n  {block} rf_self : INT; END_VAR\n  a := a;\n"
           f"END_{kind}\n" + MAIN + CONFIG.format(**NAMES))
    (msg,) = diagnostics(src)
    assert msg.startswith(f"rf.st:3:{len(block) + 4}: error: variable 'rf_self' has the name of its own {kind}")


def test_a_functions_result_is_still_its_name():
    check_text("FUNCTION rf_f : INT\n  VAR_INPUT a : INT; END_VAR\n  rf_f := a;\nEND_FUNCTION\n" + MAIN)


@pytest.mark.parametrize("kind", ["FUNCTION rf_nv : INT", "FUNCTION_BLOCK rf_nv", "PROGRAM rf_nv"])
def test_a_pou_without_any_var_block(kind):
    end = "END_" + kind.split()[0]
    body = "rf_nv := 1;" if kind.startswith("FUNCTION ") else "RETURN;"
    use = ("rf_f := rf_nv(1);" if kind.startswith("FUNCTION ") else "rf_i(a := 1);")   # adds no error
    user = ("FUNCTION_BLOCK rf_user\n  VAR_INPUT a : INT; END_VAR\n  VAR rf_f : INT; rf_i : rf_nv; END_VAR\n"
            f"  {use}\nEND_FUNCTION_BLOCK\n")
    (msg,) = diagnostics(f"{kind}\n  {body}\n{end}\n" + user + MAIN)
    assert msg.startswith("rf.st:1:") and "declares no variables: MatIEC's grammar needs" in msg


@pytest.mark.parametrize("block", ["VAR", "VAR_INPUT", "VAR_OUTPUT", "VAR_IN_OUT", "VAR_TEMP", "VAR CONSTANT"])
def test_empty_blocks(block):
    (msg,) = diagnostics(f"FUNCTION_BLOCK rf_e\n  VAR_INPUT a : INT; END_VAR\n  {block} END_VAR\n  a := a;\n"
                         f"END_FUNCTION_BLOCK\n" + MAIN)
    assert msg.startswith("rf.st:3:3: error: an empty ") and "MatIEC refuses a block that declares no variable" in msg


def empty_globals(where: str) -> str:
    """A program and a CONFIGURATION with an empty VAR_GLOBAL block in it (glob) or in its resource (res)."""
    src = MAIN + CONFIG.format(**{**NAMES, "glob": "VAR_GLOBAL END_VAR\n  "})
    if where == "res":
        src = src.replace("VAR_GLOBAL END_VAR\n  RESOURCE rf_res ON PLC\n", "RESOURCE rf_res ON PLC\n    VAR_GLOBAL END_VAR\n")
    return src


@pytest.mark.parametrize("where", ["glob", "res"])
def test_empty_global_blocks(where):
    (msg,) = diagnostics(empty_globals(where))
    assert "an empty VAR_GLOBAL ... END_VAR block: MatIEC refuses" in msg


def test_var_temp_in_a_function_is_one_error():
    (msg,) = diagnostics("FUNCTION rf_t : INT\n  VAR_INPUT a : INT; END_VAR\n  VAR_TEMP t : INT; END_VAR\n  t := a;\n"
                         "  rf_t := t;\nEND_FUNCTION\n" + MAIN)
    assert msg.startswith("rf.st:3:3: error: VAR_TEMP is not allowed in a FUNCTION: MatIEC refuses it")


def test_var_temp_is_fine_outside_functions():
    check_text("FUNCTION_BLOCK rf_t\n  VAR_INPUT a : INT; END_VAR\n  VAR_TEMP t : INT; END_VAR\n  t := a;\n"
               "END_FUNCTION_BLOCK\n" + MAIN)


@pytest.mark.parametrize("literal", ["STRING#'x'", "STRING#''"])
def test_typed_string_literals_everywhere(literal):
    for src in (f"PROGRAM rf_main\n  VAR s : STRING := {literal}; END_VAR\n  s := 'a';\nEND_PROGRAM\n",
                f"PROGRAM rf_main\n  VAR s : STRING; b : BOOL; END_VAR\n  b := s = {literal};\nEND_PROGRAM\n"):
        (msg,) = diagnostics(src)
        assert "a typed string literal is outside the supported subset" in msg


def test_non_ascii_only_inside_string_literals():
    (msg,) = diagnostics("PROGRAM rf_main\n  VAR s : STRING := 'gr\u00fc\u00dfe'; END_VAR\n  s := 'a';\nEND_PROGRAM\n")
    assert msg.startswith("rf.st:2:21: error: ") and "non-ASCII character '\u00fc'" in msg
    check_text("(* gr\u00fc\u00dfe *)\nPROGRAM rf_main\n  VAR s : STRING := '$FC'; END_VAR\n  s := 'a';\nEND_PROGRAM\n")


def test_external_without_any_configuration():
    """A library (no CONFIGURATION) whose block reads a global: iec2c takes it, its C does not compile."""
    (msg,) = diagnostics("FUNCTION_BLOCK rf_ext\n  VAR_EXTERNAL g_rf : INT; END_VAR\n  g_rf := g_rf + 1;\n"
                         "END_FUNCTION_BLOCK\n")
    assert msg.startswith("rf.st:2:16: error: VAR_EXTERNAL 'g_rf' of rf_ext: there is no CONFIGURATION")


def test_external_backed_by_a_global_of_any_resource():
    check_text("FUNCTION_BLOCK rf_ext\n  VAR_EXTERNAL g_rf : INT; END_VAR\n  g_rf := g_rf + 1;\nEND_FUNCTION_BLOCK\n"
               + MAIN + CONFIG.format(**{**NAMES, "glob": "VAR_GLOBAL g_rf : INT; END_VAR\n  "}))


def test_a_program_instance_without_its_global_is_reported_once():
    src = ("PROGRAM rf_main\n  VAR_EXTERNAL g_rf : INT; END_VAR\n  g_rf := 1;\nEND_PROGRAM\n"
           + CONFIG.format(**NAMES))
    (msg,) = diagnostics(src)
    assert "has no VAR_GLOBAL in resource" in msg


@pytest.mark.parametrize("name", ["P", "TON", "Rtc", "Eof"])
def test_a_refused_program_name_is_one_error(name):
    src = f"PROGRAM {name}\n  VAR x : INT; END_VAR\n  x := 1;\nEND_PROGRAM\n" + MAIN + CONFIG.format(
        **NAMES).replace(" : rf_main;", f" : {name};")
    (msg,) = diagnostics(src)
    assert msg.startswith("rf.st:1:9: error: ")


@pytest.mark.parametrize("name", ["Eof", "Rtc"])
def test_a_refused_task_name_is_one_error(name):
    (msg,) = diagnostics(source("task", name))
    assert msg.startswith("rf.st:") and name in msg


def test_incomplete_program_is_one_error():
    assert diagnostics("PROGRAM P\n") == ["rf.st:1:9: error: syntax error: unexpected end of file"]


@pytest.mark.parametrize("where, pos", [
    ("{{ int c_only; }}\n" + MAIN, "1:1"),
    ("PROGRAM rf_main\n  VAR i : INT; END_VAR\n  {{ if (1) { i = 2; } }}\n  i := 1;\nEND_PROGRAM\n", "3:3"),
    ("PROGRAM rf_main\n  VAR i : INT; {{ int x; }} END_VAR\n  i := 1;\nEND_PROGRAM\n", "2:16"),
])
def test_c_pragmas_get_their_own_message(where, pos):
    (msg,) = diagnostics(where)
    assert msg.startswith(f"rf.st:{pos}: error: C pragmas ({{{{ ... }}}}) are not supported by the builtin")


def test_other_pragmas_keep_their_message():
    (msg,) = diagnostics("PROGRAM rf_main\n  VAR i : INT; END_VAR\n  { something }\n  i := 1;\nEND_PROGRAM\n")
    assert "pragmas in a body (C code) are outside the supported subset" in msg


def test_a_missing_global_accessor_is_explained_as_such():
    from linmot_st.toolchain.matiec.backend import explain_c_errors
    line = "accessor.h:71:30: error: implicit declaration of function '__GET_GLOBAL_G1' [-Werror=implicit-function-declaration]"
    notes = explain_c_errors([line])[1:]
    assert len(notes) == 1 and "no VAR_GLOBAL G1 in the CONFIGURATION" in notes[0]
    wrapper = "x.c:9:5: error: implicit declaration of function '__MAIN_MOVE_INT2' [-Werror=implicit-function-declaration]"
    assert "call wrapper" in explain_c_errors([wrapper])[1]


# ---- MatIEC, where installed: what it does with each of these ------------------------------------------

def matiec_builds(src: str, folder) -> bool:
    from linmot_st.toolchain import CompileError
    from linmot_st.toolchain.testing import build_text
    try:
        build_text(src, folder, "matiec", name="rf.st")
    except CompileError:
        return False
    return True


@requires_matiec
@pytest.mark.matiec
def test_stored_c_macros_hold_every_one_this_host_defines():
    from linmot_st.toolchain import matiec
    from linmot_st.toolchain.builtin.matiec_c_macros import derive
    from linmot_st.toolchain.cc import find_compiler
    missing = set(derive(matiec.find().include, find_compiler().path)) - c_macro_names()
    assert not missing, f"regenerate matiec_c_macros.json (see matiec_c_macros.py): {sorted(missing)}"


@requires_matiec
@pytest.mark.matiec
@pytest.mark.parametrize("name", ["NAN", "INFINITY", "EOF", "INT_MAX", "HUGE_VAL", "M_PI", "FLT_MAX", "BUFSIZ",
                                  "RAND_MAX", "CHAR_BIT", "Seek_Set", "IEC_TYPES_H"])
def test_c_macro_names_break_matiecs_c(name, tmp_path):
    """iec2c takes the program; gcc does not compile its C. A plain name in the same place builds."""
    assert not matiec_builds(source("variable", name), tmp_path / "macro")
    assert matiec_builds(source("variable", name + "_X"), tmp_path / "plain")


@requires_matiec
@pytest.mark.matiec
@pytest.mark.parametrize("place", PLACES)
def test_matiec_agrees_on_the_places_of_c_macro_names(place, tmp_path):
    assert matiec_builds(source(place, "Eof"), tmp_path) == (place not in C_NAMED)


@requires_matiec
@pytest.mark.matiec
@pytest.mark.parametrize("place", PLACES)
def test_matiec_agrees_on_the_places_of_block_names(place, tmp_path):
    assert matiec_builds(source(place, "Rtc"), tmp_path) == (place not in BLOCK_NAMED)


@requires_matiec
@pytest.mark.matiec
def test_matiecs_own_blocks_are_those_beyond_the_standard():
    """stdfb.NON_STANDARD is what MatIEC's lib/*.txt declares beyond the IEC blocks the builtin provides."""
    import re

    from linmot_st.toolchain import matiec
    declared = set()
    for path in matiec.find().lib.glob("*.txt"):
        text = re.sub(r"\(\*.*?\*\)", " ", path.read_text(errors="replace"), flags=re.S)
        declared |= {m.upper() for m in re.findall(r"(?im)^\s*FUNCTION_BLOCK\s+(\w+)", text)}
    assert declared - stdfb.names() == stdfb.NON_STANDARD


@requires_matiec
@pytest.mark.matiec
@pytest.mark.parametrize("kind", ["FUNCTION rf_nv : INT", "FUNCTION_BLOCK rf_nv", "PROGRAM rf_nv"])
def test_matiec_refuses_a_pou_without_any_var_block(kind, tmp_path):
    end = "END_" + kind.split()[0]
    body = "rf_nv := 1;" if kind.startswith("FUNCTION ") else "RETURN;"
    assert not matiec_builds(f"{kind}\n  {body}\n{end}\n" + MAIN + CONFIG.format(**NAMES), tmp_path)


@requires_matiec
@pytest.mark.matiec
@pytest.mark.parametrize("where", ["glob", "res"])
def test_matiec_refuses_empty_global_blocks(where, tmp_path):
    assert not matiec_builds(empty_globals(where), tmp_path)


@requires_matiec
@pytest.mark.matiec
def test_matiec_backend_names_the_external_without_its_global(tmp_path):
    from linmot_st.toolchain import CompileError
    from linmot_st.toolchain.testing import build_text
    with pytest.raises(CompileError) as info:
        build_text("FUNCTION_BLOCK rf_ext\n  VAR_EXTERNAL g1 : INT; END_VAR\n  g1 := g1 + 1;\nEND_FUNCTION_BLOCK\n",
                   tmp_path, "matiec")
    text = "\n".join(info.value.diagnostics)
    assert "no VAR_GLOBAL G1 in the CONFIGURATION" in text
    assert "call wrapper" not in text
