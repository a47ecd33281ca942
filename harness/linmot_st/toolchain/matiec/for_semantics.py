"""Which FOR semantics the installed iec2c has, measured by a probe program (spec/matiec.md 7.1).

Users' iec2c differ in the C they generate for FOR:
  head     MatIEC HEAD since 8a06b3b (2024-06), as Beremiz builds it: `while (i < end)` tested before the
           step, so a loop that should run exactly once runs zero times, and the control variable ends at
           its last value in the loop, not one step past it;
  openplc  OpenPLC_v3's copy (utils/matiec_src): the step, then `if (i <= end) body else break`: counts
           right, but when the end is the type's maximum the control variable wraps and the loop never ends;
  fixed    IEC counts, one step past the end afterwards, and a loop up to the type's maximum ends.
The probe measures each trait on its own, so an iec2c that is none of these is reported as what it does.
It is built like any program (so its library is cached with the build cache, keyed by the iec2c) and run
once in this process; every loop in it carries an iteration guard, so a variant that spins cannot hang
it. The measured traits are kept beside the build cache, keyed by the iec2c's identity.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

from linmot_st.plc import Plc

from .. import build
from .. import cache as _cache
from .tool import find, version

GUARD = 20     # more iterations than any probe loop runs under IEC semantics: a loop that goes on spins

PROBE_ST = f"""\
(* Which FOR semantics this iec2c has: linmot_st.toolchain.matiec.for_semantics *)
PROGRAM for_probe
  VAR i, j, n, m : INT; u : USINT; d : DINT; once, past_end, spins, spins_by : BOOL; END_VAR
  n := 0;
  FOR i := 5 TO 5 DO n := n + 1; END_FOR;
  once := n = 1;
  m := 0;
  FOR j := 0 TO 4 DO m := m + 1; END_FOR;
  past_end := j = 5;
  m := 0;
  FOR u := 253 TO 255 DO m := m + 1; IF m > {GUARD} THEN EXIT; END_IF; END_FOR;
  spins := m > {GUARD};
  m := 0;
  FOR d := 2147483645 TO 2147483647 BY 1 DO m := m + 1; IF m > {GUARD} THEN EXIT; END_IF; END_FOR;
  spins_by := m > {GUARD};
END_PROGRAM
CONFIGURATION probe_conf
  RESOURCE probe_res ON PLC
    TASK tick(INTERVAL := T#10ms, PRIORITY := 0);
    PROGRAM probe WITH tick : for_probe;
  END_RESOURCE
END_CONFIGURATION
"""


@dataclass(frozen=True)
class ForSemantics:
    once: bool           # FOR i := 5 TO 5 runs its body once (not zero times)
    past_end: bool       # after FOR j := 0 TO 4, j = 5 (not 4)
    spins: bool          # FOR u := 253 TO 255 on a USINT never ends
    spins_by: bool       # FOR d := 2147483645 TO 2147483647 BY 1 on a DINT never ends

    @property
    def name(self) -> str:
        known = {(False, False, False, True): "head", (True, True, True, True): "openplc",
                 (True, True, False, False): "fixed"}
        return known.get((self.once, self.past_end, self.spins, self.spins_by), "other")

    @property
    def iec(self) -> bool:
        """Whether FOR means what it means in IEC 61131-3 (and on the builtin backend)."""
        return self.once and self.past_end and not self.spins and not self.spins_by

    def describe(self) -> str:
        parts = [
            "loops that should run once run" + ("" if self.once else " zero times"),
            "the control variable ends " + ("one step past the end" if self.past_end else "at its last value"),
        ]
        if self.spins or self.spins_by:
            parts.append("a loop whose end is the type's maximum never ends"
                         + ("" if self.spins else " (with BY, at the 32-bit limits)"))
        else:
            parts.append("a loop up to the type's maximum ends")
        label = {"head": "MatIEC HEAD's (since 2024-06, as Beremiz builds it)",
                 "openplc": "OpenPLC's copy of MatIEC", "fixed": "fixed (IEC semantics)",
                 "other": "not one of the known variants"}[self.name]
        return f"FOR semantics of this iec2c: {self.name}, {label}: " + "; ".join(parts)


_memo: dict[str, ForSemantics] = {}


def probe(cache_dir: Path | None = None) -> ForSemantics:
    """Measure the FOR semantics of the iec2c the matiec backend would use (iec2c.find())."""
    tool = find()
    if tool is None:
        raise RuntimeError("no iec2c found: set MATIEC_HOME or IEC2C, or put iec2c on PATH")
    ident = version(tool)
    if ident in _memo:
        return _memo[ident]
    folder = Path(cache_dir) if cache_dir else _cache.default_dir(Path.cwd(), in_tree=False)
    folder = folder / "for-probe"
    folder.mkdir(parents=True, exist_ok=True)
    record = folder / (_cache.make_key({"iec2c": ident, "probe": PROBE_ST})[:24] + ".json")
    if record.is_file():
        try:
            found = ForSemantics(**json.loads(record.read_text()))
            _memo[ident] = found
            return found
        except (ValueError, TypeError):
            pass        # an unreadable record is measured again
    found = _measure(folder, cache_dir)
    record.write_text(json.dumps(asdict(found)))
    _memo[ident] = found
    return found


def _measure(folder: Path, cache_dir: Path | None) -> ForSemantics:
    source = folder / "for_probe.st"
    if not source.is_file() or source.read_text() != PROBE_ST:
        source.write_text(PROBE_ST)
    res = build(source, backend="matiec", cache_dir=cache_dir or folder / "cache")
    plc = Plc(res)
    plc.step(1)
    values = {k: bool(plc[f"PROBE_CONF.PROBE_RES.PROBE.{k.upper()}"])
              for k in ("once", "past_end", "spins", "spins_by")}
    return ForSemantics(**values)
