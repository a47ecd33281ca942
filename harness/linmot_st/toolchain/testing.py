"""Helpers for tests that build ST: which backends are here, and building a program given as text.

    from linmot_st.toolchain.testing import BACKEND_PARAMS, build_text
    @pytest.mark.parametrize("backend", BACKEND_PARAMS)
    def test_x(backend, tmp_path): plc = Plc(build_text(SRC, tmp_path, backend))
"""

from __future__ import annotations

import textwrap
from pathlib import Path

import pytest

from . import BuildResult, build, builtin_available, matiec_available

MATIEC_MISSING = ("MatIEC's iec2c not found (set IEC2C or MATIEC_HOME, or put iec2c on PATH); "
                  "CI has none, so these tests run only where it is installed")
BUILTIN_MISSING = "the builtin ST compiler (linmot_st.toolchain.builtin) is not available yet"

BACKEND_PARAMS = [
    pytest.param("matiec", marks=[pytest.mark.matiec,
                                  pytest.mark.skipif(not matiec_available(), reason=MATIEC_MISSING)]),
    pytest.param("builtin", marks=pytest.mark.skipif(not builtin_available(), reason=BUILTIN_MISSING)),
]

requires_matiec = pytest.mark.skipif(not matiec_available(), reason=MATIEC_MISSING)


def write_st(text: str, folder: Path, name: str = "prog.st") -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / name
    path.write_text(textwrap.dedent(text).lstrip("\n"))
    return path


def build_text(text: str, folder: Path, backend: str, name: str = "prog.st", **kw) -> BuildResult:
    kw.setdefault("cache_dir", folder / ".cache")
    return build(write_st(text, folder, name), backend=backend, **kw)
