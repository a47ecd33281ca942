"""`linmot-st export plcopen`: the library as PLCopen XML (TC6 2.01).

- The XML validates against PLCopen's schema (../shared/plcopen/tc6_xml_v201.xsd beside the checkout).
- Round trip: the XML is read back with lxml alone (nothing from linmot_st.export) and turned into ST
  again; the compiler's syntax tree of that ST equals the tree of st_lib/linmot.st: every data type, every
  POU, every variable (name, type, section, attributes, initial value) and every body statement. The
  rebuilt ST also compiles to the same manifest (and, with MatIEC, to byte-identical C).
- A small library covers what st_lib does not use: subranges, aliases, type initial values, 2-D arrays,
  repeated array initialisers, struct initialisers, VAR_TEMP, CONSTANT, RETAIN, VAR_EXTERNAL, located
  variables, a PROGRAM and a CONFIGURATION, and a body that holds "]]>".
"""

from __future__ import annotations

import dataclasses
import json
import subprocess
import textwrap
from pathlib import Path

import pytest
from lxml import etree

from linmot_st.cli import main as cli_main
from linmot_st.export import ExportError, export_plcopen, read_library, validate
from linmot_st.export.plcopen import build_tree
from linmot_st.toolchain import build
from linmot_st.toolchain import matiec as matiec_mod
from linmot_st.toolchain.builtin import ast as A
from linmot_st.toolchain.builtin.parser import parse
from linmot_st.toolchain.testing import MATIEC_MISSING
from repo_paths import REPO

LIBRARY = REPO / "st_lib" / "linmot.st"
SCHEMA = REPO.parent / "shared" / "plcopen" / "tc6_xml_v201.xsd"
requires_schema = pytest.mark.skipif(
    not SCHEMA.is_file(),
    reason=f"PLCopen schema not found at {SCHEMA} (the shared/ folder beside the checkout; CI has it)")
MATIEC = matiec_mod.find()

NS = "http://www.plcopen.org/xml/tc6_0201"
XHTML = "http://www.w3.org/1999/xhtml"
N = {"p": NS, "x": XHTML}

SECTIONS = {"localVars": "VAR", "tempVars": "VAR_TEMP", "inputVars": "VAR_INPUT", "outputVars": "VAR_OUTPUT",
            "inOutVars": "VAR_IN_OUT", "externalVars": "VAR_EXTERNAL", "globalVars": "VAR_GLOBAL"}
POU_KINDS = {"function": "FUNCTION", "functionBlock": "FUNCTION_BLOCK", "program": "PROGRAM"}
ATTRIBUTES = {"constant": "CONSTANT", "retain": "RETAIN", "nonretain": "NON_RETAIN", "persistent": "PERSISTENT"}


# ------------------------------------------------------------------ PLCopen XML -> ST, with lxml only

def local(el) -> str:
    return etree.QName(el).localname


def only_child(el):
    children = [c for c in el if isinstance(c.tag, str)]
    assert len(children) == 1, f"{el.tag} should hold exactly one element"
    return children[0]


def type_text(holder) -> str:
    c = only_child(holder)
    tag = local(c)
    if tag == "derived":
        return c.get("name")
    if tag == "array":
        dims = ", ".join(f"{d.get('lower')}..{d.get('upper')}" for d in c.findall("p:dimension", N))
        return f"ARRAY[{dims}] OF {type_text(c.find('p:baseType', N))}"
    if tag == "struct":
        return "STRUCT\n" + "".join(var_text(v) for v in c.findall("p:variable", N)) + "END_STRUCT"
    if tag == "enum":
        return "(" + ", ".join(v.get("name") for v in c.findall("p:values/p:value", N)) + ")"
    if tag in ("subrangeSigned", "subrangeUnsigned"):
        r = c.find("p:range", N)
        return f"{type_text(c.find('p:baseType', N))}({r.get('lower')}..{r.get('upper')})"
    if tag in ("string", "wstring"):
        return tag.upper() + (f"[{c.get('length')}]" if c.get("length") else "")
    return tag


