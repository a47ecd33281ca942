"""Write a `PvlFile` as PVL text, in the layout of the seeds' examples.

The output is canonical (upper-case hex, one blank line before each object, LF line ends), so
write(parse(write(m))) == write(m). The model is checked first with the same checks as a parsed
file: what this writes always reads back to the same model.
"""

from __future__ import annotations

import os

from . import codec
from .errors import PvlError
from .model import CommandTableEntry, Curve, ParameterObject, PvlFile
from .parser import PARAMETER_COLUMNS, VALUE_COLUMN
from .validate import validate


def write_pvl(pvl: PvlFile, *, check: bool = True) -> str:
    """The PVL text of `pvl`. Raises PvlError ('<model>: ...' messages) when the model is invalid."""
    if check:
        problems = validate(pvl)
        if problems:
            raise PvlError(pvl.filename or "<model>", problems)
    out = ["@FileType,PVL", f"@FormatVersion,{pvl.format_version}"]
    for obj in pvl.objects:
        out.append("")
        if isinstance(obj, ParameterObject):
            out += _parameter_object(obj)
        elif isinstance(obj, Curve):
            out += _curve(obj)
        elif isinstance(obj, CommandTableEntry):
            out += _entry(obj)
        else:
            raise TypeError(f"not a PVL object: {obj!r}")
    return "\n".join(out) + "\n"


def save_pvl(pvl: PvlFile, path: str | os.PathLike) -> None:
    """Write `pvl` to `path` (Latin-1, LF line ends)."""
    data = write_pvl(pvl).encode(codec.TEXT_ENCODING)
    with open(path, "wb") as f:
        f.write(data)


def _parameter_object(obj: ParameterObject) -> list[str]:
    lines = ["@StartObject,Parameter",
             f"@TreeFileName,{obj.tree_file_name}",
             f"@TreeLayer,{obj.layer}",
             f"@TreeID,{obj.tree_id}",
             f"@MainVersion,{obj.main_version}",
             f"@SubVersion,{obj.sub_version}",
             f"@Revision,{obj.revision}",
             "@StartData",
             PARAMETER_COLUMNS]
    lines += [f"{p.upid:04X},{p.value:08X},{p.caption},{p.scaled_value}" for p in obj.parameters]
    return lines + ["@EndData", "@EndObject"]


def _words(words) -> list[str]:
    return [f"{w:08X}h" for w in words]


def _curve(curve: Curve) -> list[str]:
    info = curve.info
    return (["@StartObject,Curve",
             f"@CurveName,{info.name}",
             f"@CurveID,{info.curve_id}",
             f"@InfoBlockByteSize,{len(curve.info_block)}",
             f"@DataBlockByteSize,{codec.SETPOINT_SIZE * len(curve.setpoints)}",
             "@StartInfo", VALUE_COLUMN]
            + _words(curve.info_words)
            + ["@EndInfo", "@StartData", VALUE_COLUMN]
            + _words(curve.data_words)
            + ["@EndData", "@EndObject"])


def _entry(entry: CommandTableEntry) -> list[str]:
    return (["@StartObject,CommandTableEntry",
             f"@EntryID,{entry.entry_id}",
             f"@EntryName,{entry.name}",
             f"@DataBlockByteSize,{len(entry.data)}",
             "@StartData", VALUE_COLUMN]
            + _words(entry.data_words)
            + ["@EndData", "@EndObject"])
