"""The language conformance suite: data-driven ST cases, run on every available backend.

Each case is one file under cases/, an ST text whose first comment says what must happen:

    (*
      title: FOR i := 5 TO 5 runs its body once
      expect 1: N = 1; I = 6                 after 1 scan (counted from the start), these hold
      matiec-defect: spec/matiec.md 7.1 ...  MatIEC HEAD gets this case wrong, for this reason;
      matiec-expect 1: N = 0; I = 5          ... and gives these values instead (left out of the
                                             differential comparison)
      matiec-expect[head] 1: N = 0           ... only under an iec2c with these FOR semantics
                                             (toolchain/matiec/for_semantics.py: head, openplc, fixed, other)
      matiec-fault[openplc] 1: kind 5        ... under such an iec2c, scan 1 ends in this PLC fault (5:
                                             the scan watchdog, for a loop that never ends); run alone
      interval: T#10ms                       the task interval (default T#10ms)
      reject 7:12: type mismatch             the builtin compiler rejects it, first diagnostic at line 7,
                                             column 12 (`reject 7:` checks the line only), message containing...
      matiec-accepts: relaxed arrays (-l)    ...while MatIEC (with the build driver's flags) accepts it
      fault 2: kind 1 line 9                 scan 2 raises a PLC fault of this kind at this line
    *)

Values are Python literals, or duration literals (T#1s, read as ns). Paths are relative to the
case's program instance unless the case has its own CONFIGURATION (then they are suffixes of root
paths). A case without CONFIGURATION holds one PROGRAM named like the file; the runner builds all
such cases of one interval into one PLC (one gcc run per backend) with a generated CONFIGURATION,
steps it to each checkpoint, and records each program instance for the differential comparison.
Cases with their own CONFIGURATION, and fault cases, are built one by one.
"""

from __future__ import annotations

import ast as pyast
import re
from dataclasses import dataclass, field
from pathlib import Path

CASES_DIR = Path(__file__).parent / "cases"
DEFAULT_INTERVAL = "T#10ms"

_HEADER = re.compile(r"\A\s*\(\*(.*?)\*\)", re.S)
_LINE = re.compile(r"^\s*([a-z-]+)(?:\[([a-z, ]+)\])?(?:\s+(\d+))?\s*:\s*(.*?)\s*$")
ALL_VARIANTS = "*"
FOR_VARIANTS = {"head", "openplc", "fixed", "other"}     # ForSemantics.name


@dataclass
class Case:
    name: str                       # file stem
    path: Path
    text: str
    title: str = ""
    expects: dict[int, dict[str, object]] = field(default_factory=dict)
    # expectations on the matiec backend: for every iec2c ("*"), or for one FOR variant
    matiec_by_variant: dict[str, dict[int, dict[str, object]]] = field(default_factory=dict)
    matiec_faults: dict[str, tuple[int, int]] = field(default_factory=dict)     # variant -> (scan, kind)
    matiec_defect: str = ""
    interval: str = DEFAULT_INTERVAL
    reject: str | None = None
    reject_line: int | None = None
    reject_col: int | None = None
    matiec_accepts: str = ""
    fault: tuple[int, int, int | None] | None = None    # (scan, kind, line)
    own_config: bool = False

    @property
    def program(self) -> str:
        return self.name.upper()

    @property
    def instance(self) -> str:
        return f"{self.name.upper()}_I"

    @property
    def kind(self) -> str:
        if self.reject is not None:
            return "reject"
        if self.fault is not None:
            return "fault"
        return "run"

    def path_of(self, rel: str) -> str:
        if self.own_config or rel.startswith("%"):
            return rel
        return f"CONF.RES.{self.instance}.{rel}"

    @property
    def matiec_expects(self) -> dict[int, dict[str, object]]:
        """Every value a matiec expectation names, under any variant (what a run must record)."""
        out: dict[int, dict[str, object]] = {}
        for by_scan in self.matiec_by_variant.values():
            for scans, values in by_scan.items():
                out.setdefault(scans, {}).update(values)
        return out

    def _matiec_for(self, variant: str | None) -> list[dict[int, dict[str, object]]]:
        return [self.matiec_by_variant[v] for v in (ALL_VARIANTS, variant) if v in self.matiec_by_variant]

    def expected(self, backend: str, variant: str | None = None) -> dict[int, dict[str, object]]:
        if backend != "matiec":
            return self.expects
        out = {k: dict(v) for k, v in self.expects.items()}
        for by_scan in self._matiec_for(variant):
            for scans, values in by_scan.items():
                out.setdefault(scans, {}).update(values)
        return out

    def matiec_fault(self, variant: str | None) -> tuple[int, int] | None:
        return self.matiec_faults.get(variant) or self.matiec_faults.get(ALL_VARIANTS)

    def excluded_from_diff(self, variant: str | None = None) -> set[str]:
        return {p.upper() for by_scan in self._matiec_for(variant) for values in by_scan.values() for p in values}


def parse_value(text: str):
    text = text.strip()
    if re.fullmatch(r"(?i)(T|TIME)#[-0-9a-z_.]+", text):
        from linmot_st.toolchain.builtin.ast import Pos
        from linmot_st.toolchain.builtin.parser import _duration_ns
        return _duration_ns(text, Pos("<expect>", 0, 0))
    return pyast.literal_eval(text)


