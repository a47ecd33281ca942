"""The checks a PVL model must pass, whether it was read from a file or built in code.

The parser runs them on what it read (with the file lines kept in each object's `source`), the writer
on what it is asked to write, so a file this package writes always parses back to the same model.
Checks that compare a file's header lines with the blocks they describe (@CurveID against the info
block, sizes against the words given) need the text and live in `parser.py`.
"""

from __future__ import annotations

from . import codec
from .errors import Diagnostic
from .layers import LAYERS
from .model import CommandTableEntry, Curve, Parameter, ParameterObject, PvlFile, Source

UINT16_MAX = 0xFFFF
UINT32_MAX = 0xFFFFFFFF
INT32_MIN, INT32_MAX = -(1 << 31), (1 << 31) - 1


def validate(pvl: PvlFile) -> list[Diagnostic]:
    out: list[Diagnostic] = []
    if pvl.format_version != 1:
        out.append(Diagnostic(None, f"format version {pvl.format_version} is not supported (only 1)"))
    layers: dict[int, ParameterObject] = {}
    curves: dict[int, Curve] = {}
    entries: dict[int, CommandTableEntry] = {}
    out += _check_drive_type(pvl)
    for obj in pvl.objects:
        if isinstance(obj, ParameterObject):
            out += _check_parameter_object(obj)
            if obj.layer in layers:
                out.append(_at(obj.source, "TreeLayer",
                               f"layer {obj.layer} has a second Parameter object "
                               f"(the first{_line_note(layers[obj.layer].source)})"))
            else:
                layers[obj.layer] = obj
        elif isinstance(obj, Curve):
            problems = _check_curve(obj)
            out += problems
            if len(obj.info_block) == codec.INFO_BLOCK_SIZE:
                cid = obj.curve_id
                if cid in curves:
                    out.append(_at(obj.source, "CurveID", f"curve {cid}: duplicate curve ID "
                                                          f"(the first{_line_note(curves[cid].source)})"))
                else:
                    curves[cid] = obj
        elif isinstance(obj, CommandTableEntry):
            out += _check_entry(obj)
            if obj.entry_id in entries:
                out.append(_at(obj.source, "EntryID",
                               f"command-table entry {obj.entry_id}: duplicate entry ID "
                               f"(the first{_line_note(entries[obj.entry_id].source)})"))
            else:
                entries[obj.entry_id] = obj
        else:
            out.append(Diagnostic(None, f"not a PVL object: {type(obj).__name__}"))
    return out


# --- parameters ----------------------------------------------------------------------------------------

def _check_parameter_object(obj: ParameterObject) -> list[Diagnostic]:
    out = []
    where = f"layer {obj.layer}"
    if obj.layer not in LAYERS:
        out.append(_at(obj.source, "TreeLayer", f"layer {obj.layer} does not exist (layers are 1..4)"))
    for key, value in (("TreeID", obj.tree_id), ("MainVersion", obj.main_version),
                       ("SubVersion", obj.sub_version)):
        if not 0 <= value <= UINT16_MAX:
            out.append(_at(obj.source, key, f"{where}: @{key} {value} is outside 0..65535"))
    for key, text in (("TreeFileName", obj.tree_file_name), ("Revision", obj.revision)):
        if msg := text_problem(text, trailing_space=False):
            out.append(_at(obj.source, key, f"{where}: @{key} {msg}"))
    # E1100 UPIDs lie in their layer's range (Table 3); B1100 UPIDs of all layers are mixed (seed 000 3)
    layer = LAYERS.get(obj.layer) if obj.drive_type.layer_ranges else None
    seen: dict[int, Parameter] = {}
    for p in obj.parameters:
        out += _check_parameter(p, where, layer)
        if p.upid in seen:
            first = seen[p.upid].line
            out.append(Diagnostic(p.line or _line(obj.source),
                                  f"{where}: UPID {p.upid:04X}h appears twice"
                                  + (f" (first at line {first})" if first else "")))
        else:
            seen[p.upid] = p
    return out


def _check_parameter(p: Parameter, where: str, layer) -> list[Diagnostic]:
    out = []
    if not 0 <= p.upid <= UINT16_MAX:
        out.append(Diagnostic(p.line, f"{where}: UPID {p.upid:#x} is not a 16-bit number"))
    elif layer is not None and not layer.holds(p.upid):
        out.append(Diagnostic(p.line, f"{where}: UPID {p.upid:04X}h is outside the {layer.name} range "
                                      f"{layer.upid_first:04X}h..{layer.upid_last:04X}h"))
    if not 0 <= p.value <= UINT32_MAX:
        out.append(Diagnostic(p.line, f"{where}: UPID {p.upid:04X}h: value {p.value:#x} is not a raw 32-bit value"))
    if msg := text_problem(p.caption, comma=False):
        out.append(Diagnostic(p.line, f"{where}: UPID {p.upid:04X}h: caption {msg}"))
    if msg := text_problem(p.scaled_value, trailing_space=False):
        out.append(Diagnostic(p.line, f"{where}: UPID {p.upid:04X}h: scaled value {msg}"))
    return out


