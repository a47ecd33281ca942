"""Every FB call of the library, plc_project and the user example binds each VAR_IN_OUT of the FB.

CODESYS and TwinCAT reject a call that leaves an in-out unbound (IEC 61131-3: an in-out is a reference to the
caller's variable); MatIEC and the builtin compiler accept it and let the FB work on its instance's own copy
(plc_project called FB_LmCamIn without its mailbox until this test). So the check is ours: the builtin
compiler's checker binds each call's arguments, and this test reads its result."""

from __future__ import annotations

from pathlib import Path

import pytest

from linmot_st.resources import library_tree
from linmot_st.toolchain.builtin import ast as A
from linmot_st.toolchain.builtin.checker import Checker
from linmot_st.toolchain.builtin.loader import load
from linmot_st.toolchain.builtin.param_refs import _walk

ROOT = library_tree()
REPO = Path(__file__).resolve().parents[2]
# (entry file, the root its includes are read under, the folders searched first), as `linmot-st build` reads them
ENTRIES = [(ROOT / "st_lib" / "linmot.st", ROOT, []), (ROOT / "plc_project" / "plc.st", ROOT, []),
           (REPO / "examples" / "user_project" / "plc.st", REPO / "examples" / "user_project", [ROOT])]


def unbound_in_outs(entry: Path, root: Path, search: list[Path]) -> list[str]:
    elements, _, names = load(entry, root, search)
    prog = Checker().check(elements, names)
    found = []
    for pou in prog.pous:
        if pou.ast is None:
            continue
        for node in _walk(pou.ast.body):
            if isinstance(node, A.Call) and isinstance(node.target, tuple) and node.target[1] is not None:
                fb, _, bound = node.target
                keys = {v.key for v, _ in bound}
                found += [f"{node.pos}: {pou.name} calls {node.name} ({fb.name}) without {v.name}"
                          for v in fb.params if v.kind == "VAR_IN_OUT" and v.key not in keys]
    return found


@pytest.mark.parametrize("entry,root,search", ENTRIES, ids=["st_lib", "plc_project", "user_project"])
def test_every_fb_call_binds_every_in_out(entry, root, search):
    assert unbound_in_outs(entry, root, search) == []


def test_an_unbound_in_out_is_found(tmp_path):
    src = tmp_path / "p.st"
    src.write_text("FUNCTION_BLOCK fb_a\n  VAR_IN_OUT x : INT; y : INT; END_VAR\n  x := y;\nEND_FUNCTION_BLOCK\n"
                   "PROGRAM prog_a\n  VAR a : fb_a; v : INT; END_VAR\n  a(x := v);\nEND_PROGRAM\n")
    found = unbound_in_outs(src, tmp_path, [])
    assert len(found) == 1 and "without y" in found[0]
