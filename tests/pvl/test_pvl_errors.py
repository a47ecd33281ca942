"""Every check of the PVL reader and of the model: each problem is reported as `file:line: message`
at the line that holds it, and the reader goes on to report the others."""

from __future__ import annotations

import re
from dataclasses import replace

import pytest

from linmot_st.pvl import CommandTableEntry, Curve, Parameter, PvlError, PvlFile, codec, demo, parse_pvl, write_pvl

# A valid file with one object of each kind; the cases below change single lines of it.
BASE = r"""@FileType,PVL
@FormatVersion,1

@StartObject,Parameter
@TreeFileName,OSTREE1100OS__V3S0_b1
@TreeLayer,1
@TreeID,1
@MainVersion,3
@SubVersion,0
@Revision,b1
@StartData
@Col1:UPID,@Col2:Value,@Col3:Caption,@Col4:ScaledValue Unit
03F3,78412058,OS\User Comment_1,X Ax
03F4,4C207369,OS\User Comment_2,is L
03F5,00746665,OS\User Comment_3,eft
03F6,00000000,OS\User Comment_4,
@EndData
@EndObject

@StartObject,Parameter
@TreeFileName,MCTREE1100DSW4_HC_V3S0_b1
@TreeLayer,2
@TreeID,4612
@MainVersion,3
@SubVersion,0
@Revision,b1
@StartData
@Col1:UPID,@Col2:Value,@Col3:Caption,@Col4:ScaledValue Unit
1194,00000002,Motion Control SW\Motor Configuration\Motor Type,P01
1385,00000BB8,Motion Control SW\Drive Configuration\Current Limits\Max Current,3 A
@EndData
@EndObject

@StartObject,Curve
@CurveName,Example_Curve
@CurveID,23
@InfoBlockByteSize,70
@DataBlockByteSize,40
@StartInfo
@Col1:Value
00030046h
0004000Ah
6D617845h
5F656C70h
76727543h
00000065h
00000000h
00170000h
00004E20h
0005001Ah
4E200301h
00000000h
42400000h
0000000Fh
00000000h
00000000h
00000000h
00000000h
@EndInfo
@StartData
@Col1:Value
00000000h
000075CAh
0001C8F2h
0003D090h
00064DF8h
0008F448h
000B71B0h
000D794Eh
000ECC76h
000F4240h
@EndData
@EndObject

@StartObject,CommandTableEntry
@EntryID,1
@EntryName,Go_Out
@DataBlockByteSize,64
@StartData
@Col1:Value
0002A701h
42400100h
4240000Fh
4240000Fh
4240000Fh
0000000Fh
00000000h
00000000h
00000000h
6F470000h
74754F5Fh
00000000h
00000000h
00000000h
00000000h
00000000h
@EndData
@EndObject
"""
LINES = BASE.split("\n")


def edit(changes: dict[int, str | None] | None = None, insert: dict[int, str] | None = None) -> str:
    """BASE with line n (1-based) replaced (None deletes it) and lines inserted before line n."""
    out = []
    for n, text in enumerate(LINES, start=1):
        for new in (insert or {}).get(n, "").split("\n") if (insert or {}).get(n) is not None else []:
            out.append(new)
        if changes and n in changes:
            if changes[n] is not None:
                out.append(changes[n])
        else:
            out.append(text)
    return "\n".join(out)


def errors(text: str) -> list[tuple[int | None, str]]:
    with pytest.raises(PvlError) as info:
        parse_pvl(text, filename="f.pvl")
    err = info.value
    assert all(d.line is not None for d in err.diagnostics), "every reader error names a line"
    assert str(err).splitlines() == [f"f.pvl:{d.line}: {d.message}" for d in err.diagnostics]
    return [(d.line, d.message) for d in err.diagnostics]


def test_base_is_valid():
    pvl = parse_pvl(BASE)
    assert [type(o).__name__ for o in pvl] == ["ParameterObject", "ParameterObject", "Curve", "CommandTableEntry"]


