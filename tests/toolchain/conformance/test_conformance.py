"""Language conformance: every case of cases/ on every available backend, and builtin vs MatIEC.

See conformance_lib.py for the case format. Run cases are batched: one build per backend and task
interval. A MatIEC defect known from spec/matiec.md is written into its case (matiec-defect /
matiec-expect) and checked as such, never skipped. Where users' iec2c differ (FOR, spec/matiec.md 7.1),
the expectation is tagged by variant and the suite measures which one is installed (for_semantics.probe).
"""

from __future__ import annotations

import re
import tempfile
from pathlib import Path

import pytest
from conformance_lib import Case, all_cases, batch_source, single_source

from linmot_st.plc import Plc, PlcFault
from linmot_st.toolchain import CompileError, build
from linmot_st.toolchain.matiec.for_semantics import probe
from linmot_st.toolchain.testing import MATIEC_MISSING, matiec_available

CASES = all_cases()
RUN = [c for c in CASES if c.kind == "run"]
REJECT = [c for c in CASES if c.kind == "reject"]
FAULT = [c for c in CASES if c.kind == "fault"]

HAVE_MATIEC = matiec_available()
WORK = Path(tempfile.gettempdir()) / "linmot-st-conformance"
FOR_VARIANT = probe(WORK / "for-probe").name if HAVE_MATIEC else None
SPIN_WATCHDOG_NS = 200_000_000      # a case expected to spin under this iec2c: the watchdog ends it
BACKENDS = [
    pytest.param("builtin"),
    pytest.param("matiec", marks=[pytest.mark.matiec, pytest.mark.skipif(not HAVE_MATIEC, reason=MATIEC_MISSING)]),
]
DIAGNOSTIC = re.compile(r"^(?P<file>[^:]+):(?P<line>\d+):(?P<col>\d+): error: (?P<msg>.+)$")


def _write(folder: Path, name: str, text: str) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    if not path.exists() or path.read_text() != text:
        path.write_text(text)
    return path


class Outcome:
    def __init__(self):
        self.values: dict[int, dict[str, object]] = {}
        self.snapshots: dict[int, object] = {}
        self.error: str | None = None
        self.types: dict = {}                   # the manifest's types
        self.snapshot_type = ""                 # the type of the snapshots' program instance


def _variant(backend: str) -> str | None:
    return FOR_VARIANT if backend == "matiec" else None


def _run(cases: list[Case], backend: str, source: str, folder: Path, name: str) -> dict[str, Outcome]:
    outcomes = {c.name: Outcome() for c in cases}
    res = build(_write(folder, name, source), backend=backend)
    plc = Plc(res)
    checkpoints = sorted({n for c in cases for n in (*c.expects, *c.matiec_expects)})
    done = 0
    for n in checkpoints:
        plc.step(n - done)
        done = n
        for c in cases:
            if n in c.expects or n in c.matiec_expects:
                o = outcomes[c.name]
                paths = set(c.expects.get(n, {})) | set(c.matiec_expects.get(n, {}))
                o.values[n] = {p: plc[c.path_of(p)] for p in paths}
                if not c.own_config:
                    o.snapshots[n] = plc[f"CONF.RES.{c.instance}"]
                    o.types = plc.manifest["types"]
                    o.snapshot_type = next(r["type"] for r in plc.manifest["roots"]
                                           if r["path"].upper() == f"CONF.RES.{c.instance}".upper())
    return outcomes


_results: dict[str, dict[str, Outcome]] = {}


def results(backend: str) -> dict[str, Outcome]:
    """Run every run-case on a backend (once per session)."""
    if backend in _results:
        return _results[backend]
    out: dict[str, Outcome] = {}
    folder = WORK / backend
    batches: dict[str, list[Case]] = {}
    for c in RUN:
        if backend == "matiec" and c.matiec_fault(FOR_VARIANT):
            continue            # it faults (or spins) under this iec2c: test_run builds it alone
        if c.own_config:
            out.update(_guarded([c], backend, lambda c=c: _run([c], backend, c.text, folder / c.name, "case.st")))
        else:
            batches.setdefault(c.interval, []).append(c)
    for i, (interval, cases) in enumerate(sorted(batches.items())):
        try:
            out.update(_run(cases, backend, batch_source(cases, interval), folder / f"batch{i}", "batch.st"))
        except (CompileError, ValueError):
            # find the culprit(s): each case on its own
            for c in cases:
                out.update(_guarded([c], backend, lambda c=c: _run([c], backend, single_source(c),
                                                                    folder / c.name, "case.st")))
    _results[backend] = out
    return out


def _guarded(cases, backend, fn) -> dict[str, Outcome]:
    try:
        return fn()
    except (CompileError, PlcFault, ValueError) as exc:
        o = {}
        for c in cases:
            o[c.name] = Outcome()
            o[c.name].error = f"{type(exc).__name__}: {exc}"
        return o


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("case", RUN, ids=[c.name for c in RUN])
def test_run(case: Case, backend: str):
    expected_fault = case.matiec_fault(FOR_VARIANT) if backend == "matiec" else None
    if expected_fault:
        _expect_variant_fault(case, *expected_fault)
        return
    outcome = results(backend)[case.name]
    assert outcome.error is None, f"{case.name} ({case.title}) failed on {backend}:\n{outcome.error}"
    for scans, values in case.expected(backend, _variant(backend)).items():
        got = outcome.values[scans]
        for path, want in values.items():
            assert _equal(got[path], want), (f"{case.name} ({case.title}), {backend}, after {scans} scan(s): "
                                              f"{path} = {got[path]!r}, expected {want!r}")


