"""The import-linter contracts of pyproject.toml (docs/architecture.md, "Layers"): they hold, and the check
can fail (the same contract with two layers swapped is broken by the imports the package has)."""

from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from linmot_st import resources

PYPROJECT = resources.CHECKOUT / "pyproject.toml"
LINT = shutil.which("lint-imports", path=str(Path(sys.executable).parent))
pytestmark = pytest.mark.skipif(LINT is None or not PYPROJECT.is_file(),
                                reason="needs a checkout and import-linter (pip install -e '.[test]')")


def lint(config: Path) -> subprocess.CompletedProcess:
    return subprocess.run([LINT, "--no-cache", str(config)], capture_output=True, text=True,
                          cwd=resources.CHECKOUT, timeout=300)


def test_the_layers_and_the_dev_only_contracts_are_kept():
    proc = lint(PYPROJECT)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "Contracts: 2 kept, 0 broken." in proc.stdout


def test_an_upward_import_breaks_the_contract(tmp_path):
    """jobs import plc (the commissioning job runs the PLC): with plc put above jobs, that is an upward
    import, which lint-imports reports."""
    lines = PYPROJECT.read_text().splitlines(keepends=True)
    jobs, plc = lines.index('  "jobs",\n'), lines.index('  "plc",\n')
    assert jobs < plc                                   # jobs above plc in the contract
    lines[jobs], lines[plc] = lines[plc], lines[jobs]
    (tmp_path / "pyproject.toml").write_text("".join(lines))
    proc = lint(tmp_path / "pyproject.toml")
    assert proc.returncode == 1, proc.stdout
    assert "linmot_st.jobs is not allowed to import linmot_st.plc" in proc.stdout, proc.stdout