CASES = [
    # (id, text, line, message pattern)
    # file header
    ("not-pvl", "hello\n" + BASE, 1, r"not a PVL file: it must start with @FileType,PVL"),
    ("empty", "", 1, r"not a PVL file.*empty"),
    ("filetype", edit({1: "@FileType,LMC"}), 1, r"@FileType is 'LMC'"),
    ("no-format-version", edit({2: None}), 3, r"missing @FormatVersion,1"),
    ("format-version", edit({2: "@FormatVersion,2"}), 2, r"unsupported format version"),
    ("stray-line", edit({3: "junk"}), 3, r"expected @StartObject, got 'junk'"),
    # objects and header keys
    ("object-no-kind", edit({4: "@StartObject"}), 4, r"@StartObject needs a kind"),
    ("object-kind", edit({4: "@StartObject,Oscilloscope"}), 4, r"unknown object kind 'Oscilloscope'"),
    ("missing-key", edit({7: None}), 4, r"Parameter object: missing @TreeID"),
    ("unknown-key", edit({7: "@TreeId,1"}), 7, r"unknown key @TreeId in a Parameter object"),
    ("duplicate-key", edit({8: "@TreeLayer,1"}), 8, r"@TreeLayer given twice \(first at line 6\)"),
    ("key-no-value", edit({6: "@TreeLayer"}), 6, r"@TreeLayer has no value"),
    ("key-not-decimal", edit({36: "@CurveID,0x17"}), 36, r"@CurveID: '0x17' is not a decimal number"),
    ("key-line", edit({6: "TreeLayer,1"}), 6, r"Parameter object: expected @StartData before 'TreeLayer,1'"),
    ("rows-without-start", edit({39: None}), 39, r"Curve object: expected @StartInfo before '@Col1:Value'"),
    ("no-data-block", edit({n: None for n in range(11, 18)}), 11, r"expected @StartData before '@EndObject'"),
    ("eof-in-keys", "\n".join(LINES[:8]), 8, r"file ends before @StartData"),
    ("curve-data-first", edit({39: "@StartData"}), 39, r"expected @StartInfo before '@StartData'"),
    # blocks and end markers
    ("no-start-data", edit({60: "@StartDat"}), 60, r"expected @StartData, got '@StartDat'"),
    ("column-line", edit({12: "@Col1:UPID,@Col2:Value"}), 12, r"expected the column line"),
    ("column-line-missing", edit({61: None}), 61, r"expected the column line '@Col1:Value' after @StartData"),
    ("no-end-data", edit({31: None}), 31, r"missing @EndData \(the block opened at line 27\)"),
    ("no-end-info", edit({59: None}), 59, r"missing @EndInfo \(the block opened at line 39\) before '@StartData'"),
    ("end-data-in-info", edit({59: "@EndData"}), 59, r"missing @EndInfo .* before '@EndData'"),
    ("unexpected-in-block", edit({30: "@Comment,x"}), 30, r"unexpected '@Comment,x' inside the block opened at line 27"),
    ("eof-in-block", "\n".join(LINES[:70]), 70, r"missing @EndData \(the block opened at line 60\), and @EndObject"),
    ("no-end-object", edit({32: None}), 33, r"missing @EndObject \(the object started at line 20\)"),
    ("no-end-object-eof", "\n".join(LINES[:97]), 97, r"missing @EndObject \(the object started at line 75\)"),
    ("expected-end-object", edit({32: "@EndObj"}), 32, r"expected @EndObject, got '@EndObj'"),
    # parameter rows
    ("row-columns", edit({29: "1194,00000002,Motor Type"}), 29, r"a parameter row has 4 columns .* got 3"),
    ("row-upid-hex", edit({29: "11G4,00000002,Motor Type,P01"}), 29, r"UPID '11G4' is not 4 hex digits"),
    ("row-upid-short", edit({29: "194,00000002,Motor Type,P01"}), 29, r"UPID '194' is not 4 hex digits"),
    ("row-value-hex", edit({29: "1194,0000002,Motor Type,P01"}), 29, r"value '0000002' is not 8 hex digits"),
    ("elided-row", edit({29: "……"}), 29, r"a parameter row has 4 columns"),
    ("duplicate-upid", edit({30: "1194,00000003,Motor Type again,"}), 30,
     r"layer 2: UPID 1194h appears twice \(first at line 29\)"),
    ("upid-outside-layer", edit({30: "2385,00000BB8,Max Current,3 A"}), 30,
     r"UPID 2385h is outside the Motion Control SW range 1000h..1EFFh"),
    ("layer-range", edit({22: "@TreeLayer,5"}), 22, r"layer 5 does not exist \(layers are 1..4\)"),
    ("layer-twice", edit({22: "@TreeLayer,1"}), 22, r"layer 1 has a second Parameter object \(the first at line 4\)"),
    ("tree-id-range", edit({23: "@TreeID,70000"}), 23, r"@TreeID 70000 is outside 0..65535"),
    # words
    ("word-no-h", edit({41: "00030046"}), 41, r"'00030046' is not a 32-bit word"),
    ("word-short", edit({63: "75CAh"}), 63, r"'75CAh' is not a 32-bit word"),
    ("word-hex", edit({63: "0000X5CAh"}), 63, r"'0000X5CAh' is not a 32-bit word"),
    # curve header against blocks
    ("info-size", edit({37: "@InfoBlockByteSize,72"}), 37, r"@InfoBlockByteSize is 72, a curve info block has 70 bytes"),
    ("info-words", edit({58: None}), 57, r"the info block lists 17 words, @InfoBlockByteSize 70 needs 18"),
    ("data-size", edit({38: "@DataBlockByteSize,44"}), 38, r"@DataBlockByteSize is 44, the data block lists 10 words"),
    ("data-words", edit({71: None}), 38, r"@DataBlockByteSize is 40, the data block lists 9 words"),
    ("curve-id-range", edit({36: "@CurveID,101"}), 36, r"curve ID 101 is outside 1..100"),
    ("curve-id-zero", edit({36: "@CurveID,0"}), 36, r"curve ID 0 is outside 1..100"),
    ("pad-bytes", edit({58: "00010000h"}), 58, r"the 2 pad bytes after the 70-byte info block must be 00h, got 0100"),
    ("curve-id-header", edit({36: "@CurveID,24"}), 48, r"the info block's curve ID is 23, @CurveID \(line 36\) is 24"),
    ("curve-name-header", edit({35: "@CurveName,Example Curve"}), 43,
     r"the info block's name is 'Example_Curve', @CurveName \(line 35\) is 'Example Curve'"),
    # curve info block contents
    ("data-offset", edit({41: "00030048h"}), 41, r"curve 23: data offset is 72, must be 70"),
    ("object-type", edit({41: "00130046h"}), 41, r"curve 23: object type 0013h is not supported"),
    ("setpoint-count", edit({42: "0004000Bh"}), 42, r"curve 23: info block says 11 setpoints, the data block holds 10"),
    ("setpoints-min", edit({42: "00040001h", 38: "@DataBlockByteSize,4"} | {n: None for n in range(63, 72)}), 42,
     r"curve 23: 1 setpoints, a curve has at least 2"),
    ("type-size", edit({42: "0002000Ah"}), 42, r"curve 23: data type size is 2, must be 4"),
    ("name-unterminated", edit({47: "41414141h", 48: "00174141h", 46: "41414141h"}), 43,
     r"curve 23: curve name is not terminated with 00h"),
    ("x-length-zero", edit({49: "00000000h"}), 49, r"curve 23: x-length is 0"),
    ("uuids", edit({50: "0005001Bh"}), 50, r"XDimUUID/YDimUUID 001Bh/0005h do not match object type 0003h"),
    ("curve-id-twice", edit(insert={75: "\n".join(LINES[33:73]) + "\n"}), 77, r"curve 23: duplicate curve ID \(the first at line 34\)"),
    # command-table entries
    ("ct-size", edit({78: "@DataBlockByteSize,60"}), 78, r"@DataBlockByteSize is 60, a command-table entry has 64 bytes"),
    ("ct-words", edit({96: None}), 95, r"the data block lists 15 words, @DataBlockByteSize 64 needs 16"),
    ("ct-name", edit({77: "@EntryName,Go_In"}), 90, r"the entry's name is 'Go_Out', @EntryName \(line 77\) is 'Go_In'"),
    ("ct-version", edit({81: "0002A702h"}), 81, r"command-table entry 1: entry version ID is A702h, must be A701h"),
    ("ct-linked", edit({81: "0100A701h"}), 81, r"linked entry ID 0100h is neither an entry ID \(0..255\) nor FFFFh"),
    ("ct-entry-id", edit({76: "@EntryID,256"}), 76, r"command-table entry 256: entry ID outside 0..255"),
    ("ct-twice", BASE + "\n".join(LINES[74:98]) + "\n", 100, r"command-table entry 1: duplicate entry ID \(the first at line 75\)"),
]


