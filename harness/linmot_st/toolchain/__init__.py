"""ST -> C -> shared library, with MatIEC's iec2c or the builtin compiler, cached by content.

    from linmot_st.toolchain import build
    res = build("plc_project", backend="auto")   # res.library, res.manifest, res.backend, res.cached

See docs/architecture.md section 1 and docs/toolchain.md.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from . import cache as _cache
from . import cc
from . import sources as _sources
from .backend import Backend, Generated, Rejected
from .backends import BACKENDS, CHOICES, builtin_available, choose, matiec_available

_TOOLCHAIN_DIR = Path(__file__).parent


class CompileError(Exception):
    """The sources do not compile. `diagnostics` holds `file:line:col: error: message` lines."""

    def __init__(self, diagnostics: list[str] | str, backend: str = ""):
        if isinstance(diagnostics, str):
            diagnostics = diagnostics.splitlines() or [diagnostics]
        self.diagnostics = [str(d) for d in diagnostics]
        self.backend = backend
        super().__init__("\n".join(self.diagnostics))


class SourcePathError(CompileError):
    """The path given to build() is not a .st file nor a project folder: nothing was compiled, so the
    message is a plain sentence, without a source position."""


class InternalCompilerError(CompileError):
    """A backend failed in a way it should not (a bug of this project). The original exception is the
    `__cause__`; the CLI prints its traceback with --verbose or LINMOT_ST_TRACEBACK=1."""


TRACEBACK_ENV = "LINMOT_ST_TRACEBACK"
# set (to the folder of the session's coverage data) by `pytest --linmot-cov`: builds default to coverage
# builds, so that every PLC a test loads counts (docs/coverage.md)
COVERAGE_ENV = "LINMOT_ST_COVERAGE"
COVERAGE_RECORD = "coverage.json"     # in a coverage build's entry: where gcc put its objects (the .gcda paths)
COVERAGE_FORMAT = "gcov-2"            # of the coverage builds (their flags and record): part of their cache key
FAILED_KEPT = 5     # failed builds whose generated C is kept for reading (build/cache/failed-<key>)


@dataclass
class BuildResult:
    library: Path
    manifest: Path
    backend: str
    cached: bool
    entry: Path
    root: Path
    seconds: float = 0.0
    backend_version: str = ""
    warnings: list[str] = field(default_factory=list)
    c_dir: Path | None = None     # the generated C, kept for reading
    coverage: bool = False        # compiled with gcc's coverage counters (docs/coverage.md)


def choose_backend(backend: str = "auto") -> str:
    """`auto` is matiec when iec2c is found, else builtin."""
    return choose(backend).name


def _code_digest(paths: list[Path]) -> str:
    h = hashlib.sha256()
    for p in sorted(paths):
        h.update(p.name.encode() + b"\0" + p.read_bytes())
    return h.hexdigest()


def build(path: str | os.PathLike, backend: str = "auto", out: str | os.PathLike | None = None, *,
          cache_dir: str | os.PathLike | None = None, use_cache: bool = True,
          root: str | os.PathLike | None = None, coverage: bool | None = None) -> BuildResult:
    """Build a .st file or a project folder (its plc.st) into a shared library and its manifest. `root`:
    the folder include paths resolve against (default: the nearest ancestor holding st_lib/linmot.st,
    else the current directory); a root without st_lib/ gets the library tree on its include path.
    `coverage`: with gcc's coverage counters, the C mapped to ST lines (default: whether $LINMOT_ST_COVERAGE
    is set, as `pytest --linmot-cov` does)."""
    t0 = time.perf_counter()
    if coverage is None:
        coverage = bool(os.environ.get(COVERAGE_ENV))
    chosen = choose(backend)
    try:
        src = _sources.collect(path, root=root)
    except _sources.SourceError as exc:
        raise SourcePathError([f"error: {exc}"], chosen.name) from None

    reason = chosen.missing()
    if reason is not None:
        raise CompileError([f"{src.entry}:1:1: error: {reason}"], chosen.name)
    backend_version = chosen.version()
    generator = chosen.generator_files()
    flags = chosen.flags()

    try:
        compiler = cc.find_compiler()
    except cc.CCompileError as exc:
        raise CompileError([f"error: {exc}"], chosen.name) from None
    # the keys of plain builds stay what they were; a coverage build's also name its record's format
    extra_key = {"coverage": COVERAGE_FORMAT} if coverage else {}
    key = _cache.make_key({
        **extra_key,
        "backend": chosen.name,
        "backend_version": backend_version,
        "generator": _code_digest(generator + [_TOOLCHAIN_DIR / "cc.py"]),
        "cc": compiler.version,
        "cflags": cc.BASE_FLAGS + cc.LINK_FLAGS + flags,
        "glue": _code_digest(cc.GLUE_SOURCES + ([cc.COVERAGE_GLUE] if coverage else [])),
        "entry": src.entry_rel,
        "root": str(src.root),
        "search": [str(p) for p in src.search],
        "sources": {_sources.rel_name(f, src.root): _cache.file_digest(f) for f in src.files},
        "missing": src.missing,
    })
    store = _cache.Cache(Path(cache_dir) if cache_dir else _cache.default_dir(src.root, src.writable_tree))
    entry = store.lookup(key) if use_cache else None
    cached = entry is not None
    if entry is None:
        entry = _compile(chosen, src, store, key, backend_version, coverage)
    manifest = json.loads((entry / _cache.MANIFEST_NAME).read_text())
    result = BuildResult(entry / _cache.LIBRARY_NAME, entry / _cache.MANIFEST_NAME, chosen.name, cached, src.entry,
                         src.root, backend_version=backend_version, warnings=manifest.get("warnings", []),
                         c_dir=entry / "c", coverage=coverage)
    if out is not None:
        result = _export(result, Path(out))
    result.seconds = time.perf_counter() - t0
    return result


# A build whose C generation took longer than this tells on stderr what it is doing (a big dataset or
# program: the C compile that follows may take as long again)
PROGRESS_AFTER_S = 2.0


def _progress(src: _sources.Sources, text: str) -> None:
    print(f"linmot-st build: {src.entry_rel}: {text}", file=sys.stderr, flush=True)


def _c_lines(units: list[Path]) -> int:
    return sum(Path(u).read_bytes().count(b"\n") for u in units)


def _compile(chosen: Backend, src: _sources.Sources, store: _cache.Cache, key: str,
             backend_version: str, coverage: bool = False) -> Path:
    staging = store.staging()
    t0 = time.perf_counter()
    started: list[cc.Started] = []
    try:
        c_dir = staging / "c"
        c_dir.mkdir()
        # the glue includes nothing generated: its gcc runs while the ST is translated
        started = cc.start(cc.GLUE_SOURCES, staging, cwd=src.root)
        try:
            gen: Generated = (chosen.generate(src, c_dir, backend_version, coverage=True) if coverage
                              else chosen.generate(src, c_dir, backend_version))
        except Rejected as exc:
            raise CompileError(exc.diagnostics, chosen.name) from None
        except Exception as exc:
            raise _internal(exc, chosen.name, src) from exc
        manifest, all_units, one_program = gen.manifest, gen.units, gen.one_program
        unit_flags, link_flags = gen.unit_flags, []
        if coverage:
            # the ST's units counted; the flush entry point compiled plain; the .gcno files stay in the
            # entry, and the record names the folder gcc compiled in (the .gcda paths libgcov writes)
            unit_flags = {u: gen.unit_flags.get(u, []) + cc.COVERAGE_FLAGS for u in all_units}
            all_units = [*all_units, cc.COVERAGE_GLUE]
            link_flags = cc.COVERAGE_LINK_FLAGS
            # the ST files by absolute path: the C names an included file as its include path
            (staging / COVERAGE_RECORD).write_text(json.dumps({
                "objdir": str(staging), "backend": chosen.name, "root": str(src.root),
                "sources": [str(Path(p).resolve()) for p in gen.sources_read]}))
        (staging / _cache.MANIFEST_NAME).write_text(json.dumps(manifest, indent=1))
        generated_s = time.perf_counter() - t0
        loud = generated_s > PROGRESS_AFTER_S
        if loud:
            together = cc.program_lines(one_program) if len(one_program) > 1 else None
            slow = [u.name for u in all_units if cc.size_flags(u, together if u in one_program else None)]
            _progress(src, f"C generated by {chosen.name} in {generated_s:.1f} s ({_c_lines(all_units):,} lines in "
                           f"{len(all_units)} units); compiling with {Path(cc.find_compiler().path).name}"
                           + (f" (-O0 for the large {', '.join(slow)})" if slow else "") + " ...")
        try:
            cc.compile_shared(all_units, staging / _cache.LIBRARY_NAME, include_dirs=gen.include_dirs,
                              unit_flags=unit_flags, cwd=src.root, one_program=one_program, started=started,
                              link_flags=link_flags)
        except cc.CCompileError as exc:
            kept = _keep_failed(store, key, staging)
            text = str(exc)
            diags = exc.diagnostics or [f"{src.entry_rel}:1:1: error: {exc}"]
            if kept is not None:    # the staging folder is about to go: point into the kept copy
                diags = [d.replace(str(staging), str(kept)) for d in diags]
                text = text.replace(str(staging), str(kept))
            diags = chosen.explain_c_errors(diags)
            where = f"kept in {kept / 'c'}" if kept is not None else "not kept"
            raise CompileError(diags + [f"note: the C compiler rejected the C that {chosen.name} generated from "
                                        f"{src.entry_rel} (the C is {where})", text], chosen.name) from None
        if loud:
            _progress(src, f"compiled and linked in {time.perf_counter() - t0 - generated_s:.1f} s")
        for o in staging.glob("*.o"):
            o.unlink()
        meta = {"backend": chosen.name, "backend_version": backend_version, "entry": str(src.entry),
                "sources_read": {str(p): _cache.file_digest(p) for p in gen.sources_read}}
        return store.commit(key, staging, meta)
    except BaseException:
        for job in started:
            job.cancel()
        store.discard(staging)
        raise


def _keep_failed(store: _cache.Cache, key: str, staging: Path) -> Path | None:
    """Move a failed build's staging folder to `failed-<key>` beside the entries, keeping the last few."""
    target = store.folder / f"failed-{key[:16]}"
    try:
        shutil.rmtree(target, ignore_errors=True)
        os.rename(staging, target)
        os.utime(target)
    except OSError:
        return None
    old = sorted(store.folder.glob("failed-*"), key=lambda p: p.stat().st_mtime if p.exists() else 0)
    for p in old[:-FAILED_KEPT]:
        shutil.rmtree(p, ignore_errors=True)
    return target


