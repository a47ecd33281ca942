"""build(): entry resolution, include root, the content cache, compile errors, backend choice."""

from __future__ import annotations

import json
import os
import re
import time
from pathlib import Path

import pytest

from linmot_st.plc import Plc
from linmot_st.toolchain import CompileError, build, choose_backend, matiec_available
from linmot_st.toolchain.sources import collect, find_includes
from linmot_st.toolchain.testing import BACKEND_PARAMS, build_text, requires_matiec, write_st

LIBRARY = """
TYPE
  T_Pair : ARRAY[1..2] OF INT;
END_TYPE
{#include "st_lib/more.st"}
"""
MORE = """
FUNCTION Twice : INT
  VAR_INPUT
    V : INT;
  END_VAR
  Twice := V * {factor};
END_FUNCTION
"""
PROJECT = """
{#include "st_lib/linmot.st"}
PROGRAM Main
  VAR
    P : T_Pair;
    N : INT;
  END_VAR
  N := N + 1;
  P[1] := Twice(V := N);
END_PROGRAM

CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK T1(INTERVAL := T#5ms, PRIORITY := 0);
    PROGRAM Inst0 WITH T1 : Main;
  END_RESOURCE
END_CONFIGURATION
"""


def make_tree(root: Path, factor: int = 2) -> Path:
    """root/st_lib/linmot.st (the include-root marker) including st_lib/more.st; root/proj/plc.st."""
    write_st(LIBRARY, root / "st_lib", "linmot.st")
    write_st(MORE.replace("{factor}", str(factor)), root / "st_lib", "more.st")
    write_st(PROJECT, root / "proj", "plc.st")
    return root / "proj"


def test_sources_of_a_project_folder(tmp_path):
    proj = make_tree(tmp_path)
    src = collect(proj)
    assert src.entry == (proj / "plc.st").resolve()
    assert src.root == tmp_path.resolve()
    assert [p.name for p in src.files] == ["plc.st", "linmot.st", "more.st"]
    assert src.entry_rel == "proj/plc.st"


def test_includes_in_comments_are_ignored():
    assert find_includes('(* {#include "a.st"} *)\n{#include "b.st"}\n{ #include  "c.st" }') == ["b.st", "c.st"]


def test_bad_paths_are_clear_errors(tmp_path):
    with pytest.raises(CompileError, match="needs an entry file plc.st"):
        build(tmp_path, backend="matiec" if matiec_available() else "builtin")
    with pytest.raises(CompileError, match="no such file"):
        build(tmp_path / "nope.st")


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_project_build_cache_and_invalidation(backend, tmp_path):
    proj = make_tree(tmp_path / "tree")
    cache = tmp_path / "cache"
    first = build(proj, backend=backend, cache_dir=cache)
    assert first.backend == backend and not first.cached
    assert first.root == (tmp_path / "tree").resolve()
    plc = Plc(first)
    plc.step(3)
    assert plc["INST0.P[1]"] == 6 and plc.tick_ns == 5_000_000

    t0 = time.perf_counter()
    again = build(proj, backend=backend, cache_dir=cache)
    elapsed = time.perf_counter() - t0
    assert again.cached and again.library == first.library
    assert elapsed < 2.0   # the target (well under 0.2 s) is printed by `make bench`, not asserted

    # an included file changed: rebuilt, and the new code runs
    write_st(MORE.replace("{factor}", "3"), tmp_path / "tree" / "st_lib", "more.st")
    changed = build(proj, backend=backend, cache_dir=cache)
    assert not changed.cached and changed.library != first.library
    plc = Plc(changed)
    plc.step(3)
    assert plc["INST0.P[1]"] == 9


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_out_folder_gets_library_manifest_and_c(backend, tmp_path):
    res = build(make_tree(tmp_path / "tree"), backend=backend, cache_dir=tmp_path / "cache", out=tmp_path / "out")
    assert res.library.parent == tmp_path / "out" and res.library.is_file()
    manifest = json.loads(res.manifest.read_text())
    assert manifest["schema"] == 1 and manifest["backend"] == backend
    assert any(r["path"] == "CONFIG0.RES0.INST0" for r in manifest["roots"])
    assert list((tmp_path / "out" / "c").glob("*.c"))
    assert Plc(tmp_path / "out").roots()