@pytest.mark.parametrize("text,line,pattern", [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_error(text, line, pattern):
    found = errors(text)
    assert any(ln == line and re.search(pattern, msg) for ln, msg in found), found


def test_errors_are_collected_across_objects():
    text = edit({29: "11G4,00000002,Motor Type,P01", 36: "@CurveID,24", 81: "0002A702h", 7: "@TreeID,x"})
    lines = [ln for ln, _ in errors(text)]
    assert lines == sorted(lines)
    assert {7, 29, 48, 81} <= set(lines)


def test_stray_lines_between_objects_give_one_message():
    found = errors(edit(insert={20: "junk\nmore junk\n1194,00000002,x,y"}))
    assert found == [(20, "expected @StartObject, got 'junk'")]


def test_one_broken_word_gives_one_message():
    # the curve with a bad word is left out of the later checks: no follow-on messages about its sizes
    assert len(errors(edit({63: "0000X5CAh"}))) == 1


def test_many_errors_are_capped():
    from linmot_st.pvl.parser import MAX_DIAGNOSTICS
    text = edit(insert={29: "11G4,00000002,x,y\n" * (MAX_DIAGNOSTICS + 50)})
    assert len(errors(text)) == MAX_DIAGNOSTICS


# --- the writer refuses models it could not write faithfully -------------------------------------------

def _model_errors(pvl: PvlFile) -> list[str]:
    with pytest.raises(PvlError) as info:
        write_pvl(pvl)
    assert all(m.startswith("<model>: ") for m in info.value.messages)
    return info.value.messages


MC = demo.mc_parameters((0x1194, 0x11A0))


@pytest.mark.parametrize("obj,pattern", [
    (replace(MC, parameters=(Parameter(0x1194, 2, "Motor, Type", "P01"),)), r"caption .* contains a comma"),
    (replace(MC, parameters=(Parameter(0x1194, 2, "Motor Type", "P01 "),)), r"scaled value 'P01 ' ends with blanks"),
    (replace(MC, parameters=(Parameter(0x1194, 2, "Motor\nType", "P01"),)), r"contains a line break"),
    (replace(MC, parameters=(Parameter(0x1194, 2, "Motor Type", "1 \u00b5m \u2192"),)), r"outside Latin-1"),
    (replace(MC, parameters=(Parameter(0x1194, 1 << 32),)), r"is not a raw 32-bit value"),
    (replace(MC, parameters=(Parameter(0x11194, 2),)), r"is not a 16-bit number"),
    (replace(MC, revision="b1 "), r"@Revision 'b1 ' ends with blanks"),
    (replace(MC, sub_version=-1), r"@SubVersion -1 is outside 0..65535"),
    (Curve(bytes(68), (0, 1)), r"the info block has 68 bytes, must be 70"),
    (Curve.make(101, "x", (0, 1), 100), r"curve ID 101 is outside 1..100"),
    (Curve.make(1, "x", (0, 1 << 31), 100), r"setpoint 2 \(2147483648\) is not a signed 32-bit value"),
    (Curve.make(1, "x ", (0, 1), 100), r"name 'x ' ends with blanks"),
    (replace(Curve.make(1, "x", (0, 1), 100), setpoints=(0, 1, 2)), r"info block says 2 setpoints, the data block holds 3"),
    (CommandTableEntry(1, bytes(63)), r"the data block has 63 bytes, must be 64"),
    (CommandTableEntry.make(-1, "x", 0x0100), r"entry ID outside 0..255"),
    (CommandTableEntry.make(1, "Go ", 0x0100), r"command-table entry 1: name 'Go ' ends with blanks"),
])
def test_writer_refuses_invalid_models(obj, pattern):
    msgs = _model_errors(PvlFile((obj,)))
    assert any(re.search(pattern, m) for m in msgs), msgs


def test_writer_refuses_format_version():
    assert any("format version 2" in m for m in _model_errors(PvlFile((), format_version=2)))


def test_writer_refuses_non_objects():
    assert any("not a PVL object" in m for m in _model_errors(PvlFile(("text",))))  # type: ignore[arg-type]


def test_codec_refuses_unrepresentable_names():
    with pytest.raises(ValueError, match="longer than 22 bytes"):
        Curve.make(1, "x" * 23, (0, 1), 100)
    with pytest.raises(ValueError, match="00h"):
        Curve.make(1, "a\0b", (0, 1), 100)
    with pytest.raises(ValueError, match="at most 32 bytes"):
        CommandTableEntry.make(1, "x", 0x0100, bytes(33))
    with pytest.raises(ValueError, match="needs 3 stringlets"):
        codec.encode_stringlets("123456789", 2)
