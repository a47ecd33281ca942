"""Long integer-literal array initialisers (linmot_st.toolchain.builtin.bulkinit): read without the grammar,
yet the same program, the same positions and the same diagnostics as item by item; and a big PVL dataset
built with plc_project reads back word for word from the loaded PLC."""

from __future__ import annotations

import pytest

from linmot_st.toolchain.builtin import BuiltinCompileError, bulkinit, check_text, compile_text


def _slow(monkeypatch):
    monkeypatch.setattr(bulkinit, "MIN_ITEMS", 10**9)


def _program(values: list[str], elem: str = "DWORD", extra: str = "") -> str:
    rows = []
    for k in range(0, len(values), 5):
        rows.append("    " + ", ".join(values[k:k + 5]) + ("," if k + 5 < len(values) else "")
                    + (f"  (* row {k // 5}: [a, b] *)" if k % 15 == 0 else ""))
    return (f"TYPE\n  T_Data : ARRAY[1..{len(values) + 3}] OF {elem} := [\n" + "\n".join(rows) + "\n  ];\nEND_TYPE\n"
            "PROGRAM pp\n  VAR d : T_Data; s : UDINT; i : INT; END_VAR\n"
            f"  i := 1;\n  s := s + DWORD_TO_UDINT(d[i]);{extra}\nEND_PROGRAM\n")


def _literals(n: int) -> list[str]:
    forms = ["16#{:X}", "{}", "2#{:b}", "8#{:o}", "16#{:X}"]
    return [forms[k % 5].format(k * 7919 % 65536) for k in range(n)]


def test_the_fast_path_finds_the_list_and_keeps_every_position():
    text = _program(_literals(100))
    fast, found = bulkinit.extract(text)
    assert len(found) == 1 and fast.count("\n") == text.count("\n")
    (bulk,) = found.values()
    assert bulk.values == [k * 7919 % 65536 for k in range(100)]
    # everything after the list sits at the same line and column
    tail = text[text.index("];"):]
    assert fast.endswith(tail)
    line_of = lambda t: t[:t.index("];")].count("\n")            # noqa: E731
    col_of = lambda t: t.index("];") - t[:t.index("];")].rfind("\n")   # noqa: E731
    assert (line_of(fast), col_of(fast)) == (line_of(text), col_of(text))


def _c_text(text: str, folder) -> str:
    compile_text(text, folder, "t.st")
    return "".join(p.read_text() for p in sorted(folder.glob("*.c")))


def test_the_same_c_with_and_without_the_fast_path(monkeypatch, tmp_path):
    text = _program(_literals(200))
    c_fast = _c_text(text, tmp_path / "fast")
    _slow(monkeypatch)
    c_slow = _c_text(text, tmp_path / "slow")
    assert c_fast == c_slow and f"{199 * 7919 % 65536}U" in c_fast


@pytest.mark.parametrize("case, elem, values", [
    ("too big for a BYTE", "BYTE", ["1"] * 40 + ["300"] + ["2"] * 10),
    ("too many values", "DWORD", None),
    ("a bad based literal", "DWORD", ["1"] * 40 + ["8#19"]),
])
def test_the_same_diagnostics_as_item_by_item(monkeypatch, case, elem, values):
    if values is None:   # 60 values for 43 elements
        text = _program(["7"] * 40).replace("ARRAY[1..43]", "ARRAY[1..33]")
    else:
        text = _program(values, elem)
    with pytest.raises(BuiltinCompileError) as fast:
        check_text(text, "t.st")
    _slow(monkeypatch)
    with pytest.raises(BuiltinCompileError) as slow:
        check_text(text, "t.st")
    assert str(fast.value) == str(slow.value), case


def test_a_list_in_a_comment_or_in_other_shapes_is_left_to_the_grammar():
    inner = ", ".join(str(k) for k in range(40))
    text = ("PROGRAM pp\n  VAR a : ARRAY[1..40] OF INT := [" + inner + "];\n"
            "    b : ARRAY[1..80] OF INT := [40(1), " + inner + "];\n"
            "    c : ARRAY[1..40] OF INT := [-1, " + inner[3:] + "];\n  END_VAR\n"
            "  (* x := [" + inner + "] *)\n  a[1] := b[2] + c[1];\nEND_PROGRAM\n")
    fast, found = bulkinit.extract(text)
    assert len(found) == 2      # a, and the one in the comment; b (a repetition) and c (a sign) are not
    prog = check_text(text, "t.st")
    assert prog is not None     # the comment's placeholder was never reached: parsed again as written


def test_a_big_dataset_round_trip(tmp_path):
    """20 curves of 4000 setpoints: plc_project's Ds holds the dataset stream word for word."""
    from linmot_st.jobs.commission.project import INSTANCE, build_project, prepare
    from linmot_st.plc import Plc
    from linmot_st.pvl import demo
    from linmot_st.pvl.dataset import encode
    from linmot_st.pvl.model import PvlFile

    curves = [demo.minimum_jerk_curve(k + 1, f"Big_{k + 1}", 1_000_000 - 997 * k, 40_000, 4000) for k in range(20)]
    pvl = PvlFile((demo.os_parameters("Big", "Round Trip"), demo.mc_parameters(), *curves))
    words = encode(pvl)
    res = build_project(prepare(pvl, "big.pvl"), "builtin")
    plc = Plc(res)
    got = plc.var(f"{INSTANCE}.DS").read_bytes()
    assert len(words) > 80_000
    assert [int.from_bytes(got[4 * i:4 * i + 4], "little") for i in range(len(words))] == words
