"""Read PVL text into a `PvlFile`, strictly: every problem is reported as `file:line: message`.

The format is line-oriented (seeds, chapter 7), so the reader is a small state machine over lines
rather than a grammar: it keeps going after an error (skipping the bad row, or the rest of a broken
object) so that one run reports all problems. After the syntax, the header lines are checked against
the blocks they describe, then `validate.validate` checks the model.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field

from . import codec
from .errors import Diagnostic, PvlError
from .model import CommandTableEntry, Curve, Parameter, ParameterObject, PvlFile, Source
from .validate import validate

PARAMETER_COLUMNS = "@Col1:UPID,@Col2:Value,@Col3:Caption,@Col4:ScaledValue Unit"
VALUE_COLUMN = "@Col1:Value"

OBJECT_KINDS = ("Parameter", "Curve", "CommandTableEntry")
# header keys of each object kind: key -> "int" (decimal) or "text"
OBJECT_KEYS = {
    "Parameter": {"TreeFileName": "text", "TreeLayer": "int", "TreeID": "int", "MainVersion": "int",
                  "SubVersion": "int", "Revision": "text"},
    "Curve": {"CurveName": "text", "CurveID": "int", "InfoBlockByteSize": "int", "DataBlockByteSize": "int"},
    "CommandTableEntry": {"EntryID": "int", "EntryName": "text", "DataBlockByteSize": "int"},
}
MAX_DIAGNOSTICS = 500             # stop collecting after this many: the first ones tell the story

_BLOCK_KEYS = ("StartData", "EndData", "StartInfo", "EndInfo")
_DECIMAL = re.compile(r"[0-9]{1,9}", re.ASCII)
_HEX4 = re.compile(r"[0-9A-Fa-f]{4}", re.ASCII)
_HEX8 = re.compile(r"[0-9A-Fa-f]{8}", re.ASCII)
_WORD = re.compile(r"([0-9A-Fa-f]{8})[hH]", re.ASCII)


def load_pvl(path: str | os.PathLike) -> PvlFile:
    """Read and check a PVL file. Raises PvlError (file:line messages) or OSError."""
    with open(path, "rb") as f:
        raw = f.read()
    return parse_pvl(raw, filename=os.fspath(path))


def parse_pvl(text: str | bytes, filename: str = "<string>") -> PvlFile:
    """Parse and check PVL text (bytes are decoded as Latin-1). Raises PvlError."""
    if isinstance(text, (bytes, bytearray)):
        text = _decode(bytes(text), filename)
    reader = _Reader(text)
    objects = reader.read_file()
    pvl = PvlFile(tuple(objects), filename=filename)
    # the model checks see only the objects that were read without error (a broken curve or entry is
    # left out), so they add no cascade of follow-on messages
    diagnostics = sorted(reader.diagnostics + validate(pvl), key=lambda d: d.line or 0)
    if diagnostics:
        raise PvlError(filename, diagnostics[:MAX_DIAGNOSTICS])
    return pvl


def _decode(raw: bytes, filename: str) -> str:
    """Latin-1, except for a file that starts with a UTF-8 byte-order mark (an editor saved it as UTF-8)."""
    if not raw.startswith(b"\xef\xbb\xbf"):
        return raw.decode(codec.TEXT_ENCODING)
    try:
        return raw[3:].decode("utf-8")
    except UnicodeDecodeError as err:
        line = raw[3:3 + err.start].count(b"\n") + 1
        raise PvlError(filename, [Diagnostic(line, "the file starts with a UTF-8 byte-order mark "
                                                   "but this line is not UTF-8")]) from None


class _Abort(Exception):
    """Too many problems: stop reading."""


@dataclass
class _Header:
    values: dict[str, object] = field(default_factory=dict)
    lines: dict[str, int] = field(default_factory=dict)


class _Reader:
    def __init__(self, text: str):
        # only LF (and CR LF) end a line: str.splitlines would also split at 85h, which Latin-1 text
        # may hold inside a caption (cp1252's ellipsis)
        self.lines = [ln.rstrip(" \t\r") for ln in text.split("\n")]
        if self.lines and self.lines[-1] == "":
            self.lines.pop()
        self.i = 0                      # index of the next line
        self.diagnostics: list[Diagnostic] = []

    # -- line access --------------------------------------------------------------------------------
    def error(self, line: int, message: str) -> None:
        self.diagnostics.append(Diagnostic(line, message))
        if len(self.diagnostics) >= MAX_DIAGNOSTICS:
            raise _Abort

    def next_nonblank(self) -> tuple[int, str] | None:
        """Advance past blank lines; return (line number, text) of the next line without consuming it."""
        while self.i < len(self.lines) and self.lines[self.i] == "":
            self.i += 1
        return (self.i + 1, self.lines[self.i]) if self.i < len(self.lines) else None

    def eof_line(self) -> int:
        return max(len(self.lines), 1)

    # -- file ---------------------------------------------------------------------------------------
    def read_file(self) -> list:
        objects: list = []
        try:
            self.read_header()
            while (nxt := self.next_nonblank()) is not None:
                lineno, text = nxt
                self.i += 1
                key, value = _split_key(text)
                if key == "StartObject":
                    obj = self.read_object(lineno, value)
                    if obj is not None:
                        objects.append(obj)
                else:
                    # one message for the whole stray stretch, not one per line
                    self.error(lineno, f"expected @StartObject, got {_show(text)}")
                    while self.i < len(self.lines) and _split_key(self.lines[self.i])[0] != "StartObject":
                        self.i += 1
        except _Abort:
            pass
        return objects

    def read_header(self) -> None:
        nxt = self.next_nonblank()
        key, value = _split_key(nxt[1]) if nxt else (None, None)
        if key != "FileType":
            # not a PVL file at all: reporting each of its lines would bury the one useful message
            self.error(nxt[0] if nxt else 1, "not a PVL file: it must start with @FileType,PVL"
                       + (f", got {_show(nxt[1])}" if nxt else " (the file is empty)"))
            raise _Abort
        self.i += 1
        if value != "PVL":
            self.error(nxt[0], f"not a PVL file: @FileType is {value!r}, expected 'PVL'")
        nxt = self.next_nonblank()
        key, value = _split_key(nxt[1]) if nxt else (None, None)
        if key != "FormatVersion":
            self.error(nxt[0] if nxt else self.eof_line(), "missing @FormatVersion,1 after @FileType,PVL")
            return
        self.i += 1
        if value != "1":
            self.error(nxt[0], f"unsupported format version: @FormatVersion is {value!r}, expected '1'")

    # -- objects ------------------------------------------------------------------------------------
    def read_object(self, start: int, kind: str | None):
        if kind is None:
            self.error(start, f"@StartObject needs a kind: @StartObject,{'|'.join(OBJECT_KINDS)}")
            self.skip_object()
            return None
        if kind not in OBJECT_KINDS:
            self.error(start, f"unknown object kind {kind!r} (expected one of {', '.join(OBJECT_KINDS)})")
            self.skip_object()
            return None
        n_errors = len(self.diagnostics)
        header = self.read_keys(start, kind)
        if header is None:
            return None
        obj = None
        if kind == "Parameter":
            rows = self.read_block(start, "StartData", "EndData", PARAMETER_COLUMNS, self.parse_parameter_row)
            if rows is None or not self.finish_object(start):
                return None
            obj = self.build_parameter_object(start, header, rows)
        elif kind == "Curve":
            info = self.read_block(start, "StartInfo", "EndInfo", VALUE_COLUMN, self.parse_word)
            data = self.read_block(start, "StartData", "EndData", VALUE_COLUMN, self.parse_word) \
                if info is not None else None
            if data is None or not self.finish_object(start):
                return None
            if len(self.diagnostics) == n_errors:
                obj = self.build_curve(start, header, info, data)
        else:
            data = self.read_block(start, "StartData", "EndData", VALUE_COLUMN, self.parse_word)
            if data is None or not self.finish_object(start):
                return None
            if len(self.diagnostics) == n_errors:
                obj = self.build_entry(start, header, data)
        return obj

    def read_keys(self, start: int, kind: str) -> _Header | None:
        """The @Key,value lines up to the first block; None if the object ended before a block."""
        allowed = OBJECT_KEYS[kind]
        header = _Header()
        first_block = "StartInfo" if kind == "Curve" else "StartData"
        while (nxt := self.next_nonblank()) is not None:
            lineno, text = nxt
            key, value = _split_key(text)
            if key == first_block:
                missing = [k for k in allowed if k not in header.lines]
                if missing:
                    self.error(start, f"{kind} object: missing " + ", ".join(f"@{k}" for k in missing))
                    self.skip_object()
                    return None
                return header
            if key is None or key in ("EndObject", "StartObject") or key in _BLOCK_KEYS \
                    or key.startswith("Col1:"):
                # a row, a column line or another marker: the block start is missing or misspelt
                self.error(lineno, f"{kind} object: expected @{first_block} before {_show(text)}")
                self.skip_object()
                return None
            self.i += 1
            if key not in allowed:
                self.error(lineno, f"unknown key @{key} in a {kind} object "
                                   f"(expected {', '.join('@' + k for k in allowed)})")
            elif key in header.lines:
                self.error(lineno, f"@{key} given twice (first at line {header.lines[key]})")
            elif value is None:
                self.error(lineno, f"@{key} has no value (expected @{key},<value>)")
            elif allowed[key] == "int":
                if not _DECIMAL.fullmatch(value):
                    self.error(lineno, f"@{key}: {value!r} is not a decimal number")
                else:
                    header.values[key], header.lines[key] = int(value), lineno
            else:
                header.values[key], header.lines[key] = value, lineno
        self.error(self.eof_line(), f"{kind} object started at line {start}: file ends before @{first_block}")
        return None

    def read_block(self, start: int, open_key: str, close_key: str, columns: str, parse_row):
        """`@open_key`, the column line, rows until `@close_key`. Returns [(line, parsed row or None)]
        or None when the object ends without `@close_key` (reported)."""
        nxt = self.next_nonblank()
        if nxt is None or _split_key(nxt[1]) != (open_key, None):
            where = nxt[0] if nxt else self.eof_line()
            self.error(where, f"expected @{open_key}" + (f", got {_show(nxt[1])}" if nxt else ""))
            self.skip_object()
            return None
        self.i += 1
        open_line = nxt[0]
        nxt = self.next_nonblank()
        if nxt is None or nxt[1] != columns:
            where = nxt[0] if nxt else self.eof_line()
            self.error(where, f"expected the column line {columns!r} after @{open_key}"
                              + (f", got {_show(nxt[1])}" if nxt else ""))
            if nxt is None or nxt[1].startswith("@"):
                self.skip_object()
                return None
        else:
            self.i += 1
        rows = []
        lines, n = self.lines, len(self.lines)
        while True:
            # the rows, a line each (a curve's setpoints: up to 16,384 of them), read in this loop's own locals
            i = self.i
            while i < n:
                text = lines[i]
                if not text:
                    i += 1
                elif text[0] != "@":
                    i += 1
                    rows.append((i, parse_row(i, text)))        # i: the line number of lines[i - 1]
                else:
                    break
            self.i = i
            nxt = self.next_nonblank()
            if nxt is None:
                break
            lineno, text = nxt
            key, value = _split_key(text)
            if key == close_key and value is None:
                self.i += 1
                return rows
            if key in ("EndObject", "StartObject"):
                self.error(lineno, f"missing @{close_key} (the block opened at line {open_line})")
                if key == "EndObject":
                    self.i += 1
                return None
            if key in _BLOCK_KEYS:
                # another block's marker: this block lacks its end; carry on with the next block
                self.error(lineno, f"missing @{close_key} (the block opened at line {open_line}) "
                                   f"before {_show(text)}")
                if key.startswith("End"):
                    self.i += 1
                return rows
            self.i += 1                 # an @ line of no block (the rows were read above)
            self.error(lineno, f"unexpected {_show(text)} inside the block opened at line {open_line}")
        self.error(self.eof_line(), f"missing @{close_key} (the block opened at line {open_line}), "
                                    f"and @EndObject of the object started at line {start}")
        return None

    def finish_object(self, start: int) -> bool:
        """Consume @EndObject. False (reported) when the object is not closed properly."""
        nxt = self.next_nonblank()
        if nxt is None:
            self.error(self.eof_line(), f"missing @EndObject (the object started at line {start})")
            return False
        lineno, text = nxt
        key, value = _split_key(text)
        if key == "EndObject" and value is None:
            self.i += 1
            return True
        if key == "StartObject":
            self.error(lineno, f"missing @EndObject (the object started at line {start})")
            return False
        self.error(lineno, f"expected @EndObject, got {_show(text)}")
        self.skip_object()
        return False

    def skip_object(self) -> None:
        """Skip to just after the next @EndObject, or to the next @StartObject."""
        while self.i < len(self.lines):
            key, _ = _split_key(self.lines[self.i])
            if key == "StartObject":
                return
            self.i += 1
            if key == "EndObject":
                return

    # -- rows ---------------------------------------------------------------------------------------
    def parse_parameter_row(self, lineno: int, text: str) -> Parameter | None:
        # the scaled value is the last column and keeps any further commas (docs/pvl.md)
        cols = text.split(",", 3)
        if len(cols) < 4:
            self.error(lineno, f"a parameter row has 4 columns (UPID,Value,Caption,ScaledValue Unit), "
                               f"got {len(cols)}: {_show(text)}")
            return None
        upid, value, caption, scaled = cols
        ok = True
        if not _HEX4.fullmatch(upid):
            self.error(lineno, f"UPID {upid!r} is not 4 hex digits")
            ok = False
        if not _HEX8.fullmatch(value):
            self.error(lineno, f"value {value!r} is not 8 hex digits")
            ok = False
        return Parameter(int(upid, 16), int(value, 16), caption, scaled, line=lineno) if ok else None

    def parse_word(self, lineno: int, text: str) -> int | None:
        m = _WORD.fullmatch(text)
        if not m:
            self.error(lineno, f"{text!r} is not a 32-bit word (8 hex digits and 'h', e.g. 00030046h)")
            return None
        return int(m.group(1), 16)

    # -- building objects (and the header checks that need the text) --------------------------------
    def build_parameter_object(self, start, header: _Header, rows) -> ParameterObject:
        v = header.values
        return ParameterObject(
            tree_file_name=v["TreeFileName"], layer=v["TreeLayer"], tree_id=v["TreeID"],
            main_version=v["MainVersion"], sub_version=v["SubVersion"], revision=v["Revision"],
            parameters=tuple(p for _, p in rows if p is not None),
            source=Source(start, dict(header.lines)))

    def build_curve(self, start, header: _Header, info_rows, data_rows) -> Curve | None:
        v, at = header.values, header.lines
        info_words = [w for _, w in info_rows]
        data_words = [w for _, w in data_rows]
        end_info = info_rows[-1][0] if info_rows else start
        ok = True
        if v["InfoBlockByteSize"] != codec.INFO_BLOCK_SIZE:
            self.error(at["InfoBlockByteSize"], f"@InfoBlockByteSize is {v['InfoBlockByteSize']}, "
                                                f"a curve info block has {codec.INFO_BLOCK_SIZE} bytes")
            ok = False
        elif len(info_words) != codec.words_for(codec.INFO_BLOCK_SIZE):
            self.error(end_info, f"the info block lists {len(info_words)} words, @InfoBlockByteSize "
                                 f"{codec.INFO_BLOCK_SIZE} needs {codec.words_for(codec.INFO_BLOCK_SIZE)}")
            ok = False
        size = v["DataBlockByteSize"]
        if size != 4 * len(data_words):
            self.error(at["DataBlockByteSize"], f"@DataBlockByteSize is {size}, the data block lists "
                                                f"{len(data_words)} words ({4 * len(data_words)} bytes)")
            ok = False
        if not codec.CURVE_ID_MIN <= v["CurveID"] <= codec.CURVE_ID_MAX:
            self.error(at["CurveID"], f"curve ID {v['CurveID']} is outside "
                                      f"{codec.CURVE_ID_MIN}..{codec.CURVE_ID_MAX}")
            ok = False
        if not ok:
            return None
        block, pad = codec.words_to_bytes(info_words, codec.INFO_BLOCK_SIZE)
        if any(pad):
            self.error(info_rows[-1][0], f"the {len(pad)} pad bytes after the {codec.INFO_BLOCK_SIZE}-byte "
                                         f"info block must be 00h, got {pad.hex().upper()}")
        info = codec.CurveInfo.from_bytes(block)
        if info.curve_id != v["CurveID"]:
            self.error(info_rows[7][0], f"the info block's curve ID is {info.curve_id}, "
                                        f"@CurveID (line {at['CurveID']}) is {v['CurveID']}")
        if info.name != v["CurveName"]:
            self.error(info_rows[2][0], f"the info block's name is {info.name!r}, "
                                        f"@CurveName (line {at['CurveName']}) is {v['CurveName']!r}")
        return Curve(block, tuple(codec.to_signed32(w) for w in data_words),
                     source=Source(start, dict(at), tuple(ln for ln, _ in info_rows),
                                   tuple(ln for ln, _ in data_rows)))

    def build_entry(self, start, header: _Header, data_rows) -> CommandTableEntry | None:
        v, at = header.values, header.lines
        words = [w for _, w in data_rows]
        if v["DataBlockByteSize"] != codec.CT_BLOCK_SIZE:
            self.error(at["DataBlockByteSize"], f"@DataBlockByteSize is {v['DataBlockByteSize']}, "
                                                f"a command-table entry has {codec.CT_BLOCK_SIZE} bytes")
            return None
        if len(words) != codec.CT_BLOCK_SIZE // 4:
            where = data_rows[-1][0] if data_rows else at["DataBlockByteSize"]
            self.error(where, f"the data block lists {len(words)} words, @DataBlockByteSize "
                              f"{codec.CT_BLOCK_SIZE} needs {codec.CT_BLOCK_SIZE // 4}")
            return None
        block, _ = codec.words_to_bytes(words, codec.CT_BLOCK_SIZE)
        entry = CommandTableEntry(v["EntryID"], block,
                                  source=Source(start, dict(at), (), tuple(ln for ln, _ in data_rows)))
        if entry.name != v["EntryName"]:
            self.error(data_rows[9][0], f"the entry's name is {entry.name!r}, "
                                        f"@EntryName (line {at['EntryName']}) is {v['EntryName']!r}")
        return entry


def _split_key(text: str) -> tuple[str | None, str | None]:
    """'@Key,value' -> ('Key', 'value'); '@Key' -> ('Key', None); other lines -> (None, None)."""
    if not text.startswith("@"):
        return None, None
    key, comma, value = text[1:].partition(",")
    return key, (value if comma else None)


def _show(text: str) -> str:
    return repr(text if len(text) <= 60 else text[:57] + "...")
