"""Property-based tests (hypothesis): generated models survive write -> parse unchanged, and mutated PVL
text either reads as a valid model or fails with PvlError messages that carry line numbers, never with
another exception."""

from __future__ import annotations

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from linmot_st.pvl import (
    CommandTableEntry,
    Curve,
    Parameter,
    ParameterObject,
    PvlError,
    PvlFile,
    codec,
    demo,
    parse_pvl,
    validate,
    write_pvl,
)
from linmot_st.pvl.layers import LAYERS

LATIN1 = st.characters(min_codepoint=0, max_codepoint=0xFF, blacklist_characters="\n\r")


def text(*, comma=True, max_size=40, nul=True):
    chars = LATIN1
    if not comma:
        chars = st.characters(min_codepoint=0, max_codepoint=0xFF, blacklist_characters="\n\r,")
    if not nul:
        chars = st.characters(min_codepoint=1, max_codepoint=0xFF, blacklist_characters="\n\r")
    return st.text(chars, max_size=max_size)


def no_trailing_blanks(s: str) -> str:
    return s.rstrip(" \t")


u16 = st.integers(0, 0xFFFF)
u32 = st.integers(0, 0xFFFFFFFF)
i32 = st.integers(-(1 << 31), (1 << 31) - 1)


@st.composite
def parameter_objects(draw, layer: int):
    lay = LAYERS[layer]
    upids = draw(st.lists(st.integers(lay.upid_first, lay.upid_last), unique=True, max_size=25))
    rows = tuple(Parameter(u, draw(u32), draw(text(comma=False)), no_trailing_blanks(draw(text())))
                 for u in upids)
    return ParameterObject(no_trailing_blanks(draw(text())), layer, draw(u16), draw(u16), draw(u16),
                           no_trailing_blanks(draw(text(max_size=5))), rows)


def names(size: int):
    # a name field holds `size` bytes; curve names keep room for the terminating 00h
    return text(nul=False, max_size=size).map(no_trailing_blanks)


@st.composite
def curves(draw, curve_id: int):
    return Curve.make(curve_id, draw(names(codec.CURVE_NAME_SIZE - 1)),
                      draw(st.lists(i32, min_size=2, max_size=60)), draw(st.integers(1, 0xFFFFFFFF)),
                      object_type=draw(st.sampled_from(sorted(codec.SUPPORTED_OBJECT_TYPES))),
                      wizard_type=draw(u16), wizard_params=tuple(draw(st.lists(u32, min_size=7, max_size=7))))


@st.composite
def entries(draw, entry_id: int):
    return CommandTableEntry.make(entry_id, draw(names(codec.CT_NAME_SIZE)), draw(u16),
                                  draw(st.binary(max_size=codec.CT_PARAMS_SIZE)),
                                  draw(st.one_of(st.just(codec.CT_NOT_LINKED), st.integers(0, 255))))


@st.composite
def pvl_files(draw):
    layers = draw(st.lists(st.integers(1, 4), unique=True, max_size=4))
    curve_ids = draw(st.lists(st.integers(1, 100), unique=True, max_size=4))
    entry_ids = draw(st.lists(st.integers(0, 255), unique=True, max_size=4))
    objects = ([draw(parameter_objects(n)) for n in layers] + [draw(curves(c)) for c in curve_ids]
               + [draw(entries(e)) for e in entry_ids])
    return PvlFile(tuple(draw(st.permutations(objects))))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(pvl_files())
def test_generated_models_round_trip(pvl):
    assert validate(pvl) == []
    text = write_pvl(pvl)
    back = parse_pvl(text)
    assert back == pvl
    assert write_pvl(back) == text
    # the decoded views agree with what was generated
    for c in pvl.curves:
        assert back.curve(c.curve_id).info == c.info


# --- mutated text ---------------------------------------------------------------------------------------

SOURCES = [write_pvl(demo.seed_parameters_file()), write_pvl(demo.seed_curve_file()),
           write_pvl(PvlFile(demo.two_axes_file().objects[:2] + demo.two_axes_file().objects[4:]))]
INTERESTING = st.sampled_from(list("0123456789ABCDEFabcdefh,@ \t\n\r\x00\x85\xff") + ["@EndData", "@EndObject",
                              "@StartObject,Curve", "@Col1:Value", "FFFFFFFFh", "\n@EndInfo\n"])


@st.composite
def mutations(draw):
    text = draw(st.sampled_from(SOURCES))
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["replace", "insert", "delete", "dup-line", "drop-line", "swap-lines"]))
        lines = text.split("\n")
        if kind in ("dup-line", "drop-line", "swap-lines"):
            i = draw(st.integers(0, len(lines) - 1))
            j = draw(st.integers(0, len(lines) - 1))
            if kind == "dup-line":
                lines.insert(i, lines[j])
            elif kind == "drop-line":
                del lines[i]
            else:
                lines[i], lines[j] = lines[j], lines[i]
            text = "\n".join(lines)
        else:
            pos = draw(st.integers(0, max(len(text) - 1, 0)))
            piece = draw(st.one_of(INTERESTING, st.text(LATIN1, min_size=1, max_size=3)))
            if kind == "replace":
                text = text[:pos] + piece + text[pos + 1:]
            elif kind == "insert":
                text = text[:pos] + piece + text[pos:]
            else:
                text = text[:pos] + text[pos + 1:]
    return text


@settings(max_examples=400, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mutations())
def test_mutated_text_gives_a_model_or_located_errors(text):
    n_lines = text.count("\n") + 1
    try:
        pvl = parse_pvl(text, filename="m.pvl")
    except PvlError as err:
        assert err.diagnostics
        for d in err.diagnostics:
            assert d.line is not None and 1 <= d.line <= n_lines, (d, n_lines)
        assert all(m.startswith("m.pvl:") for m in err.messages)
        return
    # accepted: then it is a valid model that writes and reads back unchanged
    assert validate(pvl) == []
    assert parse_pvl(write_pvl(pvl)) == pvl


@settings(max_examples=200, deadline=None)
@given(st.binary(max_size=300))
def test_arbitrary_bytes_never_crash(data):
    try:
        parse_pvl(b"@FileType,PVL\n@FormatVersion,1\n" + data)
    except PvlError as err:
        assert all(d.line is not None for d in err.diagnostics)
