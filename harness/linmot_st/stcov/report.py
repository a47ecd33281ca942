"""The coverage of a session folder (collect.dump) as numbers and as reports.

gcov reads each build's counters (`gcov --json-format`: the counts per line of every source file the C
named with `#line`); the ST files' lines are kept and summed over builds (st_lib's files are in many);
the branches are the ST's arms (arms.py). gcovr writes the reports from that: it reads our counts as its
own JSON tracefile format and writes the terminal table, Cobertura XML and the annotated HTML.
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import os
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

from . import arms as arms_mod

ST_SUFFIXES = (".st",)


@dataclass
class FileCoverage:
    path: Path
    lines: dict[int, int] = field(default_factory=dict)          # instrumented ST line -> times entered
    st: arms_mod.StFile | None = None

    def branches(self) -> list[tuple[arms_mod.Decision, list[int | None]]]:
        return [(d, d.counts(self.lines)) for d in (self.st.decisions if self.st else [])]

    def totals(self, pou: str | None = None) -> Totals:
        t = Totals()
        for line, count in self.lines.items():
            if pou is None or (self.st and self.st.pou_at(line) == pou):
                t.lines += 1
                t.lines_hit += count > 0
        for d, counts in self.branches():
            if pou is None or d.pou == pou:
                known = [c for c in counts if c is not None]
                t.branches += len(known)
                t.branches_hit += sum(c > 0 for c in known)
        return t


@dataclass
class Totals:
    lines: int = 0
    lines_hit: int = 0
    branches: int = 0
    branches_hit: int = 0

    def add(self, other: Totals) -> None:
        self.lines += other.lines
        self.lines_hit += other.lines_hit
        self.branches += other.branches
        self.branches_hit += other.branches_hit

    @staticmethod
    def percent(hit: int, total: int) -> str:
        return f"{100.0 * hit / total:5.1f}%" if total else "    -"


def gcov_tool() -> str:
    """gcov of the C compiler that compiled (gcc's; $GCOV overrides)."""
    return os.environ.get("GCOV", "gcov")


def read(folder: Path) -> dict[Path, FileCoverage]:
    """The ST line counts of every build under the session folder, summed per file."""
    files: dict[Path, FileCoverage] = {}
    for data in sorted(Path(folder).glob("*/*.gcda")):
        sources = _sources_of(data.parent)
        proc = subprocess.run([gcov_tool(), "--json-format", "--stdout", "--object-directory", str(data.parent),
                               data.name], cwd=data.parent, capture_output=True, text=True, check=False)
        if proc.returncode != 0:
            raise RuntimeError(f"gcov failed on {data}: {proc.stderr.strip()}")
        for text in proc.stdout.splitlines():      # one JSON document per line (per .gcda)
            if not text.strip():
                continue
            doc = json.loads(text)
            cwd = Path(doc.get("current_working_directory", "."))
            for f in doc["files"]:
                if not f["file"].lower().endswith(ST_SUFFIXES):
                    continue
                path = _resolve(f["file"], cwd, sources)
                cov = files.setdefault(path, FileCoverage(path))
                for line in f["lines"]:
                    n = line["line_number"]
                    cov.lines[n] = cov.lines.get(n, 0) + int(line["count"])
    for cov in files.values():
        cov.st = arms_mod.read(cov.path)
    return files


def _sources_of(build: Path) -> list[Path]:
    try:
        record = json.loads((build / "coverage.json").read_text())
    except (OSError, ValueError):
        return []
    return [Path(p) for p in record.get("sources", [])]


def _resolve(name: str, cwd: Path, sources: list[Path]) -> Path:
    """The ST file a `#line` name means: the build's source of that path (an included file is named by its
    include path, relative to the folder it was found in), else the name against gcc's working folder."""
    p = Path(name)
    if p.is_absolute():
        return p.resolve()
    for src in sources:
        if src.parts[-len(p.parts):] == p.parts:
            return src
    return (cwd / p).resolve()


def total(files: dict[Path, FileCoverage]) -> Totals:
    t = Totals()
    for cov in files.values():
        t.add(cov.totals())
    return t


def summary(files: dict[Path, FileCoverage], root: Path | None = None, per_pou: bool = True) -> str:
    """The terminal table: per file (and per POU) lines and branches covered."""
    rows = [("ST coverage", "lines", "", "branches", "")]
    for path in sorted(files):
        cov = files[path]
        name = _rel(path, root)
        t = cov.totals()
        rows.append((name, f"{t.lines_hit}/{t.lines}", Totals.percent(t.lines_hit, t.lines),
                     f"{t.branches_hit}/{t.branches}", Totals.percent(t.branches_hit, t.branches)))
        if per_pou and cov.st:
            for pou in cov.st.pous:
                p = cov.totals(pou.name)
                if p.lines:
                    rows.append((f"  {pou.kind} {pou.name}", f"{p.lines_hit}/{p.lines}",
                                 Totals.percent(p.lines_hit, p.lines), f"{p.branches_hit}/{p.branches}",
                                 Totals.percent(p.branches_hit, p.branches)))
    t = total(files)
    rows.append(("TOTAL", f"{t.lines_hit}/{t.lines}", Totals.percent(t.lines_hit, t.lines),
                 f"{t.branches_hit}/{t.branches}", Totals.percent(t.branches_hit, t.branches)))
    width = max(len(r[0]) for r in rows)
    return "\n".join(f"{r[0]:<{width}}  {r[1]:>11} {r[2]:>6}  {r[3]:>11} {r[4]:>6}" for r in rows)


def _rel(path: Path, root: Path | None) -> str:
    if root is not None:
        try:
            return str(path.relative_to(root))
        except ValueError:
            pass
    return str(path)


def tracefile(files: dict[Path, FileCoverage]) -> dict:
    """Our counts in gcovr's JSON format (format 0.15, as gcovr 8 writes it), arms as its branches: on the
    line of each IF / CASE, one branch per arm whose count is known."""
    out = []
    for path in sorted(files):
        cov = files[path]
        try:
            text = path.read_text(errors="replace").splitlines()
        except OSError:
            text = []
        arms_at: dict[int, list[int]] = {}
        for d, counts in cov.branches():
            arms_at.setdefault(d.line, []).extend(c for c in counts if c is not None)
        lines = []
        for n in sorted(set(cov.lines) | set(arms_at)):
            src = text[n - 1] if 0 < n <= len(text) else ""
            pou = (cov.st.pou_at(n) if cov.st else None) or ""
            lines.append({"line_number": n, "function_name": pou, "count": cov.lines.get(n, 0),
                          "branches": [{"branchno": k, "count": c, "fallthrough": False, "throw": False,
                                        "source_block_id": 0} for k, c in enumerate(arms_at.get(n, []))],
                          "gcovr/md5": hashlib.md5(src.encode()).hexdigest()})
        functions = []
        for pou in cov.st.pous if cov.st else []:
            counted = [cov.lines[n] for n in sorted(cov.lines) if pou.first_line <= n <= pou.last_line]
            if counted:
                functions.append({"name": pou.name, "lineno": pou.first_line, "execution_count": counted[0]})
        out.append({"file": str(path), "lines": lines, "functions": functions})
    return {"gcovr/format_version": "0.15", "files": out}


def write_reports(files: dict[Path, FileCoverage], out_dir: Path, root: Path, *, xml: Path | None = None,
                  html: Path | None = None) -> dict[str, Path]:
    """Cobertura XML and the HTML (one page per ST file, its source annotated) by gcovr, from tracefile().
    Returns what was written by kind."""
    out_dir.mkdir(parents=True, exist_ok=True)
    trace = out_dir / "coverage.json"
    trace.write_text(json.dumps(tracefile(files)))
    xml = xml or out_dir / "coverage.xml"
    html = html or out_dir / "html" / "index.html"
    html.parent.mkdir(parents=True, exist_ok=True)
    argv = [*gcovr_command(), "--root", str(root), "--json-add-tracefile", str(trace),
            "--cobertura-pretty", "--cobertura", str(xml), "--html-details", str(html),
            "--html-title", "ST coverage (linmot-st)"]
    proc = subprocess.run(argv, capture_output=True, text=True, check=False)
    if proc.returncode != 0:
        raise RuntimeError(f"gcovr failed ({' '.join(argv)}):\n{proc.stdout}{proc.stderr}")
    return {"json": trace, "cobertura": xml, "html": html}


def gcovr_command() -> list[str]:
    """gcovr of this Python (a dependency), else the one on PATH."""
    if importlib.util.find_spec("gcovr") is not None:
        return [sys.executable, "-m", "gcovr"]
    found = shutil.which("gcovr")
    if not found:
        raise RuntimeError("gcovr is not installed (pip install gcovr)")
    return [found]
