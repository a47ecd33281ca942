"""No import cycles in linmot_st (issue 19): a module never imports, directly or through others, a module
that imports it, not even inside a function (a lazy import that hides a cycle counts). And each module of
the packages that had such cycles imports on its own in a fresh interpreter."""

from __future__ import annotations

import subprocess
import sys

import grimp
import pytest

PACKAGE = "linmot_st"
ALONE = ("linmot_st.pvl", "linmot_st.plctest", "linmot_st.toolchain")   # each module imported on its own


def build_graph():
    return grimp.build_graph(PACKAGE, cache_dir=None)      # no .grimp_cache folder in the tree


@pytest.fixture(scope="module")
def graph():
    return build_graph()


def cycles(graph) -> list[tuple[str, ...]]:
    """One chain per import edge that closes a cycle: (module, what it imports, ..., module)."""
    found = []
    for module in sorted(graph.modules):
        for imported in sorted(graph.find_modules_directly_imported_by(module)):
            back = graph.find_shortest_chain(importer=imported, imported=module)
            if back:
                found.append((module, *back))
    return found


def test_no_import_cycle(graph):
    assert cycles(graph) == []


def test_a_cycle_is_found():
    """The check itself: the two cycles of issue 19, put back into a graph of the package, are reported."""
    bad = build_graph()
    bad.add_import(importer="linmot_st.pvl.to_st", imported="linmot_st.pvl.cli")
    bad.add_import(importer="linmot_st.plctest.stunit", imported="linmot_st.plctest.plugin")
    found = {chain[:2] for chain in cycles(bad)}
    assert ("linmot_st.pvl.to_st", "linmot_st.pvl.cli") in found
    assert ("linmot_st.plctest.stunit", "linmot_st.plctest.plugin") in found


def modules_alone(graph) -> list[str]:
    return sorted(m for m in graph.modules if any(m == p or m.startswith(p + ".") for p in ALONE)
                  and not m.startswith("linmot_st.toolchain.builtin."))    # the compiler's own modules: not touched


@pytest.mark.parametrize("package", ALONE)
def test_each_module_imports_alone(graph, package):
    """`python -c "import M"` for every module of the package, each in a fresh interpreter (the order of
    a test session's imports cannot hide a module that only imports after another)."""
    failed = {}
    for module in [m for m in modules_alone(graph) if m == package or m.startswith(package + ".")]:
        proc = subprocess.run([sys.executable, "-c", f"import {module}"], capture_output=True, text=True)
        if proc.returncode != 0:
            failed[module] = proc.stderr.strip().splitlines()[-1]
    assert failed == {}