def _check_drive_type(pvl: PvlFile) -> list[Diagnostic]:
    """One drive series per file; no curve or command-table object in a file for a series without them."""
    out = []
    objs = pvl.parameter_objects
    kind = pvl.drive_type
    for o in objs:
        if o.drive_type is not kind:
            out.append(_at(o.source, "TreeFileName",
                           f"layer {o.layer}: tree {o.tree_file_name!r} is for {o.drive_type.a_name}, "
                           f"layer {objs[0].layer}'s tree {objs[0].tree_file_name!r} for {kind.a_name} "
                           "(one file is for one drive series)"))
    for c in pvl.curves if not kind.curves else ():
        out.append(_at(c.source, None, f"a curve object in a file for {kind.a_name}: the {kind.name} has no "
                                       "curves (seed 000 chapter 5)"))
    for e in pvl.command_table if not kind.command_table else ():
        out.append(_at(e.source, None, f"a command-table object in a file for {kind.a_name}: the {kind.name} "
                                       "has no command table (seed 000 chapter 6)"))
    return out


# --- curves --------------------------------------------------------------------------------------------

def _check_curve(curve: Curve) -> list[Diagnostic]:
    src = curve.source
    if len(curve.info_block) != codec.INFO_BLOCK_SIZE:
        return [_at(src, None, f"curve: the info block has {len(curve.info_block)} bytes, "
                               f"must be {codec.INFO_BLOCK_SIZE}")]
    info = curve.info
    where = f"curve {info.curve_id}"
    out = []
    for offset, msg in codec.curve_info_problems(curve.info_block, len(curve.setpoints)):
        out.append(Diagnostic(_word_line(src, src.info_lines if src else (), offset // 4), f"{where}: {msg}"))
    if msg := text_problem(info.name, trailing_space=False):
        out.append(_at(src, "CurveName", f"{where}: name {msg}"))
    for i, v in enumerate(curve.setpoints):
        if not INT32_MIN <= v <= INT32_MAX:
            out.append(Diagnostic(_word_line(src, src.data_lines if src else (), i),
                                  f"{where}: setpoint {i + 1} ({v}) is not a signed 32-bit value"))
    return out


# --- command table -------------------------------------------------------------------------------------

def _check_entry(entry: CommandTableEntry) -> list[Diagnostic]:
    src = entry.source
    where = f"command-table entry {entry.entry_id}"
    out = []
    if not codec.CT_ENTRY_MIN <= entry.entry_id <= codec.CT_ENTRY_MAX:
        out.append(_at(src, "EntryID", f"{where}: entry ID outside {codec.CT_ENTRY_MIN}..{codec.CT_ENTRY_MAX}"))
    if len(entry.data) != codec.CT_BLOCK_SIZE:
        return out + [_at(src, None, f"{where}: the data block has {len(entry.data)} bytes, "
                                     f"must be {codec.CT_BLOCK_SIZE}")]
    for offset, msg in codec.ct_entry_problems(entry.data):
        out.append(Diagnostic(_word_line(src, src.data_lines if src else (), offset // 4), f"{where}: {msg}"))
    if msg := text_problem(entry.name, trailing_space=False):
        out.append(_at(src, "EntryName", f"{where}: name {msg}"))
    return out


# --- helpers -------------------------------------------------------------------------------------------

def text_problem(text: str, *, comma: bool = True, trailing_space: bool = True) -> str | None:
    """Why `text` cannot stand in a PVL line (None if it can): line breaks, characters outside Latin-1,
    a comma where it would split the column, trailing blanks where the reader strips them."""
    if "\n" in text or "\r" in text:
        return f"{text!r} contains a line break"
    try:
        text.encode(codec.TEXT_ENCODING)
    except UnicodeEncodeError:
        return f"{text!r} has characters outside Latin-1"
    if not comma and "," in text:
        return f"{text!r} contains a comma (it would split the column; see docs/pvl.md)"
    if not trailing_space and text != text.rstrip(" \t"):
        return f"{text!r} ends with blanks (a reader strips them)"
    return None


def _line(src: Source | None) -> int | None:
    return src.line if src else None


def _at(src: Source | None, key: str | None, message: str) -> Diagnostic:
    if src is None:
        return Diagnostic(None, message)
    return Diagnostic(src.keys.get(key, src.line) if key else src.line, message)


def _word_line(src: Source | None, lines: tuple[int, ...], index: int) -> int | None:
    if src is None:
        return None
    return lines[index] if index < len(lines) else src.line


def _line_note(src: Source | None) -> str:
    return f" at line {src.line}" if src else " one"