def value_text(holder) -> str:
    c = only_child(holder)
    tag = local(c)
    if tag == "simpleValue":
        return c.get("value", "")
    if tag == "arrayValue":
        items = []
        for v in c.findall("p:value", N):
            rep = v.get("repetitionValue", "1")
            items.append(value_text(v) if rep == "1" else f"{rep}({value_text(v)})")
        return "[" + ", ".join(items) + "]"
    assert tag == "structValue"
    return "(" + ", ".join(f"{v.get('member')} := {value_text(v)}" for v in c.findall("p:value", N)) + ")"


def var_text(v) -> str:
    at = f" AT {v.get('address')}" if v.get("address") else ""
    init = v.find("p:initialValue", N)
    return (f"{v.get('name')}{at} : {type_text(v.find('p:type', N))}"
            + (f" := {value_text(init)}" if init is not None else "") + ";\n")


def var_list_text(lst, keyword: str) -> str:
    attrs = [word for attr, word in ATTRIBUTES.items() if lst.get(attr) == "true"]
    return f"{keyword}{' ' + attrs[0] if attrs else ''}\n" + "".join(var_text(v) for v in lst.findall("p:variable", N)) \
        + "END_VAR\n"


def formatted(el) -> str:
    ps = el.findall("x:p", N)
    assert len(ps) == 1
    return ps[0].text or ""


def xml_to_st(root) -> str:
    out = []
    dts = root.findall("p:types/p:dataTypes/p:dataType", N)
    if dts:
        out.append("TYPE\n")
        for dt in dts:
            init = dt.find("p:initialValue", N)
            out.append(f"{dt.get('name')} : {type_text(dt.find('p:baseType', N))}"
                       + (f" := {value_text(init)}" if init is not None else "") + ";\n")
        out.append("END_TYPE\n")
    for pou in root.findall("p:types/p:pous/p:pou", N):
        kind = POU_KINDS[pou.get("pouType")]
        itf = pou.find("p:interface", N)
        ret = itf.find("p:returnType", N)
        out.append(f"{kind} {pou.get('name')}" + (f" : {type_text(ret)}" if ret is not None else "") + "\n")
        for lst in itf:
            if local(lst) in SECTIONS:
                out.append(var_list_text(lst, SECTIONS[local(lst)]))
        out.append(formatted(pou.find("p:body/p:ST", N)))
        out.append(f"\nEND_{kind}\n")
    for conf in root.findall("p:instances/p:configurations/p:configuration", N):
        out.append(f"CONFIGURATION {conf.get('name')}\n")
        for lst in conf.findall("p:globalVars", N):
            out.append(var_list_text(lst, "VAR_GLOBAL"))
        for res in conf.findall("p:resource", N):
            out.append(f"RESOURCE {res.get('name')} ON PLC\n")
            for lst in res.findall("p:globalVars", N):
                out.append(var_list_text(lst, "VAR_GLOBAL"))
            for task in res.findall("p:task", N):
                params = [f"{k.upper()} := {task.get(k)}" for k in ("single", "interval", "priority") if task.get(k)]
                out.append(f"TASK {task.get('name')}({', '.join(params)});\n")
            for task in res.findall("p:task", N):
                for inst in task.findall("p:pouInstance", N):
                    out.append(f"PROGRAM {inst.get('name')} WITH {task.get('name')} : {inst.get('typeName')};\n")
            for inst in res.findall("p:pouInstance", N):
                out.append(f"PROGRAM {inst.get('name')} : {inst.get('typeName')};\n")
            out.append("END_RESOURCE\n")
        out.append("END_CONFIGURATION\n")
    return "".join(out)


# ------------------------------------------------------------------ syntax trees compared without positions

SKIP_FIELDS = {"pos", "name_pos", "type_pos", "end_pos", "ty", "sym", "target", "std"}


