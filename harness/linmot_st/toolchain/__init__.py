"""ST -> C -> shared library, with MatIEC's iec2c or the builtin compiler, cached by content.

    from linmot_st.toolchain import build
    res = build("plc_project", backend="auto")   # res.library, res.manifest, res.backend, res.cached

See docs/architecture.md section 1 and docs/toolchain.md.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import shutil
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from . import cache as _cache
from . import cc, sources as _sources

BACKENDS = ("auto", "matiec", "builtin")
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


def matiec_available() -> bool:
    from . import matiec
    return matiec.find() is not None


def builtin_available() -> bool:
    try:
        from .builtin import compile_to_c  # noqa: F401
    except ImportError:
        return False
    return True


def choose_backend(backend: str = "auto") -> str:
    """`auto` is matiec when iec2c is found, else builtin."""
    if backend not in BACKENDS:
        raise ValueError(f"unknown backend {backend!r}: choose one of {', '.join(BACKENDS)}")
    if backend != "auto":
        return backend
    return "matiec" if matiec_available() else "builtin"


def _code_digest(paths: list[Path]) -> str:
    h = hashlib.sha256()
    for p in sorted(paths):
        h.update(p.name.encode() + b"\0" + p.read_bytes())
    return h.hexdigest()


def build(path: str | os.PathLike, backend: str = "auto", out: str | os.PathLike | None = None, *,
          cache_dir: str | os.PathLike | None = None, use_cache: bool = True,
          root: str | os.PathLike | None = None) -> BuildResult:
    """Build a .st file or a project folder (its plc.st) into a shared library and its manifest. `root`:
    the folder include paths resolve against (default: the nearest ancestor holding st_lib/linmot.st,
    else the current directory); a root without st_lib/ gets the library tree on its include path."""
    t0 = time.perf_counter()
    chosen = choose_backend(backend)
    try:
        src = _sources.collect(path, root=root)
    except _sources.SourceError as exc:
        raise SourcePathError([f"error: {exc}"], chosen) from None

    if chosen == "matiec":
        from . import matiec
        tool = matiec.find()
        if tool is None:
            raise CompileError([f"{src.entry}:1:1: error: backend matiec: iec2c not found "
                                f"(set IEC2C or MATIEC_HOME, or put iec2c on PATH)"], chosen)
        backend_version = matiec.version(tool)
        # st_decls reads declarations with the builtin parser: its files shape the MatIEC manifest too
        generator = [_TOOLCHAIN_DIR / "matiec.py", _TOOLCHAIN_DIR / "st_decls.py",
                     *sorted((_TOOLCHAIN_DIR / "builtin").glob("*.py")), _TOOLCHAIN_DIR / "builtin" / "st.lark"]
        flags = list(matiec.flags(tool.iec2c)) + _matiec_unit_flags()
    else:
        tool = None
        try:
            from . import builtin
            from .builtin import compile_to_c  # noqa: F401
        except ImportError as exc:
            raise CompileError([f"{src.entry}:1:1: error: the builtin compiler is not available: {exc}"],
                               chosen) from None
        builtin_dir = _TOOLCHAIN_DIR / "builtin"
        generator = [p for p in builtin_dir.rglob("*") if p.suffix in (".py", ".lark", ".c", ".h", ".json")]
        version_fn = getattr(builtin, "backend_version", None)
        backend_version = version_fn() if callable(version_fn) else "builtin-" + _code_digest(generator)[:16]
        flags = list(cc.BUILTIN_FLAGS)

    try:
        compiler = cc.find_compiler()
    except cc.CCompileError as exc:
        raise CompileError([f"error: {exc}"], chosen) from None
    key = _cache.make_key({
        "backend": chosen,
        "backend_version": backend_version,
        "generator": _code_digest(generator + [_TOOLCHAIN_DIR / "cc.py"]),
        "cc": compiler.version,
        "cflags": cc.BASE_FLAGS + cc.LINK_FLAGS + flags,
        "glue": _code_digest(cc.GLUE_SOURCES),
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
        entry = _compile(chosen, tool, src, store, key, backend_version)
    manifest = json.loads((entry / _cache.MANIFEST_NAME).read_text())
    result = BuildResult(entry / _cache.LIBRARY_NAME, entry / _cache.MANIFEST_NAME, chosen, cached, src.entry,
                         src.root, backend_version=backend_version, warnings=manifest.get("warnings", []),
                         c_dir=entry / "c")
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


def _compile(chosen: str, tool, src: _sources.Sources, store: _cache.Cache, key: str,
             backend_version: str) -> Path:
    staging = store.staging()
    t0 = time.perf_counter()
    started: list[cc.Started] = []
    try:
        c_dir = staging / "c"
        c_dir.mkdir()
        # the glue includes nothing generated: its gcc runs while the ST is translated
        started = cc.start(cc.GLUE_SOURCES, staging, cwd=src.root)
        if chosen == "matiec":
            from . import matiec
            try:
                manifest, units, plain_units = matiec.generate(tool, src, c_dir, backend_version)
            except matiec.MatiecError as exc:
                raise CompileError(exc.diagnostics, chosen) from None
            except Exception as exc:
                raise _internal(exc, chosen, src) from exc
            unit_flags = {u: _matiec_unit_flags() for u in units}
            all_units, one_program = units + plain_units, []
            include_dirs = [c_dir, tool.include]
            read = list(src.files)
            if not trap_flags_supported():
                manifest.setdefault("warnings", []).append(
                    "array indices are not checked: the C compiler has no trapping bounds sanitizer")
            elif not cc.checks_undefined_values():
                manifest.setdefault("warnings", []).append(
                    "shift counts and REAL -> integer conversions are not checked: the C compiler has no "
                    "UBSan shift-exponent/float-cast-overflow checks; where MatIEC's C leaves them undefined "
                    "the values are the C compiler's")
        else:
            manifest, all_units, read = _builtin_generate(src, c_dir)
            unit_flags = {u: list(cc.BUILTIN_FLAGS) for u in all_units}
            include_dirs, one_program = [c_dir], all_units      # one program cut into units
        (staging / _cache.MANIFEST_NAME).write_text(json.dumps(manifest, indent=1))
        generated_s = time.perf_counter() - t0
        loud = generated_s > PROGRESS_AFTER_S
        if loud:
            together = cc.program_lines(one_program) if len(one_program) > 1 else None
            slow = [u.name for u in all_units if cc.size_flags(u, together if u in one_program else None)]
            _progress(src, f"C generated by {chosen} in {generated_s:.1f} s ({_c_lines(all_units):,} lines in "
                           f"{len(all_units)} units); compiling with {Path(cc.find_compiler().path).name}"
                           + (f" (-O0 for the large {', '.join(slow)})" if slow else "") + " ...")
        try:
            cc.compile_shared(all_units, staging / _cache.LIBRARY_NAME, include_dirs=include_dirs,
                              unit_flags=unit_flags, cwd=src.root, one_program=one_program, started=started)
        except cc.CCompileError as exc:
            kept = _keep_failed(store, key, staging)
            text = str(exc)
            diags = exc.diagnostics or [f"{src.entry_rel}:1:1: error: {exc}"]
            if kept is not None:    # the staging folder is about to go: point into the kept copy
                diags = [d.replace(str(staging), str(kept)) for d in diags]
                text = text.replace(str(staging), str(kept))
            if chosen == "matiec":
                diags = _explain_matiec_c_errors(diags)
            where = f"kept in {kept / 'c'}" if kept is not None else "not kept"
            raise CompileError(diags + [f"note: the C compiler rejected the C that {chosen} generated from "
                                        f"{src.entry_rel} (the C is {where})", text], chosen) from None
        if loud:
            _progress(src, f"compiled and linked in {time.perf_counter() - t0 - generated_s:.1f} s")
        for o in staging.glob("*.o"):
            o.unlink()
        meta = {"backend": chosen, "backend_version": backend_version, "entry": str(src.entry),
                "sources_read": {str(p): _cache.file_digest(p) for p in read}}
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


# a global's accessor (__GET_GLOBAL_X, declared by the CONFIGURATION's VAR_GLOBAL X) is no call wrapper
_MISSING_GLOBAL = re.compile(r"implicit declaration of function .__GET_GLOBAL_(\w+).")
_MISSING_WRAPPER = re.compile(r"implicit declaration of function .__(?!GET_GLOBAL_)\w+?\d+.")


def _explain_matiec_c_errors(diags: list[str]) -> list[str]:
    """Add what is known about MatIEC defects that surface as C errors."""
    missing = sorted({m[1] for d in diags for m in [_MISSING_GLOBAL.search(d)] if m})
    if missing:
        diags = diags + [
            f"note: no VAR_GLOBAL {', '.join(missing)} in the CONFIGURATION (or no CONFIGURATION at all) for a "
            "VAR_EXTERNAL of that name: iec2c accepts such a VAR_EXTERNAL, but its C then calls __GET_GLOBAL_<name>, "
            "which only the global's declaration provides. Declare the global in the CONFIGURATION built with it."]
    if any(_MISSING_WRAPPER.search(d) for d in diags):
        diags = diags + [
            "note: iec2c used a call wrapper it never defined (MatIEC defect: inside a FUNCTION_BLOCK, a "
            "FUNCTION with VAR_IN_OUT called as an argument of another call, e.g. UDINT_TO_INT(F(Buf, 1)), "
            "gets no wrapper and shifts the numbering of the later ones). Assign such a call's result to a "
            "variable first, then convert it."]
    return diags


def _matiec_unit_flags() -> list[str]:
    """Flags of the units iec2c wrote: an index out of range, a shift count out of range and an undefined
    float -> integer conversion stop the scan (the glue reports kinds 2, 6 and 7); and since
    MatIEC sometimes calls a helper it never declares (nor defines), an implicit `int` declaration, which
    would compile into wrong code, is an error at the ST line."""
    return cc.check_flags() + ["-Werror=implicit-function-declaration"]


def trap_flags_supported() -> bool:
    return bool(cc.check_flags())


def _builtin_generate(src: _sources.Sources, c_dir: Path) -> tuple[dict, list[Path], list[Path]]:
    """Run the builtin compiler; returns (manifest, C units, sources it read)."""
    from . import builtin
    error_cls = getattr(builtin, "BuiltinCompileError", ())
    try:
        out = builtin.compile_to_c(src.entry, src.root, c_dir, search=src.search)
    except Exception as exc:
        if error_cls and isinstance(exc, error_cls):
            diags = [str(d) for d in (getattr(exc, "diagnostics", None) or [])] or str(exc).splitlines()
            raise CompileError(diags, "builtin") from None
        raise _internal(exc, "builtin", src) from exc
    manifest = getattr(out, "manifest", None)
    if isinstance(manifest, (str, Path)):
        manifest = json.loads(Path(manifest).read_text())
    if manifest is None:
        manifest = json.loads((c_dir / "manifest.json").read_text())
    units = getattr(out, "c_files", None) or getattr(out, "c_sources", None) or sorted(c_dir.glob("*.c"))
    units = [Path(u) if Path(u).is_absolute() else c_dir / u for u in units]
    read = [Path(p) for p in (getattr(out, "sources", None) or src.files)]
    return manifest, units, read


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


__all__ = ["build", "BuildResult", "CompileError", "SourcePathError", "InternalCompilerError", "choose_backend", "matiec_available", "builtin_available"]
