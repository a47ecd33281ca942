"""Fixtures of the tests of st_lib's configuration FBs on the testbench (stbench.py)."""

from __future__ import annotations

import pytest

from stbench import Bench


@pytest.fixture
def b() -> Bench:
    """The testbench PLC with one emulated E1100 (node 1), its channel enabled and ready."""
    return Bench(nodes=1)
