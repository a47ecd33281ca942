"""A readable summary of a PVL file (`linmot-st pvl show FILE`)."""

from __future__ import annotations

from . import codec
from .model import PvlFile


def summary(pvl: PvlFile, *, verbose: bool = False) -> str:
    layers, curves, entries = pvl.parameter_objects, pvl.curves, pvl.command_table
    out = [f"{pvl.filename or '<model>'}: PVL format {pvl.format_version}: "
           f"{_n(len(layers), 'parameter layer')}, {_n(len(curves), 'curve')}, "
           f"{_n(len(entries), 'command-table entry', 'command-table entries')}, "
           f"for {pvl.drive_type.a_name}"]
    for obj in layers:
        out.append("")
        out.append(f"Layer {obj.layer} ({obj.layer_name}): tree {obj.tree_file_name}, tree ID {obj.tree_id}, "
                   f"version {obj.main_version}.{obj.sub_version}, revision {obj.revision}: "
                   f"{_n(len(obj.parameters), 'parameter')}")
        if obj.layer in obj.drive_type.identity_upids:
            tree, main, sub = obj.identity_upids
            out.append(f"  compatibility: the drive's UPID {tree:04X}h must read {obj.tree_id}, "
                       f"{main:04X}h {obj.main_version}, {sub:04X}h {obj.sub_version} or more")
        strings = obj.strings()
        in_strings = {p.upid for s in strings for p in s.stringlets}
        for s in strings:
            last = s.stringlets[-1].upid
            out.append(f"  string {s.upid:04X}h {s.name} = {s.text!r} "
                       f"(stringlets {s.stringlets[0].upid:04X}h..{last:04X}h)")
        rows = obj.parameters if verbose else [p for p in obj.parameters if p.upid not in in_strings]
        for p in rows:
            scaled = f"  = {p.scaled_value}" if p.scaled_value else ""
            out.append(f"  {p.upid:04X}h  {p.value:08X}h  {p.caption}{scaled}")
    if curves:
        out.append("")
        out.append("Curves:")
        out.append(f"  {'ID':>3}  {'name':<22} {'setpoints':>9}  {'x-length':<22} type")
        for c in curves:
            info = c.info
            out.append(f"  {info.curve_id:>3}  {info.name:<22} {info.setpoints:>9}  "
                       f"{_x_length(info):<22} {info.kind} ({info.object_type:04X}h)")
            if verbose:
                lo, hi = min(c.setpoints), max(c.setpoints)
                out.append(f"       XDimUUID {info.x_dim_uuid:04X}h, YDimUUID {info.y_dim_uuid:04X}h, "
                           f"wizard type {info.wizard_type:04X}h, wizard parameters {list(info.wizard_params)}; "
                           f"setpoints {lo}..{hi} ({_units(info.y_dim_uuid)})")
    if entries:
        out.append("")
        out.append("Command table (project extension objects):")
        out.append(f"  {'ID':>3}  {'name':<17} {'command':<8} linked")
        for e in entries:
            b = e.block
            linked = "-" if b.linked_entry == codec.CT_NOT_LINKED else str(b.linked_entry)
            out.append(f"  {e.entry_id:>3}  {b.name:<17} {b.motion_header:04X}h    {linked}")
            if verbose:
                out.append(f"       parameters {b.parameters.hex(' ').upper()}")
    return "\n".join(out) + "\n"


def _x_length(info: codec.CurveInfo) -> str:
    if info.x_dim_uuid == codec.UUID_TIME:
        return f"{info.x_length} ({info.x_length / 100:g} ms)"
    if info.x_dim_uuid == codec.UUID_ENCODER:
        return f"{info.x_length} increments"
    return f"{info.x_length} ({_units(info.x_dim_uuid)})"


def _units(uuid: int) -> str:
    return codec.UUID_UNITS.get(uuid, f"unit {uuid:04X}h")


def _n(count: int, singular: str, plural: str | None = None) -> str:
    return f"{count} {singular if count == 1 else (plural or singular + 's')}"