DIAGNOSTIC = re.compile(r"^(?P<file>[^:]+):(?P<line>\d+):(?P<col>\d+): error: .+")


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_syntax_error_is_a_compile_error_with_position(backend, tmp_path):
    src = """
    PROGRAM Main
      VAR
        X : INT;
      END_VAR
      X := X + ;
    END_PROGRAM
    """
    with pytest.raises(CompileError) as info:
        build_text(src, tmp_path, backend)
    first = info.value.diagnostics[0]
    m = DIAGNOSTIC.match(first)
    assert m, first
    assert m["file"].endswith("prog.st") and m["line"] == "5"


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_type_error_is_a_compile_error(backend, tmp_path):
    src = """
    PROGRAM Main
      VAR
        X : INT;
        B : BYTE;
      END_VAR
      X := B + 1;
    END_PROGRAM
    """
    with pytest.raises(CompileError) as info:
        build_text(src, tmp_path, backend)
    assert any(DIAGNOSTIC.match(d) and ":6:" in d for d in info.value.diagnostics), info.value.diagnostics


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_error_in_an_included_file_names_that_file(backend, tmp_path):
    write_st(LIBRARY, tmp_path / "st_lib", "linmot.st")
    write_st(MORE.replace("{factor}", "2 +"), tmp_path / "st_lib", "more.st")
    write_st(PROJECT, tmp_path / "proj", "plc.st")
    with pytest.raises(CompileError) as info:
        build(tmp_path / "proj", backend=backend, cache_dir=tmp_path / "cache")
    assert any(d.startswith("st_lib/more.st:") and ": error: " in d for d in info.value.diagnostics), \
        info.value.diagnostics


def _fake_iec2c(tmp_path, monkeypatch, script: str) -> None:
    """A stand-in iec2c (a shell script) with an empty library folder, found through IEC2C."""
    fake = tmp_path / "matiec" / "iec2c"
    (tmp_path / "matiec" / "lib" / "C").mkdir(parents=True)
    (tmp_path / "matiec" / "lib" / "ieclib.txt").write_text("")
    fake.write_text("#!/bin/sh\n" + script)
    fake.chmod(0o755)
    monkeypatch.setenv("IEC2C", str(fake))
    monkeypatch.delenv("MATIEC_HOME", raising=False)


def test_iec2c_crash_is_a_compile_error(tmp_path, monkeypatch):
    """MatIEC segfaults (exit 139) after some syntax errors: any non-zero exit is a failure, with its messages.
    A stand-in iec2c that prints a message and dies of SIGSEGV checks this without MatIEC."""
    _fake_iec2c(tmp_path, monkeypatch, 'echo "prog.st:2-5..2-7: error: invalid external variable declaration." >&2\n'
                                       'kill -SEGV $$\n')
    with pytest.raises(CompileError) as info:
        build_text("PROGRAM Main\nEND_PROGRAM\n", tmp_path, "matiec")
    diags = info.value.diagnostics
    assert diags[0] == "prog.st:2:5: error: invalid external variable declaration."
    assert any(DIAGNOSTIC.match(d) and "iec2c crashed (SIGSEGV)" in d for d in diags), diags


@pytest.mark.parametrize("signal_name, wording", [
    ("TERM", "iec2c was stopped from outside (SIGTERM)"),
    ("KILL", "iec2c was killed (SIGKILL): out of memory, or killed from outside"),
    ("ABRT", "iec2c aborted (SIGABRT)"),
])
def test_iec2c_signals_are_worded_by_signal(tmp_path, monkeypatch, signal_name, wording):
    """Only a segfault is MatIEC's known reaction to bad syntax; a killed iec2c is not called a crash."""
    _fake_iec2c(tmp_path, monkeypatch, f"kill -{signal_name} $$\n")
    with pytest.raises(CompileError) as info:
        build_text("PROGRAM Main\nEND_PROGRAM\n", tmp_path, "matiec")
    diags = info.value.diagnostics
    assert any(DIAGNOSTIC.match(d) and wording in d for d in diags), diags
    assert not any("syntax errors" in d for d in diags), diags


