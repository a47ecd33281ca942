"""Every file generated from the protocol catalogue, and the check that they are current.

    python -m linmot_st.protocol --write     # rewrite them all
    python -m linmot_st.protocol --check     # exit 1, naming each file that differs

Whole files: st_lib/types/errors.st (the ErrorIDs), st_lib/motion/drive_errors.st (the drive's error texts),
st_lib/motion/codec_gen.st (the motion command encoder F_LmMotionEncode). Tables between markers: the ErrorIDs
in docs/st-library.md, the drive errors in docs/motion.md.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path

from .commands import COMMANDS, CommandDef
from .errors import DRIVE_ERRORS, ERRORS

REPO = Path(__file__).resolve().parents[3]
COMMAND = "python -m linmot_st.protocol --write"


@dataclass(frozen=True)
class Generated:
    """A generated file (begin None) or the table between two marker lines of a hand-written one."""
    path: str                           # relative to the repository
    render: Callable[[], str]
    begin: str | None = None
    end: str | None = None

    def current(self, text: str) -> str:
        """What the file should hold, given what it holds now."""
        if self.begin is None:
            return self.render()
        begin, end = self.begin, self.end
        assert end is not None, f"{self.path}: a table between markers needs both"
        pattern = re.compile(re.escape(begin) + ".*?" + re.escape(end), re.S)
        if not pattern.search(text):
            raise ValueError(f"{self.path}: markers {begin!r} .. {end!r} not found")
        return pattern.sub(lambda _m: "\n".join([begin, self.render(), end]), text)


# ---------------------------------------------------------------- the ErrorIDs and the drive's errors

def render_st() -> str:
    width = max(len(e.name) for e in ERRORS)
    lines = [
        "(* ErrorID numbers of the library. GENERATED from harness/linmot_st/protocol/errors.py by",
        "   `python -m linmot_st.protocol --write`: edit the Python table, not this file.",
        "   Every FB holds one instance `E : T_LmErrorIds` and reports `E.<Name>`; the members' initial",
        "   values are the numbers. Groups: 01xx invalid input, 02xx channel, 03xx transfer,",
        "   04xx E1100 result code rr (16#0400 + rr), 05xx firmware compatibility, 06xx commissioning,",
        "   07xx motion. *)",
        "TYPE",
        "  T_LmErrorIds : STRUCT",
    ]
    for e in ERRORS:
        text = e.text.replace("(*", "( *").replace("*)", "* )")
        lines.append(f"    {e.name.ljust(width)} : WORD := 16#{e.value:04X};  (* {text} *)")
    lines += ["  END_STRUCT;", "END_TYPE", ""]
    return "\n".join(lines)


def render_drive_st() -> str:
    width = max(len(d.name) for d in DRIVE_ERRORS)
    lines = [
        "(* The drive's error codes (the logged error code of the MC software, [MC] chapter 10; the CANopen",
        "   interface's C1h..DCh). GENERATED from harness/linmot_st/emulator/data/e1100_error_texts.csv by",
        "   `python -m linmot_st.protocol --write`: edit the table, not this file.",
        "   Declare `DE : T_LmDriveErrors;` and compare: IF Err.AxisErrorID = DE.PosLagAlways THEN ...",
        "   F_LmDriveErrorText gives the drive's text, F_LmDriveErrorFatal whether it can be acknowledged. *)",
        "TYPE",
        "  T_LmDriveErrors : STRUCT",
    ]
    for d in DRIVE_ERRORS:
        lines.append(f"    {d.name.ljust(width)} : WORD := 16#{d.code:04X};  (* {d.text}{' (fatal)' if d.fatal else ''} *)")
    lines += ["  END_STRUCT;", "END_TYPE", "",
              "FUNCTION F_LmDriveErrorText : STRING",
              "  (* the drive's text for a logged error code; '' for a code the table does not know *)",
              "  VAR_INPUT", "    Code : WORD;", "  END_VAR",
              "  CASE WORD_TO_UINT(Code) OF"]
    for d in DRIVE_ERRORS:
        lines.append(f"    {d.code}: F_LmDriveErrorText := '{d.text}';")
    lines += ["  ELSE", "    F_LmDriveErrorText := '';", "  END_CASE;", "END_FUNCTION", "",
              "FUNCTION F_LmDriveErrorFatal : BOOL",
              "  (* TRUE for a code the table marks fatal (no acknowledge possible) *)",
              "  VAR_INPUT", "    Code : WORD;", "  END_VAR",
              "  CASE WORD_TO_UINT(Code) OF",
              "    " + ", ".join(str(d.code) for d in DRIVE_ERRORS if d.fatal) + ":",
              "      F_LmDriveErrorFatal := TRUE;",
              "  ELSE", "    F_LmDriveErrorFatal := FALSE;", "  END_CASE;", "END_FUNCTION", ""]
    return "\n".join(lines)


def render_drive_doc_table() -> str:
    rows = ["| code | T_LmDriveErrors member | the drive's text | fatal |", "|---|---|---|---|"]
    for d in DRIVE_ERRORS:
        rows.append(f"| {d.code:04X}h | `{d.name}` | {d.text} | {'yes' if d.fatal else ''} |")
    return "\n".join(rows)


def render_doc_table() -> str:
    rows = ["| ErrorID | Name | Meaning |", "|---|---|---|"]
    for e in ERRORS:
        rows.append(f"| 16#{e.value:04X} | `{e.name}` | {e.text} |")
    return "\n".join(rows)


def parse_st(text: str) -> dict[str, int]:
    """Members and values of T_LmErrorIds as written in an ST file (used by the divergence check)."""
    out: dict[str, int] = {}
    for m in re.finditer(r"^\s*(\w+)\s*:\s*WORD\s*:=\s*16#([0-9A-Fa-f]+)\s*;", text, re.M):
        out[m.group(1)] = int(m.group(2), 16)
    return out


# ---------------------------------------------------------------- the motion command encoder

_PUT = {2: ("F_LmImgPutU16", "DINT_TO_UINT"), 4: ("F_LmImgPutU32", "DINT_TO_UDINT")}
_PARAMS = "ABCDE"


def _layout(c: CommandDef) -> tuple[int, ...]:
    """The byte widths of the fields, in order: commands with the same widths share one CASE branch."""
    return tuple(2 if f.type in ("INT", "UINT") else 4 for f in c.fields)


def _ids(cids: list[int]) -> str:
    return ", ".join(f"{cid:03X}h" for cid in cids)


def _wrapped(head: str, parts: list[str], width: int = 110) -> list[str]:
    """A comment table row: the head, then the parts comma-separated, broken between parts."""
    lines, line = [], " " * 7 + head
    for k, part in enumerate(parts):
        part += "," if k < len(parts) - 1 else ""
        if len(line) + 1 + len(part) > width:
            lines.append(line)
            line = " " * 12 + part
        else:
            line += " " + part
    return lines + [line]


def render_codec(commands: Mapping[int, CommandDef] | None = None) -> str:
    """st_lib/motion/codec_gen.st: F_LmMotionEncode, one CASE branch per parameter layout (MatIEC subset: a
    WHILE loop clears the image, no FOR)."""
    commands = COMMANDS if commands is None else commands
    rows = sorted(commands.values(), key=lambda c: c.cid)
    table = []
    for c in rows:
        params = [f"{_PARAMS[i]} {f.name} {f.type}{' [' + f.unit + ']' if f.unit else ''}"
                  for i, f in enumerate(c.fields)] or ["-"]
        table += _wrapped(f"{c.cid:03X}h {c.name}:", params)
    branches: dict[tuple[int, ...], list[int]] = {}
    for c in rows:
        branches.setdefault(_layout(c), []).append(c.cid)
    lines = [
        "(* The motion command encoder. GENERATED from the catalogue harness/linmot_st/protocol/commands/ by",
        f"   `{COMMAND}`: edit the catalogue, not this file.",
        "   Helpers and unit conversions: codec.st (hand-written). *)",
        "",
        "FUNCTION F_LmMotionEncode : USINT",
        "  (* the image of command Cid (the header's upper 12 bits, e.g. 16#090 for 090xh) with count Count:",
        "     header in bytes 0..1, parameters from byte 2 in the command's layout; returns the number of parameter",
        "     bytes, 255 for a command this library does not encode. A..E are the parameters in the order of",
        "     [MC] 4.3, each converted to its field's width (signed fields two's complement):",
        *[line.replace("(*", "( *").replace("*)", "* )") for line in table],
        "  *)",
        "  VAR_INPUT", "    Cid : UINT;", "    Count : USINT;", "    A : DINT;", "    B : DINT;", "    C : DINT;",
        "    D : DINT;", "    E : DINT;", "  END_VAR",
        "  VAR_IN_OUT", "    Img : T_LmMotionImage;", "  END_VAR",
        "  VAR", "    N : USINT;", "    Ok : BOOL;", "    I : INT;", "  END_VAR",
        "  I := 0;", "  WHILE I <= 19 DO", "    Img[I] := 0;", "    I := I + 1;", "  END_WHILE;",
        "  Ok := F_LmImgPutU16(Img, 0, Cid * 16 + USINT_TO_UINT(Count MOD 16));",
        "  N := 255;",
        "  CASE UINT_TO_INT(Cid) OF",
    ]
    for layout, cids in sorted(branches.items(), key=lambda kv: kv[1][0]):
        lines.append(f"    {', '.join(str(cid) for cid in cids)}:  (* {_ids(cids)} *)")
        offset = 2
        for i, width in enumerate(layout):
            put, conv = _PUT[width]
            lines.append(f"      Ok := {put}(Img, {offset}, {conv}({_PARAMS[i]}));")
            offset += width
        lines.append(f"      N := {offset - 2};")
    lines += ["  END_CASE;", "  F_LmMotionEncode := N;", "END_FUNCTION", ""]
    return "\n".join(lines)


# ---------------------------------------------------------------- the list

def _markers(name: str) -> tuple[str, str]:
    return f"<!-- {name}:begin (generated by {COMMAND}) -->", f"<!-- {name}:end -->"


ARTEFACTS: tuple[Generated, ...] = (
    Generated("st_lib/types/errors.st", render_st),
    Generated("st_lib/motion/drive_errors.st", render_drive_st),
    Generated("st_lib/motion/codec_gen.st", render_codec),
    Generated("docs/st-library.md", render_doc_table, *_markers("errors")),
    Generated("docs/motion.md", render_drive_doc_table, *_markers("drive-errors")),
)


def check(root: Path = REPO) -> list[str]:
    """One line per generated file that differs from what the catalogue generates (empty: all current)."""
    problems = []
    for a in ARTEFACTS:
        path = root / a.path
        if not path.exists():
            problems.append(f"{a.path}: missing (run {COMMAND})")
            continue
        text = path.read_text()
        try:
            if a.current(text) != text:
                problems.append(f"{a.path}: differs from the catalogue (run {COMMAND})")
        except ValueError as exc:
            problems.append(str(exc))
    return problems


def write(root: Path = REPO) -> list[str]:
    """Rewrite every generated file; the ones that changed."""
    changed = []
    for a in ARTEFACTS:
        path = root / a.path
        old = path.read_text() if path.exists() else ""
        new = a.current(old)
        if new != old:
            path.write_text(new)
            changed.append(a.path)
    return changed
