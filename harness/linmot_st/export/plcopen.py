"""The library as PLCopen XML (TC6 XML 2.01, namespace http://www.plcopen.org/xml/tc6_0201).

Every TYPE becomes a `dataType` (struct, array with its dimensions, enum, subrange, alias), every POU a
`pou` with its interface (one varList per declaration block, in source order, with its CONSTANT/RETAIN
attribute; initial values as simpleValue/arrayValue/structValue) and its body as the original ST text in
`<body><ST><xhtml:p><![CDATA[…]]></xhtml:p></ST></body>`, the form Beremiz writes and reads.
Comments that document a declaration go to its `documentation` element.

Two additions that the schema allows and that help importers keep what TC6 cannot express:
- each POU carries its declaration part as written (CODESYS's `interfaceasplaintext` addData, which
  CODESYS and TwinCAT read to keep comments and layout; other tools ignore unknown addData);
- a CONFIGURATION, if the entry file has one, goes to `instances` (tasks, program instances, globals).
"""

from __future__ import annotations

import datetime
import os
from pathlib import Path

from lxml import etree

from linmot_st.toolchain.builtin import ast as A
from linmot_st.toolchain.builtin import types as T

from .library import ExportError, Library, read_library
from .st import package_version, sources_digest

NS = "http://www.plcopen.org/xml/tc6_0201"
XHTML = "http://www.w3.org/1999/xhtml"
NSMAP = {None: NS, "xhtml": XHTML}
CODESYS_PLAINTEXT = "http://www.3s-software.com/plcopenxml/interfaceasplaintext"

POU_TYPES = {"FUNCTION": "function", "FUNCTION_BLOCK": "functionBlock", "PROGRAM": "program"}
VAR_LISTS = {"VAR": "localVars", "VAR_TEMP": "tempVars", "VAR_INPUT": "inputVars", "VAR_OUTPUT": "outputVars",
             "VAR_IN_OUT": "inOutVars", "VAR_EXTERNAL": "externalVars", "VAR_GLOBAL": "globalVars"}
QUALIFIERS = {"CONSTANT": "constant", "RETAIN": "retain", "NON_RETAIN": "nonretain", "PERSISTENT": "persistent"}
# PLCopen spells the elementary types as IEC does, except the date/time ones and the strings
ELEMENTARY = {name: name for name in T.ELEMENTARY} | {"TIME_OF_DAY": "TOD", "DATE_AND_TIME": "DT",
                                                     "STRING": "string", "WSTRING": "wstring"}
UNSIGNED = {t.name for t in T.UNSIGNED_INTS + T.NBITS}


def _q(tag: str) -> str:
    return f"{{{NS}}}{tag}"


def _sub(parent, tag: str, **attrs) -> etree._Element:
    return etree.SubElement(parent, _q(tag), {k: str(v) for k, v in attrs.items() if v is not None})


def _formatted(parent, tag: str, text: str) -> etree._Element:
    """A formattedText element holding `text` as one xhtml:p (CDATA where the text allows it)."""
    el = _sub(parent, tag)
    p = etree.SubElement(el, f"{{{XHTML}}}p")
    p.text = etree.CDATA(text) if "]]>" not in text else text
    return el


def timestamp() -> str:
    """SOURCE_DATE_EPOCH when set (reproducible files), else now; UTC, xsd:dateTime."""
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    t = (datetime.datetime.fromtimestamp(int(epoch), datetime.timezone.utc) if epoch
         else datetime.datetime.now(datetime.timezone.utc))
    return t.replace(microsecond=0).strftime("%Y-%m-%dT%H:%M:%SZ")


# ---------------------------------------------------------------------------------------- values

def expr_text(e: A.Node) -> str:
    """An initial value's expression as ST text (literals as written)."""
    if isinstance(e, A.Literal):
        text = e.text or str(e.value)
        text = f"{e.type_name}#{text}" if e.type_name else text
    elif isinstance(e, A.EnumLit):
        text = f"{e.type_name}#{e.value}" if e.type_name else e.value
    elif isinstance(e, A.Name):
        text = e.name
    elif isinstance(e, A.UnOp):
        text = ("-" if e.op == "NEG" else "NOT ") + expr_text(e.operand)
    elif isinstance(e, A.BinOp):
        text = f"{expr_text(e.left)} {e.op} {expr_text(e.right)}"
    elif isinstance(e, A.Member):
        text = f"{expr_text(e.base)}.{e.name}"
    elif isinstance(e, A.Index):
        text = f"{expr_text(e.base)}[{', '.join(expr_text(i) for i in e.indices)}]"
    elif isinstance(e, A.Call):
        args = ", ".join((f"{a.name} {'=>' if a.output else ':='} " if a.name else "") + expr_text(a.value)
                         for a in e.args)
        text = f"{e.name}({args})"
    else:
        raise ExportError(f"{e.pos}: this initial value cannot be exported ({type(e).__name__})")
    return f"({text})" if getattr(e, "paren", False) else text