def norm(x):
    if isinstance(x, A.Pos):
        return None
    if isinstance(x, A.VarBlock):      # `a, b : T` and `a : T; b : T` declare the same
        decls = [A.VarDecl(d.pos, [n], d.spec, d.init, d.location, d.edge) for d in x.decls for n in d.names]
        return ("VarBlock", x.kind, x.qualifier, [norm(d) for d in decls])
    if dataclasses.is_dataclass(x):
        return (type(x).__name__,
                {f.name: norm(getattr(x, f.name)) for f in dataclasses.fields(x) if f.name not in SKIP_FIELDS})
    if isinstance(x, (list, tuple)):
        return [norm(i) for i in x if not isinstance(i, A.Pos)]
    return x


def declarations(elements) -> list:
    """The types (out of their TYPE blocks), then the POUs and configurations, each in source order;
    pragmas dropped. PLCopen keeps types and POUs in two lists, so their interleaving is not kept."""
    types, others = [], []
    for el in elements:
        if isinstance(el, A.TypeBlock):
            types += el.decls
        elif not isinstance(el, A.Pragma):
            others.append(el)
    return types + others


def label(node) -> str:
    return f"{type(node).__name__} {getattr(node, 'name', '')}"


# ------------------------------------------------------------------ fixtures

@pytest.fixture(scope="module")
def exported():
    data, lib = export_plcopen()
    return data, lib, etree.fromstring(data)


@requires_schema
def test_the_plcopen_xml_validates_against_the_schema(exported):
    data, _, _ = exported
    assert validate(data, SCHEMA) == []
    # and with lxml directly, independent of export.validate
    assert etree.XMLSchema(etree.parse(str(SCHEMA))).validate(etree.fromstring(data).getroottree())


@requires_schema
def test_the_schema_check_can_fail(exported):
    """validate() reports what is wrong: a pou without its pouType, an unknown element."""
    root = etree.fromstring(exported[0])
    pou = root.find("p:types/p:pous/p:pou", N)
    del pou.attrib["pouType"]
    etree.SubElement(root.find("p:types/p:dataTypes", N), f"{{{NS}}}bogus")
    errors = validate(etree.tostring(root), SCHEMA)
    assert any("pouType" in e for e in errors) and any("bogus" in e for e in errors)


def test_every_type_and_pou_is_there_in_order(exported):
    _, lib, root = exported
    assert [dt.get("name") for dt in root.findall("p:types/p:dataTypes/p:dataType", N)] == \
        [t.decl.name for t in lib.types]
    assert [(p.get("name"), POU_KINDS[p.get("pouType")]) for p in root.findall("p:types/p:pous/p:pou", N)] == \
        [(p.pou.name, p.pou.kind) for p in lib.pous]
    assert len(lib.types) >= 20 and len(lib.pous) >= 80


def test_round_trip_every_type_pou_variable_and_body_equals_the_compiler_ast(exported):
    _, lib, root = exported
    rebuilt = declarations(parse(xml_to_st(root), "roundtrip.st"))
    original = declarations(lib.elements)
    assert [label(n) for n in rebuilt] == [label(n) for n in original]
    for mine, theirs in zip(rebuilt, original):
        assert norm(mine) == norm(theirs), label(theirs)


def test_each_variable_has_its_name_type_section_and_initial_value(exported):
    """The same, stated per variable: the XML's view of each declaration against the compiler's AST."""
    _, lib, root = exported
    pous = {p.get("name"): p for p in root.findall("p:types/p:pous/p:pou", N)}
    checked = 0
    for entry in lib.pous:
        itf = pous[entry.pou.name].find("p:interface", N)
        lists = [lst for lst in itf if local(lst) in SECTIONS]
        assert [SECTIONS[local(lst)] for lst in lists] == [b.kind for b in entry.pou.blocks], entry.pou.name
        if entry.pou.return_spec is not None:
            assert norm(type_spec(type_text(itf.find("p:returnType", N)))) == norm(entry.pou.return_spec)
        for lst, block in zip(lists, entry.pou.blocks):
            assert [w for a, w in ATTRIBUTES.items() if lst.get(a) == "true"] == \
                ([block.qualifier] if block.qualifier else [])
            xml_vars = lst.findall("p:variable", N)
            ast_vars = [(name, d) for d in block.decls for name, _ in d.names]
            assert [v.get("name") for v in xml_vars] == [n for n, _ in ast_vars], entry.pou.name
            for v, (name, decl) in zip(xml_vars, ast_vars):
                where = f"{entry.pou.name}.{name}"
                assert norm(type_spec(type_text(v.find("p:type", N)))) == norm(decl.spec), where
                init = v.find("p:initialValue", N)
                assert (init is None) == (decl.init is None), where
                if init is not None:
                    assert norm(init_value(value_text(init))) == norm(decl.init), where
                checked += 1
    assert checked > 500


