"""Where the repository's files are, for tests in any folder of tests/ (importable through the pytest
settings' pythonpath, so no test counts its own depth with Path(__file__).parents[n])."""

from __future__ import annotations

from pathlib import Path

TESTS = Path(__file__).resolve().parents[1]
REPO = TESTS.parent
EXAMPLES = REPO / "examples"
VECTORS = TESTS / "vectors"                  # the shared test vectors (ST and Python ends of one protocol)
DATA = TESTS / "data"                        # input files of single tests
ST_BENCHES = TESTS / "st_lib"                # the ST testbenches and their drivers (stbench.py, motionbench.py)
CONFORMANCE_CASES = TESTS / "toolchain" / "conformance" / "cases"
