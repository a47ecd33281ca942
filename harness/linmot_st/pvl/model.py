"""The content of a PVL file as immutable values.

A `PvlFile` is a sequence of objects in file order: `ParameterObject` (the parameters of one firmware
layer with the identity of its parameter tree), `Curve` (a curve info block and its setpoints) and
`CommandTableEntry` (this project's extension, docs/pvl.md). Curves and command-table entries keep
their blocks as the exact bytes the drive receives; their decoded fields are views on those bytes.

Every object may carry a `source` (where it was read; left out of comparisons) so that the checks in
`validate.py` can point at file lines.
"""

from __future__ import annotations

import re
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field

from . import codec
from .codec import CtEntryBlock, CurveInfo
from .drive_types import E1100, DriveType, drive_type_of_tree_file
from .layers import LAYERS, TreeIdentity


@dataclass(frozen=True)
class Source:
    """Where an object was read: the line of its start, of each header key and of each word/row."""

    line: int
    keys: Mapping[str, int] = field(default_factory=dict)
    info_lines: tuple[int, ...] = ()       # curve info words
    data_lines: tuple[int, ...] = ()       # curve setpoints / command-table words


@dataclass(frozen=True)
class Parameter:
    """One row of a Parameter object. `value` is the raw 32-bit value (0..FFFFFFFFh)."""

    upid: int
    value: int
    caption: str = ""
    scaled_value: str = ""                 # the fourth column, "ScaledValue Unit"
    line: int | None = field(default=None, compare=False, repr=False)

    @property
    def signed_value(self) -> int:
        return codec.to_signed32(self.value)


@dataclass(frozen=True)
class StringParameter:
    """A string parameter recognised among the rows (see `ParameterObject.strings`)."""

    upid: int                              # the string's own UPID; stringlet k at upid + k (E1100), + k - 1 (B1100)
    name: str                              # the caption without the stringlet suffix
    text: str
    stringlets: tuple[Parameter, ...]


_STRINGLET_CAPTION = re.compile(r"(.*)_([1-9][0-9]*)", re.ASCII | re.DOTALL)


@dataclass(frozen=True)
class ParameterObject:
    """The parameters of one firmware layer (a `@StartObject,Parameter` block)."""

    tree_file_name: str
    layer: int
    tree_id: int
    main_version: int
    sub_version: int
    revision: str
    parameters: tuple[Parameter, ...] = ()
    source: Source | None = field(default=None, compare=False, repr=False)

    @property
    def identity(self) -> TreeIdentity:
        return TreeIdentity(self.layer, self.tree_id, self.main_version, self.sub_version)

    @property
    def drive_type(self) -> DriveType:
        """The drive series this layer's tree is for (from @TreeFileName; drive_types.py)."""
        return drive_type_of_tree_file(self.tree_file_name)

    @property
    def identity_upids(self) -> tuple[int, int, int]:
        """Where the drive reports this layer's tree ID, main and sub version (seed 000 Table 4)."""
        return self.drive_type.identity_upids.get(self.layer, (0, 0, 0))

    @property
    def layer_name(self) -> str:
        return LAYERS[self.layer].name if self.layer in LAYERS else f"layer {self.layer}"

    def get(self, upid: int) -> Parameter | None:
        return next((p for p in self.parameters if p.upid == upid), None)

    def string(self, string_upid: int) -> str | None:
        """The string parameter at `string_upid`, from its stringlets present here (E1100: UPID + 1, + 2, ...;
        B1100: UPID + 0, + 1, ...)."""
        values = []
        k = 1
        while (p := self.get(self.drive_type.stringlet_upid(string_upid, k))) is not None:
            values.append(p.value)
            k += 1
        return codec.decode_stringlets(values) if values else None

    def strings(self) -> tuple[StringParameter, ...]:
        """The string parameters among the rows. A PVL file has no type column, so a run of rows is
        taken as the stringlets of one string when their captions read `NAME_1`, `NAME_2`, ... at UPIDs
        S+1, S+2, ... (B1100: S, S+1, ...) and each row's scaled value is its stringlet's characters (as LinMot-Talk writes
        them: `03F3,78412058,OS\\User Comment_1,X Ax`)."""
        found: list[StringParameter] = []
        rows = self.parameters
        i = 0
        while i < len(rows):
            m = _STRINGLET_CAPTION.fullmatch(rows[i].caption)
            if not m or m.group(2) != "1" or not _is_stringlet(rows[i]):
                i += 1
                continue
            name, base = m.group(1), self.drive_type.string_upid_of_first(rows[i].upid)
            first = rows[i].upid
            run = [rows[i]]
            j = i + 1
            while j < len(rows):
                mj = _STRINGLET_CAPTION.fullmatch(rows[j].caption)
                k = len(run) + 1
                if not (mj and mj.group(1) == name and mj.group(2) == str(k)
                        and rows[j].upid == first + k - 1 and _is_stringlet(rows[j])):
                    break
                run.append(rows[j])
                j += 1
            found.append(StringParameter(base, name, codec.decode_stringlets(p.value for p in run), tuple(run)))
            i = j
        return tuple(found)