def value_element(parent, tag: str, init: A.Node, **attrs) -> etree._Element:
    """A PLCopen `value`: simpleValue, arrayValue (with repetitionValue) or structValue."""
    el = _sub(parent, tag, **attrs)
    if isinstance(init, A.ArrayInit):
        arr = _sub(el, "arrayValue")
        for count, item in init.entries():
            if item is None:           # n() : n elements keep their default
                _sub(_sub(arr, "value", repetitionValue=count), "simpleValue")
            else:
                value_element(arr, "value", item, repetitionValue=count if count != 1 else None)
    elif isinstance(init, A.StructInit):
        st = _sub(el, "structValue")
        for member, _pos, item in init.items:
            value_element(st, "value", item, member=member)
    else:
        _sub(el, "simpleValue", value=expr_text(init))
    return el


# ----------------------------------------------------------------------------------------- types

class _Writer:
    def __init__(self, lib: Library, plaintext_interfaces: bool):
        self.lib = lib
        self.plaintext = plaintext_interfaces
        # declared spellings of user types and POUs, for references written in another case
        self.names = {t.decl.name.upper(): t.decl.name for t in lib.types}
        self.names.update({p.pou.name.upper(): p.pou.name for p in lib.pous})

    def type_element(self, parent, tag: str, spec: A.Node, docs: dict[int, str] | None = None):
        el = _sub(parent, tag)
        self.type_content(el, spec, docs or {})
        return el

    def type_content(self, el, spec: A.Node, docs: dict[int, str]) -> None:
        if isinstance(spec, A.NamedSpec):
            key = spec.name.upper()
            if key in ELEMENTARY:
                _sub(el, ELEMENTARY[key])
            else:
                _sub(el, "derived", name=self.names.get(key, spec.name))
        elif isinstance(spec, A.ArraySpec):
            if spec.star or any(not isinstance(b, int) for r in spec.ranges for b in r):
                raise ExportError(f"{spec.pos}: only arrays with literal bounds can be exported")
            arr = _sub(el, "array")
            for lo, hi in spec.ranges:
                _sub(arr, "dimension", lower=lo, upper=hi)
            self.type_element(arr, "baseType", spec.elem, docs)
        elif isinstance(spec, A.StructSpec):
            st = _sub(el, "struct")
            for f in spec.fields:
                self.variable(st, f.name, f.spec, f.init, docs.get(id(f)), docs)
        elif isinstance(spec, A.EnumSpec):
            if spec.explicit:
                raise ExportError(f"{spec.pos}: enum values with explicit numbers are outside the subset")
            values = _sub(_sub(el, "enum"), "values")
            for name, _pos in spec.values:
                _sub(values, "value", name=name)
        elif isinstance(spec, A.SubrangeSpec):
            kind = "subrangeUnsigned" if spec.base.upper() in UNSIGNED else "subrangeSigned"
            sr = _sub(el, kind)
            _sub(sr, "range", lower=spec.lo, upper=spec.hi)
            self.type_element(sr, "baseType", A.NamedSpec(spec.pos, spec.base))
        elif isinstance(spec, A.StringLenSpec):
            _sub(el, ELEMENTARY.get(spec.base.upper(), "string"), length=spec.length)
        else:
            raise ExportError(f"{spec.pos}: {getattr(spec, 'what', type(spec).__name__)} cannot be exported")

    def variable(self, parent, name: str, spec: A.Node, init: A.Node | None, doc: str | None,
                 docs: dict[int, str] | None = None, address: str | None = None) -> None:
        var = _sub(parent, "variable", name=name, address=address)
        self.type_element(var, "type", spec, docs)
        if init is not None:
            value_element(var, "initialValue", init)
        if doc:
            _formatted(var, "documentation", doc)

    def data_types(self, parent) -> None:
        dts = _sub(parent, "dataTypes")
        for t in self.lib.types:
            d = t.decl
            dt = _sub(dts, "dataType", name=d.name)
            self.type_element(dt, "baseType", d.spec, t.field_docs)
            if d.init is not None:
                value_element(dt, "initialValue", d.init)
            if t.doc:
                _formatted(dt, "documentation", t.doc)

    # ------------------------------------------------------------------------------------ POUs
    def var_list(self, parent, block: A.VarBlock, docs: dict[int, str]) -> None:
        tag = VAR_LISTS.get(block.kind)
        if tag is None:
            raise ExportError(f"{block.pos}: {block.kind} blocks cannot be exported")
        attrs = {QUALIFIERS[block.qualifier]: "true"} if block.qualifier in QUALIFIERS else {}
        lst = _sub(parent, tag, **attrs)
        for decl in block.decls:
            if decl.edge:
                raise ExportError(f"{decl.pos}: {decl.edge} declarations cannot be exported")
            for name, _pos in decl.names:
                self.variable(lst, name, decl.spec, decl.init, docs.get(id(decl)), address=decl.location)

    def pous(self, parent) -> None:
        pous = _sub(parent, "pous")
        for entry in self.lib.pous:
            p = entry.pou
            pou = _sub(pous, "pou", name=p.name, pouType=POU_TYPES[p.kind])
            itf = _sub(pou, "interface")
            if p.return_spec is not None:
                self.type_element(itf, "returnType", p.return_spec)
            for block in p.blocks:
                self.var_list(itf, block, entry.var_docs)
            body = _sub(pou, "body")
            _formatted(body, "ST", entry.body)
            if self.plaintext:
                data = _sub(_sub(pou, "addData"), "data", name=CODESYS_PLAINTEXT, handleUnknown="implementation")
                text = etree.SubElement(_sub(data, "InterfaceAsPlainText"), f"{{{XHTML}}}xhtml", nsmap={None: XHTML})
                text.text = entry.declarations + "\n"
            if entry.doc:
                _formatted(pou, "documentation", entry.doc)

    # --------------------------------------------------------------------------- configurations
    def configurations(self, parent) -> None:
        confs = _sub(_sub(parent, "instances"), "configurations")
        for c in self.lib.configurations:
            conf = _sub(confs, "configuration", name=c.name)
            for r in c.resources:
                res = _sub(conf, "resource", name=r.name)
                tasks = {}
                for t in r.tasks:
                    params = {n.upper(): expr_text(v) for n, _p, v in t.params}
                    tasks[t.name.upper()] = _sub(res, "task", name=t.name, single=params.get("SINGLE"),
                                                 interval=params.get("INTERVAL"),
                                                 priority=params.get("PRIORITY", "0"))
                for block in r.globals:
                    self.global_list(res, block)
                for pc in r.programs:
                    if pc.bindings:
                        raise ExportError(f"{pc.pos}: program instances with parameter bindings cannot be "
                                          f"expressed in PLCopen XML")
                    holder = tasks.get(pc.task.upper()) if pc.task else res
                    if holder is None:
                        raise ExportError(f"{pc.pos}: unknown task {pc.task}")
                    _sub(holder, "pouInstance", name=pc.name, typeName=self.names.get(pc.type_name.upper(),
                                                                                       pc.type_name))
                # the schema wants a resource's tasks, then its globals, then its free program instances
                _reorder(res, ["task", "globalVars", "pouInstance"])
            for block in c.globals:
                self.global_list(conf, block)
            _reorder(conf, ["resource", "globalVars"])

    def global_list(self, parent, block: A.VarBlock) -> None:
        attrs = {QUALIFIERS[block.qualifier]: "true"} if block.qualifier in QUALIFIERS else {}
        lst = _sub(parent, "globalVars", **attrs)
        for decl in block.decls:
            for name, _pos in decl.names:
                self.variable(lst, name, decl.spec, decl.init, None, address=decl.location)