def type_spec(text: str) -> A.Node:
    return parse(f"TYPE X_ : {text}; END_TYPE", "t.st")[0].decls[0].spec


def init_value(text: str) -> A.Node:
    return parse(f"TYPE X_ : INT := {text}; END_TYPE", "v.st")[0].decls[0].init


def test_bodies_are_the_original_text_with_comments(exported):
    _, lib, root = exported
    pous = {p.get("name"): p for p in root.findall("p:types/p:pous/p:pou", N)}
    source = LIBRARY.parent.joinpath("channel", "channel.st").read_text()
    body = formatted(pous["FB_LmChannel"].find("p:body/p:ST", N))
    assert "(* clock: a TON as time source, restarted daily; Axis.Now only ever grows *)" in body
    for line in body.splitlines():
        assert line.strip() in source
    # CDATA, as Beremiz writes and reads it
    assert b"<ST>\n" in exported[0] and b"<xhtml:p><![CDATA[" in exported[0]


def test_declaration_comments_become_documentation(exported):
    _, _, root = exported
    frame = root.find("p:types/p:dataTypes/p:dataType[@name='T_CanFrame']", N)
    ident = frame.find("p:baseType/p:struct/p:variable[@name='Id']", N)
    assert formatted(ident.find("p:documentation", N)) == "11-bit identifier (COB-ID)"
    drive = root.find("p:types/p:dataTypes/p:dataType[@name='E_LmDrive']", N)
    assert formatted(drive.find("p:documentation", N)).startswith("drive family")
    channel = root.find("p:types/p:pous/p:pou[@name='FB_LmChannel']", N)
    assert "per-drive channel" in formatted(channel.find("p:documentation", N))


def test_declarations_as_written_ride_along_for_codesys(exported):
    _, lib, root = exported
    key = "http://www.3s-software.com/plcopenxml/interfaceasplaintext"
    for entry, pou in zip(lib.pous, root.findall("p:types/p:pous/p:pou", N)):
        data = pou.find(f"p:addData/p:data[@name='{key}']", N)
        assert data.get("handleUnknown") == "implementation"
        text = data.find("p:InterfaceAsPlainText/x:xhtml", N).text
        assert text.startswith(f"{entry.pou.kind} {entry.pou.name}")
        assert text.rstrip().endswith("END_VAR") or not entry.pou.blocks
    data, _ = export_plcopen(plaintext_interfaces=False)
    assert key.encode() not in data


def test_rebuilt_st_compiles_to_the_same_layout(exported, tmp_path):
    _, _, root = exported
    st = tmp_path / "roundtrip.st"
    st.write_text(xml_to_st(root))
    mine = json.loads(Path(build(st, backend="builtin", cache_dir=tmp_path / "c").manifest).read_text())
    lib = json.loads(Path(build(LIBRARY, backend="builtin", cache_dir=tmp_path / "c").manifest).read_text())
    assert mine["types"] == lib["types"] and set(mine["pous"]) == set(lib["pous"])


@pytest.mark.matiec
@pytest.mark.skipif(MATIEC is None, reason=MATIEC_MISSING)
def test_rebuilt_st_gives_matiec_the_same_c(exported, tmp_path):
    _, _, root = exported
    st = tmp_path / "roundtrip.st"
    st.write_text(xml_to_st(root))

    def iec2c(src: Path, out: Path, cwd: Path):
        out.mkdir()
        proc = subprocess.run([str(MATIEC.iec2c), "-f", "-l", "-p", "-I", str(MATIEC.lib), "-T", str(out), str(src)],
                              cwd=cwd, capture_output=True, text=True, timeout=120)
        assert proc.returncode == 0, proc.stderr

    iec2c(st, tmp_path / "rt", tmp_path)
    iec2c(LIBRARY.relative_to(REPO), tmp_path / "lib", REPO)
    for name in ("POUS.h", "POUS.c"):
        assert (tmp_path / "rt" / name).read_bytes() == (tmp_path / "lib" / name).read_bytes(), name