def _expect_variant_fault(case: Case, scan: int, kind: int):
    """A run case that this iec2c's C turns into a PLC fault (kind 5: its FOR never ends)."""
    res = build(_write(WORK / "matiec" / case.name, "case.st", single_source(case)), backend="matiec")
    plc = Plc(res)
    plc.watchdog_ns = SPIN_WATCHDOG_NS
    if scan > 1:
        plc.step(scan - 1)
    with pytest.raises(PlcFault) as info:
        plc.step(1)
    assert info.value.kind == kind, f"{case.name} under {FOR_VARIANT}: {info.value}, expected kind {kind}"


@pytest.mark.matiec
@pytest.mark.skipif(not HAVE_MATIEC, reason=MATIEC_MISSING)
@pytest.mark.parametrize("case", RUN, ids=[c.name for c in RUN])
def test_differential(case: Case):
    """Both backends leave every variable of the case's program in the same state (but the values a
    matiec-expect names: a documented difference, checked by test_run)."""
    if case.matiec_fault(FOR_VARIANT):
        return                  # nothing to compare: MatIEC's run ends in a fault (test_run checks it)
    a, b = results("builtin")[case.name], results("matiec")[case.name]
    if a.error or b.error:
        pytest.fail(f"not comparable: builtin: {a.error}; matiec: {b.error}")
    skip = case.excluded_from_diff(FOR_VARIANT)
    refs = _by_reference(a.types, b.types)
    for scans in a.snapshots:
        da, db = (_drop(_mask(o.snapshots[scans], o.snapshot_type, o.types, refs), skip) for o in (a, b))
        assert _equal(da, db), f"{case.name} after {scans} scan(s): builtin {da} != matiec {db}"


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("case", REJECT, ids=[c.name for c in REJECT])
def test_reject(case: Case, backend: str):
    path = _write(WORK / backend / "reject", f"{case.name}.st", single_source(case))
    if backend == "matiec" and case.matiec_accepts:
        build(path, backend=backend)      # a documented difference: MatIEC accepts it
        return
    with pytest.raises(CompileError) as info:
        build(path, backend=backend)
    text = str(info.value)
    if backend == "builtin":
        first = info.value.diagnostics[0]
        m = DIAGNOSTIC.match(first)
        assert m, f"{case.name}: not `file:line:col: error: message`: {first!r}"
        assert Path(m["file"]).name == path.name, f"{case.name}: the diagnostic names {m['file']}, not {path.name}"
        assert case.reject.lower() in m["msg"].lower(), f"{case.name}: expected {case.reject!r} in:\n{text}"
        if case.reject_line is not None:
            assert int(m["line"]) == case.reject_line, f"{case.name}: expected line {case.reject_line}:\n{text}"
        if case.reject_col is not None:
            assert int(m["col"]) == case.reject_col, f"{case.name}: expected column {case.reject_col}:\n{text}"
    else:   # MatIEC's own words, in the same form
        assert DIAGNOSTIC.match(info.value.diagnostics[0]), info.value.diagnostics[0]


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("case", FAULT, ids=[c.name for c in FAULT])
def test_fault(case: Case, backend: str):
    scan, kind, line = case.fault
    if backend == "matiec" and case.matiec_fault(FOR_VARIANT):
        scan, kind = case.matiec_fault(FOR_VARIANT)     # a documented difference in how MatIEC's C stops
    res = build(_write(WORK / backend / "fault", f"{case.name}.st", single_source(case)), backend=backend)
    plc = Plc(res)
    if scan > 1:
        plc.step(scan - 1)
    with pytest.raises(PlcFault) as info:
        plc.step(1)
    f = info.value
    assert f.kind == kind, f"{case.name}: fault kind {f.kind} ({f}), expected {kind}"
    assert f.pou.upper() == case.program, f"{case.name}: fault in {f.pou!r}, expected {case.program}"
    if line is not None and (backend == "builtin" or f.line):
        assert f.line == line, f"{case.name}: fault at line {f.line}, expected {line}"
    assert plc.scan_count == scan - 1


def _by_reference(builtin: dict, matiec: dict) -> set[tuple[str, str]]:
    """(FB type, member) of the parameters the builtin passes by reference (a pointer, `ptr:`, where MatIEC
    holds a copy, `var:`; toolchain/builtin/param_refs.py): the member reads the actual as it is now, not
    the copy of the last call, so it is not compared (the variables it points to are)."""
    out = set()
    for name, spec in builtin.items():
        theirs = {f["name"]: f["type"] for f in matiec.get(name, {}).get("fields", [])}
        for f in spec.get("fields", []):
            if f["type"].startswith("ptr:") and theirs.get(f["name"], "").startswith("var:"):
                out.add((name, f["name"]))
    return out


def _mask(snapshot, type_name: str, types: dict, refs: set[tuple[str, str]]):
    """The snapshot with each member passed by reference (`refs`) replaced by a mark."""
    spec = types.get(type_name)
    if not isinstance(snapshot, dict) or not spec or spec.get("kind") not in ("fb", "program"):
        return snapshot
    fields = {f["name"]: f["type"] for f in spec["fields"]}
    return {k: "(by reference)" if (type_name, k.upper()) in refs else _mask(v, fields.get(k.upper(), ""), types, refs)
            for k, v in snapshot.items()}


def _drop(snapshot, skip: set[str]):
    if isinstance(snapshot, dict):
        return {k: v for k, v in snapshot.items() if k.upper() not in skip}
    return snapshot


def _equal(a, b) -> bool:
    if isinstance(a, float) or isinstance(b, float):
        try:
            return a == b or abs(a - b) <= 1e-9 * max(1.0, abs(a), abs(b))
        except TypeError:
            return False
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(_equal(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and isinstance(b, (list, tuple)):
        return len(a) == len(b) and all(_equal(x, y) for x, y in zip(a, b))
    return a == b