def _split_assignments(text: str) -> list[str]:
    parts, depth, quote, cur = [], 0, None, []
    for ch in text:
        if quote:
            cur.append(ch)
            if ch == quote:
                quote = None
            continue
        if ch in "'\"":
            quote = ch
        elif ch in "[({":
            depth += 1
        elif ch in "])}":
            depth -= 1
        elif ch == ";" and depth == 0:
            parts.append("".join(cur))
            cur = []
            continue
        cur.append(ch)
    if "".join(cur).strip():
        parts.append("".join(cur))
    return [p.strip() for p in parts if p.strip()]


def _assignments(text: str, where: str) -> dict[str, object]:
    out = {}
    for part in _split_assignments(text):
        if "=" not in part:
            raise ValueError(f"{where}: expected PATH = VALUE, got {part!r}")
        path, value = part.split("=", 1)
        out[path.strip()] = parse_value(value)
    return out


def load_case(path: Path) -> Case:
    text = path.read_text()
    case = Case(path.stem, path, text)
    m = _HEADER.match(text)
    if not m:
        raise ValueError(f"{path}: a case starts with a (* ... *) header")
    for raw in m.group(1).splitlines():
        if not raw.strip():
            continue
        lm = _LINE.match(raw)
        if not lm:
            raise ValueError(f"{path}: cannot read header line {raw!r}")
        key, tags, num, rest = lm.group(1), lm.group(2), lm.group(3), lm.group(4)
        where = f"{path.name}: {key}"
        variants = [t.strip() for t in tags.split(",")] if tags else [ALL_VARIANTS]
        if tags and (key not in ("matiec-expect", "matiec-fault") or not set(variants) <= FOR_VARIANTS):
            raise ValueError(f"{where}: [variant] tags are {sorted(FOR_VARIANTS)}, on matiec-expect and "
                             f"matiec-fault only")
        if key == "title":
            case.title = rest
        elif key == "expect":
            case.expects.setdefault(int(num), {}).update(_assignments(rest, where))
        elif key == "matiec-expect":
            for v in variants:
                case.matiec_by_variant.setdefault(v, {}).setdefault(int(num), {}).update(_assignments(rest, where))
        elif key == "matiec-fault":
            fm = re.fullmatch(r"kind\s+(\d+)", rest)
            if not fm or not num:
                raise ValueError(f"{where}: write `matiec-fault[VARIANT] SCAN: kind K`")
            for v in variants:
                case.matiec_faults[v] = (int(num), int(fm.group(1)))
        elif key == "matiec-defect":
            case.matiec_defect = rest
        elif key == "interval":
            case.interval = rest
        elif key == "reject":
            col = re.match(r"(\d+):\s*(.*)$", rest) if num else None
            case.reject = col.group(2) if col else rest
            case.reject_line = int(num) if num else None
            case.reject_col = int(col.group(1)) if col else None
        elif key == "matiec-accepts":
            case.matiec_accepts = rest
        elif key == "fault":
            fm = re.fullmatch(r"kind\s+(\d+)(?:\s+line\s+(\d+))?", rest)
            if not fm or not num:
                raise ValueError(f"{where}: write `fault SCAN: kind K [line L]`")
            case.fault = (int(num), int(fm.group(1)), int(fm.group(2)) if fm.group(2) else None)
        else:
            raise ValueError(f"{path}: unknown header key {key!r}")
    if (case.matiec_by_variant or case.matiec_faults) and not case.matiec_defect:
        raise ValueError(f"{path}: matiec-expect needs a matiec-defect line saying why")
    case.own_config = re.search(r"(?im)^\s*CONFIGURATION\b", _strip_comments(text)) is not None
    if case.kind == "run" and not case.expects:
        raise ValueError(f"{path}: a case needs expectations, a reject line or a fault line")
    return case


def _strip_comments(text: str) -> str:
    return re.sub(r"\(\*.*?\*\)", " ", text, flags=re.S)


def all_cases() -> list[Case]:
    return [load_case(p) for p in sorted(CASES_DIR.glob("*.st"))]


def config_for(cases: list[Case], interval: str) -> str:
    lines = ["CONFIGURATION CONF", "  RESOURCE RES ON PLC",
             f"    TASK TICK(INTERVAL := {interval}, PRIORITY := 0);"]
    for c in cases:
        lines.append(f"    PROGRAM {c.instance} WITH TICK : {c.program};")
    lines += ["  END_RESOURCE", "END_CONFIGURATION", ""]
    return "\n".join(lines)


def batch_source(cases: list[Case], interval: str) -> str:
    """One ST text: the cases' declarations, then a configuration that instantiates each program."""
    names: dict[str, str] = {}
    for c in cases:
        for kw, name in re.findall(r"(?im)^\s*(TYPE|FUNCTION_BLOCK|FUNCTION|PROGRAM)\s+(\w+)", _strip_comments(c.text)):
            if kw.upper() == "TYPE":
                continue
            key = name.upper()
            if key in names:
                raise ValueError(f"{c.path.name} and {names[key]} both declare {name}: give each case's POUs "
                                 f"names of their own")
            names[key] = c.path.name
    return "\n".join(c.text for c in cases) + "\n" + config_for(cases, interval)


def single_source(case: Case) -> str:
    if case.own_config:
        return case.text
    return case.text + "\n" + config_for([case], case.interval)