PROJECT = REPO / "plc_project"


@pytest.mark.skipif(not (PROJECT / "plc.st").is_file(), reason="plc_project/plc.st not present in this checkout")
def test_the_plc_project_exports_whole_with_its_configuration(tmp_path):
    """`--entry plc_project`: library, program and configuration in one document (a Beremiz project)."""
    data, lib = export_plcopen(PROJECT)
    root = etree.fromstring(data)
    if SCHEMA.is_file():
        assert validate(data, SCHEMA) == []
    assert lib.configurations and root.find("p:instances/p:configurations/p:configuration/p:resource/p:task", N) \
        is not None
    rebuilt = declarations(parse(xml_to_st(root), "roundtrip.st"))
    original = declarations(lib.elements)
    assert [label(n) for n in rebuilt] == [label(n) for n in original]
    for mine, theirs in zip(rebuilt, original):
        assert norm(mine) == norm(theirs), label(theirs)


# ------------------------------------------------------------------ what st_lib does not use

COVERAGE_LIB = """
    (* a library that uses what st_lib does not *)
    TYPE
      T_Range : INT(-10..10);
      T_URange : UINT(1..100) := 5;
      T_Alias : DINT := 42;
      T_Alias2 : T_Alias;
      T_Matrix : ARRAY[0..2, 1..4] OF INT := [1, 2, 10(7)];
      E_Color : (RED, GREEN, BLUE) := GREEN;
      T_Rec : STRUCT
        Name : STRING := 'a$'b';    (* quoted *)
        Pos : T_Range := -3;
        Tab : ARRAY[1..3] OF REAL := [1.5, 2(0.0)];
        When : TIME := T#1h2m;
        Day : TOD := TOD#12:30:00;
        Color : E_Color := E_Color#BLUE;
      END_STRUCT;
      T_Recs : ARRAY[1..2] OF T_Rec;
    END_TYPE

    FUNCTION F_Add : DINT
      VAR_INPUT
        a, b : DINT;
      END_VAR
      VAR CONSTANT
        K : DINT := 16#10;
      END_VAR
      F_Add := a + b + K;
    END_FUNCTION

    FUNCTION_BLOCK FB_Count
      VAR_INPUT
        Enable : BOOL;
      END_VAR
      VAR_OUTPUT
        N : UDINT;
      END_VAR
      VAR_IN_OUT
        S : T_Rec;
      END_VAR
      VAR RETAIN
        Total : UDINT;
      END_VAR
      VAR
        Edge : R_TRIG;
        Cfg : T_Rec;
        M : T_Matrix;
      END_VAR
      VAR_EXTERNAL
        G_Limit : UDINT;
      END_VAR
      VAR_TEMP
        Next : UDINT;
      END_VAR
      Edge(CLK := Enable);
      Next := N + 1;
      IF Edge.Q AND Next <= G_Limit THEN
        N := N + 1;
        Total := Total + 1;
      END_IF;
    END_FUNCTION_BLOCK

    PROGRAM P_Main
      VAR
        Rec : T_Rec;
        Count : FB_Count;
        Arr : ARRAY[1..3] OF INT := [3(1)];
        Idx : ARRAY[1..3] OF INT := [1, 2, 3];
        Sum : DINT;
      END_VAR
      VAR
        Cell AT %MW10 : INT;
      END_VAR
      VAR_EXTERNAL CONSTANT
        G_K : INT;
      END_VAR
      Count(Enable := TRUE, S := Rec);
      IF Arr[Idx[1]]>0 THEN  (* "]]>" ends a CDATA section: this body cannot be one *)
        Sum := F_Add(a := 1, b := INT_TO_DINT(G_K));
      END_IF;
      Cell := Arr[2];
    END_PROGRAM

    CONFIGURATION Cfg0
      VAR_GLOBAL
        G_Limit : UDINT := 10;
      END_VAR
      RESOURCE Res0 ON PLC
        VAR_GLOBAL CONSTANT
          G_K : INT := 3;
        END_VAR
        TASK Fast(INTERVAL := T#10ms, PRIORITY := 1);
        PROGRAM Inst0 WITH Fast : P_Main;
      END_RESOURCE
    END_CONFIGURATION
    """