def _reorder(el, order: list[str]) -> None:
    children = sorted(el, key=lambda c: order.index(etree.QName(c).localname))
    for c in children:
        el.append(c)


# ------------------------------------------------------------------------------------- document

def build_tree(lib: Library, plaintext_interfaces: bool = True) -> etree._ElementTree:
    w = _Writer(lib, plaintext_interfaces)
    now = timestamp()
    project = etree.Element(_q("project"), nsmap=NSMAP)
    _sub(project, "fileHeader", companyName="linmot-st project", productName="linmot-st",
         productVersion=package_version(), creationDateTime=now,
         contentDescription=f"{lib.names[0]} and its includes, exported by `linmot-st export plcopen`")
    ch = _sub(project, "contentHeader", name="LinMot ST library", version=package_version(),
              modificationDateTime=now, language="en")
    c = lib.counts
    _sub(ch, "Comment").text = (
        f"LinMot E1100/B1100 configuration over CANopen: {c['types']} data types, {c['functions']} functions, "
        f"{c['function_blocks']} function blocks. Sources: {', '.join(lib.names)} "
        f"(sha256 {sources_digest(lib.files)}). Generated: edit the ST sources, not this file.")
    info = _sub(ch, "coordinateInfo")
    for lang in ("fbd", "ld", "sfc"):
        _sub(_sub(info, lang), "scaling", x=0, y=0)
    types = _sub(project, "types")
    w.data_types(types)
    w.pous(types)
    w.configurations(project)
    return etree.ElementTree(project)


def export_plcopen(entry: str | Path | None = None, plaintext_interfaces: bool = True):
    """(XML bytes, Library) of the library of `entry` (default st_lib/linmot.st). Raises ExportError."""
    lib = read_library(entry)
    tree = build_tree(lib, plaintext_interfaces)
    data = etree.tostring(tree, xml_declaration=True, encoding="utf-8", pretty_print=True)
    return data, lib


def validate(xml: bytes | str | Path, schema: str | Path) -> list[str]:
    """Errors of `xml` against the XSD `schema` ("line N: message"), [] when valid."""
    xsd = etree.XMLSchema(etree.parse(str(schema)))
    doc = etree.parse(str(xml)) if isinstance(xml, (str, Path)) else etree.fromstring(xml).getroottree()
    if xsd.validate(doc):
        return []
    return [f"line {e.line}: {e.message}" for e in xsd.error_log]