def test_iec2c_has_a_time_limit(tmp_path, monkeypatch):
    """iec2c runs at most LINMOT_ST_IEC2C_TIMEOUT seconds (120 by default): MatIEC takes minutes on huge arrays."""
    _fake_iec2c(tmp_path, monkeypatch, '[ "$1" = "-h" ] && exit 0\nexec sleep 30\n')
    monkeypatch.setenv("LINMOT_ST_IEC2C_TIMEOUT", "0.5")
    t0 = time.perf_counter()
    with pytest.raises(CompileError) as info:
        build_text("PROGRAM Main\nEND_PROGRAM\n", tmp_path, "matiec")
    assert time.perf_counter() - t0 < 10
    assert DIAGNOSTIC.match(info.value.diagnostics[0])
    assert "iec2c did not finish within 0.5 s" in info.value.diagnostics[0]
    assert "LINMOT_ST_IEC2C_TIMEOUT" in info.value.diagnostics[0]
    monkeypatch.setenv("LINMOT_ST_IEC2C_TIMEOUT", "soon")
    with pytest.raises(CompileError, match="LINMOT_ST_IEC2C_TIMEOUT='soon': expected a number of seconds"):
        build_text("PROGRAM Main\nEND_PROGRAM\n", tmp_path, "matiec")


def test_default_iec2c_time_limit(monkeypatch):
    from linmot_st.toolchain import matiec
    monkeypatch.delenv("LINMOT_ST_IEC2C_TIMEOUT", raising=False)
    assert matiec.timeout_s() == 120
    monkeypatch.setenv("LINMOT_ST_IEC2C_TIMEOUT", "0")
    assert matiec.timeout_s() is None


def test_auto_picks_builtin_without_iec2c(monkeypatch, tmp_path):
    monkeypatch.setenv("IEC2C", str(tmp_path / "no-iec2c"))
    monkeypatch.delenv("MATIEC_HOME", raising=False)
    monkeypatch.setenv("PATH", os.pathsep.join(p for p in os.environ["PATH"].split(os.pathsep)
                                               if not (Path(p) / "iec2c").exists()))
    assert choose_backend("auto") == "builtin"
    with pytest.raises(CompileError, match="iec2c not found"):
        build(write_st("PROGRAM Main\nEND_PROGRAM\n", tmp_path), backend="matiec", cache_dir=tmp_path / "c")


@requires_matiec
def test_auto_picks_matiec_with_iec2c():
    assert choose_backend("auto") == "matiec"


def test_unknown_backend():
    with pytest.raises(ValueError, match="unknown backend"):
        choose_backend("gcc")


@requires_matiec
def test_matiec_missing_call_wrapper_is_an_error_at_the_st_line(tmp_path):
    """A MatIEC defect: a FUNCTION with VAR_IN_OUT called as the argument of another call inside an FB gets
    no C wrapper. With an implicit declaration the C would compile and misbehave; it must not build."""
    src = """
    TYPE
      T_B : ARRAY[0..3] OF BYTE;
    END_TYPE
    FUNCTION F_Get : UDINT
      VAR_IN_OUT
        B : T_B;
      END_VAR
      VAR_INPUT
        Ofs : INT;
      END_VAR
      F_Get := BYTE_TO_UDINT(B[Ofs]);
    END_FUNCTION
    FUNCTION_BLOCK Fb
      VAR
        Buf : T_B;
        W : UDINT;
        K : INT;
      END_VAR
      K := UDINT_TO_INT(F_Get(Buf, 1));
      W := F_Get(Buf, 2);
    END_FUNCTION_BLOCK
    """
    with pytest.raises(CompileError) as info:
        build_text(src, tmp_path, "matiec")
    diags = info.value.diagnostics
    assert any(DIAGNOSTIC.match(d) and ("prog.st:19:" in d or "prog.st:20:" in d) for d in diags), diags
    assert any("MatIEC defect" in d for d in diags)


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_named_configuration_and_two_tasks(backend, tmp_path):
    """Any CONFIGURATION/RESOURCE names; the tick is the GCD of the task intervals and each task runs at
    its own multiple of it, from the first scan."""
    src = """
    PROGRAM Counter
      VAR
        N : INT;
      END_VAR
      N := N + 1;
    END_PROGRAM

    CONFIGURATION Plant
      VAR_GLOBAL
        G : INT := 3;
      END_VAR
      RESOURCE Cpu ON PLC
        TASK Fast(INTERVAL := T#2ms, PRIORITY := 0);
        TASK Slow(INTERVAL := T#6ms, PRIORITY := 1);
        PROGRAM A WITH Fast : Counter;
        PROGRAM B WITH Slow : Counter;
      END_RESOURCE
    END_CONFIGURATION
    """
    plc = Plc(build_text(src, tmp_path, backend))
    assert plc.tick_ns == 2_000_000
    assert set(plc.roots()) >= {"PLANT.CPU.A", "PLANT.CPU.B", "PLANT.G"}
    plc.step(7)
    assert (plc["PLANT.CPU.A.N"], plc["B.N"], plc["G"]) == (7, 3, 3)