@pytest.fixture(scope="module")
def coverage(tmp_path_factory):
    folder = tmp_path_factory.mktemp("cov")
    entry = folder / "st_lib" / "linmot.st"
    entry.parent.mkdir()
    entry.write_text(textwrap.dedent(COVERAGE_LIB).lstrip("\n"))
    data, lib = export_plcopen(entry)
    return entry, data, lib, etree.fromstring(data)


@requires_schema
def test_coverage_library_validates(coverage):
    _, data, _, _ = coverage
    assert validate(data, SCHEMA) == []


def test_coverage_library_round_trips(coverage, tmp_path):
    entry, data, lib, root = coverage
    text = xml_to_st(root)
    rebuilt = declarations(parse(text, "roundtrip.st"))
    original = declarations(lib.elements)
    assert [label(n) for n in rebuilt] == [label(n) for n in original]
    for mine, theirs in zip(rebuilt, original):
        assert norm(mine) == norm(theirs), label(theirs)
    st = tmp_path / "roundtrip.st"
    st.write_text(text)
    mine = json.loads(Path(build(st, backend="builtin", cache_dir=tmp_path / "c").manifest).read_text())
    orig = json.loads(Path(build(entry, backend="builtin", cache_dir=tmp_path / "c").manifest).read_text())
    assert mine["types"] == orig["types"] and mine["roots"] == orig["roots"]


def test_coverage_library_xml_details(coverage):
    _, data, _, root = coverage
    dt = {d.get("name"): d for d in root.findall("p:types/p:dataTypes/p:dataType", N)}
    assert dt["T_Range"].find("p:baseType/p:subrangeSigned/p:range", N).attrib == {"lower": "-10", "upper": "10"}
    assert dt["T_URange"].find("p:baseType/p:subrangeUnsigned/p:baseType/p:UINT", N) is not None
    assert dt["T_Alias2"].find("p:baseType/p:derived", N).get("name") == "T_Alias"
    dims = dt["T_Matrix"].findall("p:baseType/p:array/p:dimension", N)
    assert [(d.get("lower"), d.get("upper")) for d in dims] == [("0", "2"), ("1", "4")]
    reps = dt["T_Matrix"].findall("p:initialValue/p:arrayValue/p:value", N)
    assert [r.get("repetitionValue") for r in reps] == [None, None, "10"]
    assert dt["T_Rec"].find("p:baseType/p:struct/p:variable[@name='Day']/p:type/p:TOD", N) is not None
    pou = {p.get("name"): p for p in root.findall("p:types/p:pous/p:pou", N)}
    itf = pou["FB_Count"].find("p:interface", N)
    assert itf.find("p:localVars", N).get("retain") == "true"
    assert itf.find("p:externalVars/p:variable", N).get("name") == "G_Limit"
    assert pou["F_Add"].find("p:interface/p:localVars", N).get("constant") == "true"
    assert pou["FB_Count"].find("p:interface/p:tempVars/p:variable", N).get("name") == "Next"
    assert pou["P_Main"].find("p:interface/p:localVars/p:variable[@name='Cell']", N).get("address") == "%MW10"
    assert b"Arr[Idx[1]]&gt;0" in data      # not a CDATA section here
    conf = root.find("p:instances/p:configurations/p:configuration", N)
    assert conf.get("name") == "Cfg0"
    task = conf.find("p:resource/p:task", N)
    assert (task.get("name"), task.get("interval"), task.get("priority")) == ("Fast", "T#10ms", "1")
    assert task.find("p:pouInstance", N).attrib == {"name": "Inst0", "typeName": "P_Main"}
    assert conf.find("p:resource/p:globalVars", N).get("constant") == "true"