def _internal(exc: BaseException, backend: str, src: _sources.Sources) -> InternalCompilerError:
    """An unexpected exception of a backend, reported with the file it was compiling."""
    detail = str(exc).splitlines()[0] if str(exc) else ""
    return InternalCompilerError(
        [f"{src.entry_rel}: error: internal compiler error of the {backend} backend: {type(exc).__name__}"
         + (f": {detail}" if detail else ""),
         f"note: this is a bug of linmot-st, not of the ST; --verbose (or {TRACEBACK_ENV}=1) shows the traceback"],
        backend)


def _export(result: BuildResult, out: Path) -> BuildResult:
    """Copy the library, its manifest and the generated C into `out`."""
    out.mkdir(exist_ok=True)                  # the folder named, not its parents (checked by the CLI)
    shutil.copyfile(result.library, out / result.library.name)
    shutil.copyfile(result.manifest, out / result.manifest.name)
    if result.c_dir and result.c_dir.is_dir():
        shutil.copytree(result.c_dir, out / "c", dirs_exist_ok=True)
    result.library, result.manifest, result.c_dir = out / result.library.name, out / result.manifest.name, out / "c"
    return result


def say(message: str) -> None:
    print(message, file=sys.stderr)


__all__ = ["build", "BuildResult", "CompileError", "SourcePathError", "InternalCompilerError", "choose_backend", "matiec_available",
           "builtin_available", "Backend", "BACKENDS", "CHOICES"]