def test_cache_commit_keeps_a_valid_entry_a_concurrent_builder_made(tmp_path):
    from linmot_st.toolchain.cache import LIBRARY_NAME, MANIFEST_NAME, Cache
    cache = Cache(tmp_path)
    src = tmp_path / "a.st"
    src.write_text("x")
    meta = {"sources_read": {str(src): __import__("hashlib").sha256(b"x").hexdigest()}}
    first = cache.staging()
    (first / LIBRARY_NAME).write_text("first")
    (first / MANIFEST_NAME).write_text("{}")
    entry = cache.commit("ab" * 32, first, meta)
    second = cache.staging()
    (second / LIBRARY_NAME).write_text("second")
    (second / MANIFEST_NAME).write_text("{}")
    assert cache.commit("ab" * 32, second, meta) == entry
    assert (entry / LIBRARY_NAME).read_text() == "first" and not second.exists()
    src.write_text("changed")                       # now the entry is stale: a new commit replaces it
    assert cache.lookup("ab" * 32) is None
    third = cache.staging()
    (third / LIBRARY_NAME).write_text("third")
    (third / MANIFEST_NAME).write_text("{}")
    cache.commit("ab" * 32, third, {"sources_read": {}})
    assert (entry / LIBRARY_NAME).read_text() == "third"


def test_failed_c_is_kept_for_reading_and_bounded(tmp_path, monkeypatch):
    """When gcc rejects generated C, the C stays in <cache>/failed-<key>/ (the last FAILED_KEPT builds) and
    the diagnostics point there, not into a deleted staging folder; a note names the ST entry."""
    import linmot_st.toolchain as toolchain
    from linmot_st.toolchain.backend import Generated

    def broken_generate(src, c_dir, version):
        unit = c_dir / "broken.c"
        unit.write_text("int broken(void) { return undeclared_thing; }\n")
        return Generated({"schema": 1}, [unit], {unit: []}, [c_dir], [unit], list(src.files))

    monkeypatch.setattr(toolchain.BACKENDS["builtin"], "generate", broken_generate)
    cache = tmp_path / "cache"
    for i in range(toolchain.FAILED_KEPT + 2):
        entry = write_st(f"PROGRAM Main\n  VAR i : INT; END_VAR\n  i := {i};\nEND_PROGRAM\n", tmp_path / f"p{i}")
        with pytest.raises(CompileError) as info:
            build(entry, backend="builtin", cache_dir=cache)
        diags = info.value.diagnostics
        first = DIAGNOSTIC.match(diags[0])
        assert first and "undeclared_thing" in diags[0], diags
        kept = Path(first["file"])
        assert kept.is_file() and kept.parent.parent.name.startswith("failed-") and kept.parent.parent.parent == cache
        assert any(d.startswith("note: the C compiler rejected the C that builtin generated from ")
                   and str(entry) in d and str(kept.parent) in d for d in diags), diags
        assert not list(cache.glob("staging-*"))
    assert len(list(cache.glob("failed-*"))) == toolchain.FAILED_KEPT


def test_cache_folder_outside_a_library_tree(tmp_path, monkeypatch):
    """build/cache under a library tree (`make clean` removes it); the user's cache folder for a file built
    from a folder that holds no library, never a build/ folder wherever the command happens to run."""
    from linmot_st.toolchain.cache import default_dir
    monkeypatch.delenv("LINMOT_ST_CACHE", raising=False)
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "xdg"))
    monkeypatch.chdir(tmp_path)
    res = build(write_st("PROGRAM Main\n  VAR i : INT; END_VAR\n  i := 1;\nEND_PROGRAM\n", tmp_path / "loose"),
                backend="builtin")
    assert res.library.is_relative_to(tmp_path / "xdg" / "linmot-st")
    assert not (tmp_path / "build").exists()
    monkeypatch.delenv("XDG_CACHE_HOME")
    assert default_dir(tmp_path, in_tree=False) == Path.home() / ".cache" / "linmot-st"
    tree = make_tree(tmp_path / "tree")
    assert build(tree, backend="builtin").library.is_relative_to(tmp_path / "tree" / "build" / "cache")
    monkeypatch.setenv("LINMOT_ST_CACHE", str(tmp_path / "mine"))
    assert default_dir(tmp_path, in_tree=False) == tmp_path / "mine"