def _is_stringlet(p: Parameter) -> bool:
    return codec.stringlet_text(p.value) == p.scaled_value


@dataclass(frozen=True)
class Curve:
    """A curve object: the 70-byte info block as sent to the drive, and the setpoints (signed 32-bit)."""

    info_block: bytes
    setpoints: tuple[int, ...]
    source: Source | None = field(default=None, compare=False, repr=False)

    @classmethod
    def make(cls, curve_id: int, name: str, setpoints, x_length: int, *,
             object_type: int = codec.OBJECT_TYPE_POSITION_TIME, wizard_type: int = 0,
             wizard_params: tuple[int, ...] = (0,) * 7) -> Curve:
        """A curve with a consistent info block (the unit IDs follow the object type)."""
        points = tuple(int(v) for v in setpoints)
        x_uuid, y_uuid = codec.SUPPORTED_OBJECT_TYPES.get(object_type, (codec.UUID_TIME, codec.UUID_POSITION))
        info = CurveInfo(curve_id=curve_id, name=name, setpoints=len(points), x_length=x_length,
                         object_type=object_type, x_dim_uuid=x_uuid, y_dim_uuid=y_uuid,
                         wizard_type=wizard_type, wizard_params=tuple(wizard_params))
        return cls(info.to_bytes(), points)

    @property
    def info(self) -> CurveInfo:
        return CurveInfo.from_bytes(self.info_block)

    @property
    def curve_id(self) -> int:
        return self.info.curve_id

    @property
    def name(self) -> str:
        return self.info.name

    @property
    def info_words(self) -> tuple[int, ...]:
        return codec.bytes_to_words(self.info_block)

    @property
    def data_words(self) -> tuple[int, ...]:
        return tuple(codec.to_unsigned32(v) for v in self.setpoints)

    @property
    def data_block(self) -> bytes:
        return b"".join(codec.to_unsigned32(v).to_bytes(4, "little") for v in self.setpoints)


@dataclass(frozen=True)
class CommandTableEntry:
    """A command-table entry (project extension object `@StartObject,CommandTableEntry`)."""

    entry_id: int
    data: bytes                            # the 64-byte entry data block as sent to the drive
    source: Source | None = field(default=None, compare=False, repr=False)

    @classmethod
    def make(cls, entry_id: int, name: str, motion_header: int, parameters: bytes = b"",
             linked_entry: int = codec.CT_NOT_LINKED) -> CommandTableEntry:
        block = CtEntryBlock(name=name, motion_header=motion_header, parameters=parameters,
                             linked_entry=linked_entry)
        return cls(entry_id, block.to_bytes())

    @property
    def block(self) -> CtEntryBlock:
        return CtEntryBlock.from_bytes(self.data)

    @property
    def name(self) -> str:
        return self.block.name

    @property
    def data_words(self) -> tuple[int, ...]:
        return codec.bytes_to_words(self.data)


PvlObject = ParameterObject | Curve | CommandTableEntry


@dataclass(frozen=True)
class PvlFile:
    """A whole PVL file: its objects in file order."""

    objects: tuple[PvlObject, ...] = ()
    format_version: int = 1
    filename: str | None = field(default=None, compare=False)

    @property
    def drive_types(self) -> tuple[DriveType, ...]:
        """The drive series the Parameter objects are for, each once, in file order (validate.py refuses
        a file with more than one)."""
        out: list[DriveType] = []
        for o in self.parameter_objects:
            if o.drive_type not in out:
                out.append(o.drive_type)
        return tuple(out)

    @property
    def drive_type(self) -> DriveType:
        """The drive series the file is for: that of its Parameter objects (E1100 for a file without)."""
        types = self.drive_types
        return types[0] if types else E1100

    @property
    def parameter_objects(self) -> tuple[ParameterObject, ...]:
        return tuple(o for o in self.objects if isinstance(o, ParameterObject))

    @property
    def curves(self) -> tuple[Curve, ...]:
        return tuple(o for o in self.objects if isinstance(o, Curve))

    @property
    def command_table(self) -> tuple[CommandTableEntry, ...]:
        return tuple(o for o in self.objects if isinstance(o, CommandTableEntry))

    def layer(self, number: int) -> ParameterObject | None:
        return next((o for o in self.parameter_objects if o.layer == number), None)

    def curve(self, curve_id: int) -> Curve | None:
        return next((c for c in self.curves if c.curve_id == curve_id), None)

    def entry(self, entry_id: int) -> CommandTableEntry | None:
        return next((e for e in self.command_table if e.entry_id == entry_id), None)

    def __iter__(self) -> Iterator[PvlObject]:
        return iter(self.objects)
