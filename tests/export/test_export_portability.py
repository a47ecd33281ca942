"""A second opinion on portability: the exported library (`linmot-st export st`) read by independent IEC
61131-3 parsers from PyPI, blark (the TwinCAT dialect) and tree-sitter-iec61131-3-st (docs/import.md,
"Other parsers"). Each must read every type and POU that the builtin compiler reads, with no error.

blark's parser is Earley and slow (about a minute of CPU for the 150 kB export), so it reads the export one
source file's section at a time, one test each, which pytest-xdist spreads over its workers; and a section
blark has read before (same text, same blark version, same expected counts) is not read again: the verdict
is kept in pytest's cache (.pytest_cache, which `make clean` removes)."""

from __future__ import annotations

import hashlib
import re
from collections import Counter

import pytest

from linmot_st import resources
from linmot_st.toolchain.sources import collect

blark_parse = pytest.importorskip("blark.parse", reason="blark is a test dependency (pip install -e '.[test]')")
tree_sitter = pytest.importorskip("tree_sitter", reason="tree-sitter is a test dependency")
ts_st = pytest.importorskip("tree_sitter_iec61131_3_st", reason="tree-sitter-iec61131-3-st is a test dependency")

TREE = resources.library_tree()
SOURCES = [f.relative_to(TREE).as_posix() for f in collect(TREE / "st_lib" / "linmot.st").files[1:]]
KIND = {"FUNCTION": "Function", "FUNCTION_BLOCK": "FunctionBlock", "PROGRAM": "Program"}
_export = {}


def exported():
    if not _export:
        from linmot_st.export.st import export_st
        _export["st"] = export_st()
    return _export["st"]


def section(name: str) -> str:
    """The text of one source file inside the export, between its marker comments."""
    text = exported().text
    m = re.search(rf"^\(\* ==== {re.escape(name)} ==== \*\)\n(.*?)^\(\* ==== end of {re.escape(name)} ==== \*\)$",
                  text, re.S | re.M)
    assert m, f"{name} has no section in the export"
    return m[1]


def expected_counts(name: str) -> Counter:
    lib = exported().library
    c = Counter("DataTypeDeclaration" for t in lib.types if t.decl.pos.file == name)
    c.update(KIND[p.pou.kind] for p in lib.pous if p.pou.pos.file == name)
    return c


def blark_counts(text: str, name: str) -> Counter:
    res = blark_parse.parse_source_code(text, fn=name)
    assert res.exception is None, f"blark rejects {name}: {res.exception}"
    return Counter(type(item).__name__ for item in res.transform().items)


def tree_sitter_counts(text: str) -> tuple[Counter, list[str]]:
    parser = tree_sitter.Parser(tree_sitter.Language(ts_st.language()))
    source = text.encode("latin-1")
    root = parser.parse(source).root_node
    errors = []

    def walk(node):
        if node.type == "ERROR" or node.is_missing:
            line = source.split(b"\n")[node.start_point[0]].decode("latin-1")
            errors.append(f"line {node.start_point[0] + 1}: {node.type}: {line.strip()[:80]}")
            return
        for child in node.children:
            walk(child)

    walk(root)
    return Counter(c.type for c in root.children), errors


@pytest.mark.slow
@pytest.mark.parametrize("name", SOURCES)
def test_blark_reads_every_type_and_pou_of_the_export(name, request):
    from importlib.metadata import version
    text, expected = section(name), expected_counts(name)
    key = hashlib.sha256(repr((text, version("blark"), sorted(expected.items()))).encode()).hexdigest()
    cache = getattr(request.config, "cache", None)     # None with -p no:cacheprovider
    if cache is not None and cache.get(f"linmot-st/blark/{key}", None) == "read":
        return                                   # this very text was read by this blark before
    assert blark_counts(text, name) == expected
    if cache is not None:
        cache.set(f"linmot-st/blark/{key}", "read")


def test_the_sections_cover_the_whole_library():
    lib = exported().library
    total = sum((expected_counts(n) for n in SOURCES), Counter())
    assert total["DataTypeDeclaration"] == len(lib.types) and sum(total.values()) == len(lib.types) + len(lib.pous)


def test_tree_sitter_reads_the_exported_library_without_an_error():
    c = exported().library.counts
    kinds, errors = tree_sitter_counts(exported().text)
    assert errors == []
    assert (kinds["type_declaration"], kinds["function_declaration"], kinds["function_block_declaration"]) == (
        c["types"], c["functions"], c["function_blocks"])


def test_tree_sitter_reads_the_st_assertion_library():
    assert tree_sitter_counts((TREE / "st_lib" / "stunit" / "stunit.st").read_text())[1] == []
