"""The compiler backends seen through their protocol (toolchain/backend.py): every backend of the table
fits it, and the driver builds with a backend it has never heard of by name, so it branches on none."""

from __future__ import annotations

from pathlib import Path

import pytest

from linmot_st.plc import Plc
from linmot_st.toolchain import CompileError, build, choose_backend
from linmot_st.toolchain.backend import Backend, Generated
from linmot_st.toolchain.backends import AUTO, BACKENDS, CHOICES, auto_note, choose
from linmot_st.toolchain.testing import write_st

SRC = """
PROGRAM Main
  VAR n : INT; END_VAR
  n := n + 1;
END_PROGRAM
CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    TASK t(INTERVAL := T#1ms, PRIORITY := 0);
    PROGRAM Inst0 WITH t : Main;
  END_RESOURCE
END_CONFIGURATION
"""


class Relabelled:
    """A third backend: the builtin compiler's C under another name and version, with its own note on C
    errors; and, on request, one more C unit that does not compile."""

    name = "relabelled"
    found_note, missing_note = "always here", "never missing"

    def __init__(self, broken_unit: bool = False):
        self.inner = BACKENDS["builtin"]
        self.broken_unit = broken_unit
        self.explained: list[list[str]] = []

    def missing(self):
        return None

    def available(self):
        return True

    def version(self):
        return "relabelled-1"

    def generator_files(self):
        return self.inner.generator_files()

    def flags(self):
        return self.inner.flags()

    def generate(self, src, c_dir: Path, version: str) -> Generated:
        gen = self.inner.generate(src, c_dir, version)
        gen.manifest["backend"] = self.name
        if self.broken_unit:
            unit = c_dir / "broken.c"
            unit.write_text("int broken(void) { return undeclared_thing; }\n")
            gen.units.append(unit)
            gen.unit_flags[unit] = []
        return gen

    def explain_c_errors(self, diagnostics):
        self.explained.append(diagnostics)
        return diagnostics + ["note: explained by the relabelled backend"]


def test_every_backend_of_the_table_fits_the_protocol():
    assert CHOICES == (AUTO, *BACKENDS) and list(BACKENDS) == ["matiec", "builtin"]
    for name, backend in BACKENDS.items():
        assert isinstance(backend, Backend) and backend.name == name
        assert backend.available() == (backend.missing() is None)
        if backend.available():
            assert backend.version() and all(p.is_file() for p in backend.generator_files())


def test_the_driver_builds_with_any_backend_of_the_table(tmp_path, monkeypatch):
    relabelled = Relabelled()
    monkeypatch.setitem(BACKENDS, relabelled.name, relabelled)
    entry = write_st(SRC, tmp_path / "p")
    res = build(entry, backend="relabelled", cache_dir=tmp_path / "cache")
    assert (res.backend, res.backend_version, res.cached) == ("relabelled", "relabelled-1", False)
    plc = Plc(res)
    plc.step(3)
    assert plc["CONFIG0.RES0.INST0.N"] == 3
    # its own cache entry, apart from the builtin's build of the same source
    assert build(entry, backend="relabelled", cache_dir=tmp_path / "cache").cached
    builtin = build(entry, backend="builtin", cache_dir=tmp_path / "cache")
    assert not builtin.cached and builtin.library.parent != res.library.parent


def test_c_errors_are_explained_by_the_backend_that_made_the_c(tmp_path, monkeypatch):
    relabelled = Relabelled(broken_unit=True)
    monkeypatch.setitem(BACKENDS, relabelled.name, relabelled)
    with pytest.raises(CompileError) as info:
        build(write_st(SRC, tmp_path / "p"), backend="relabelled", cache_dir=tmp_path / "cache")
    assert len(relabelled.explained) == 1 and "undeclared_thing" in " ".join(relabelled.explained[0])
    assert "note: explained by the relabelled backend" in info.value.diagnostics
    assert info.value.backend == "relabelled"


def test_auto_takes_the_first_backend_that_can_run(monkeypatch):
    monkeypatch.setattr(BACKENDS["matiec"], "missing", lambda: "no iec2c here")
    assert choose(AUTO) is BACKENDS["builtin"] and choose_backend("auto") == "builtin"
    assert auto_note(BACKENDS["builtin"]) == "iec2c not found"
    monkeypatch.setattr(BACKENDS["matiec"], "missing", lambda: None)
    assert choose(AUTO) is BACKENDS["matiec"] and auto_note(BACKENDS["matiec"]) == "iec2c found"


def test_a_backend_that_cannot_run_says_why_at_the_entry(tmp_path, monkeypatch):
    monkeypatch.setattr(BACKENDS["builtin"], "missing", lambda: "the builtin compiler is not available: test")
    entry = write_st(SRC, tmp_path / "p")
    with pytest.raises(CompileError) as info:
        build(entry, backend="builtin", cache_dir=tmp_path / "cache")
    assert info.value.diagnostics == [f"{entry}:1:1: error: the builtin compiler is not available: test"]