def test_what_plcopen_cannot_hold_is_a_clear_error(tmp_path):
    entry = tmp_path / "st_lib" / "linmot.st"
    entry.parent.mkdir()
    entry.write_text(textwrap.dedent("""
        PROGRAM Prog
          VAR_INPUT
            I : INT;
          END_VAR
          I := I + 1;
        END_PROGRAM
        CONFIGURATION C
          VAR_GLOBAL
            G : INT;
          END_VAR
          RESOURCE R ON PLC
            TASK T(INTERVAL := T#1ms, PRIORITY := 0);
            PROGRAM Inst WITH T : Prog(I := G);
          END_RESOURCE
        END_CONFIGURATION
        """))
    # the checker refuses it first (MatIEC cannot compile it either) ...
    with pytest.raises(ExportError, match=r"does not compile:\n.*linmot.st:14:\d+: error: binding program"):
        export_plcopen(entry)
    # ... and the XML writer on its own says why PLCopen cannot hold it
    with pytest.raises(ExportError, match=r"linmot.st:14:\d+: program instances with parameter bindings"):
        build_tree(read_library(entry, check=False))


def test_struct_initial_values_become_struct_values(tmp_path):
    """Struct initialisers export as structValue, also those the builtin checker refuses (struct initialisers inside arrays)."""
    entry = tmp_path / "st_lib" / "linmot.st"
    entry.parent.mkdir()
    entry.write_text(textwrap.dedent("""
        TYPE
          T_P : STRUCT
            X : INT;
            Name : STRING;
          END_STRUCT;
          T_Ps : ARRAY[1..3] OF T_P := [(X := 1, Name := 'a'), 2((X := 5))];
        END_TYPE
        FUNCTION_BLOCK FB_S
          VAR
            P : T_P := (X := -2);
          END_VAR
          P.X := P.X + 1;
        END_FUNCTION_BLOCK
        """))
    lib = read_library(entry, check=False)
    data = etree.tostring(build_tree(lib))
    root = etree.fromstring(data)
    if SCHEMA.is_file():
        assert validate(data, SCHEMA) == []
    first = root.find("p:types/p:dataTypes/p:dataType[@name='T_Ps']/p:initialValue/p:arrayValue/p:value", N)
    assert [(v.get("member"), v.find("p:simpleValue", N).get("value")) for v in first.find("p:structValue", N)] \
        == [("X", "1"), ("Name", "'a'")]
    rebuilt = declarations(parse(xml_to_st(root), "roundtrip.st"))
    original = declarations(lib.elements)
    assert [norm(n) for n in rebuilt] == [norm(n) for n in original]


# ------------------------------------------------------------------ the command

@requires_schema
def test_cli_writes_valid_xml(tmp_path, capsys):
    out = tmp_path / "lib.xml"
    assert cli_main(["export", "plcopen", str(out), "--schema", str(SCHEMA)]) == 0
    msg = capsys.readouterr().out
    c = read_library().counts
    assert f"wrote {out}: {c['types']} data types, {c['functions']} functions, {c['function_blocks']} " \
           f"function blocks" in msg
    assert f"{out.stat().st_size:,} bytes" in msg and "valid against" in msg
    assert validate(out, SCHEMA) == []


def test_cli_errors(tmp_path, capsys):
    assert cli_main(["export", "plcopen", str(tmp_path / "no" / "lib.xml")]) == 2     # checked before the export
    assert "linmot-st export plcopen: error: " in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit_:
        cli_main(["export", "plcopen", str(tmp_path / "lib.xml"), "--schema", str(tmp_path / "x.xsd")])
    assert exit_.value.code == 2
    assert "x.xsd: no such file" in capsys.readouterr().err
    bad = tmp_path / "bad.xsd"
    bad.write_text('<xsd:schema xmlns:xsd="http://www.w3.org/2001/XMLSchema" '
                   'targetNamespace="urn:other"><xsd:element name="other"/></xsd:schema>')
    assert cli_main(["export", "plcopen", str(tmp_path / "lib.xml"), "--schema", str(bad)]) == 1
    assert "does not validate" in capsys.readouterr().err
    assert not (tmp_path / "lib.xml").exists()
