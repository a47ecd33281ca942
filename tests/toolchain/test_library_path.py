"""The library on the include path: a project outside any library tree includes st_lib/ and plc_project/
from the library tree (docs/toolchain.md, "The library on the include path")."""

from __future__ import annotations

import json

import pytest

from linmot_st import resources
from linmot_st.plc import Plc
from linmot_st.toolchain import CompileError, build
from linmot_st.toolchain.sources import collect
from linmot_st.toolchain.testing import BACKEND_PARAMS, write_st

STATION = """
{#include "st_lib/linmot.st"}
{#include "src/station.st"}
CONFIGURATION Config0
  RESOURCE Res0 ON PLC
    VAR_GLOBAL
      CAN0 : T_CanMailbox;
    END_VAR
    TASK Cyclic(INTERVAL := T#1ms, PRIORITY := 0);
    PROGRAM Main WITH Cyclic : Station;
  END_RESOURCE
END_CONFIGURATION
"""

PROGRAM = """
PROGRAM Station
  VAR_EXTERNAL
    CAN0 : T_CanMailbox;
  END_VAR
  VAR
    Ax : T_LmAxis;
    Ch : FB_LmChannel;
  END_VAR
  Ch(Enable := TRUE, NodeId := 3, Axis := Ax, Box := CAN0);
END_PROGRAM
"""


def user_project(folder):
    write_st(PROGRAM, folder / "src", "station.st")
    return write_st(STATION, folder, "plc.st")


def test_a_root_without_the_library_searches_the_library_tree(tmp_path, monkeypatch):
    user_project(tmp_path / "proj")
    monkeypatch.chdir(tmp_path / "proj")           # no library tree above it: the root is the cwd
    src = collect("plc.st")
    tree = resources.library_tree()
    assert src.root == (tmp_path / "proj").resolve() and src.search == [tree]
    assert not src.missing
    assert tree / "st_lib" / "types" / "can.st" in src.files
    assert (tmp_path / "proj" / "src" / "station.st").resolve() in src.files


def test_a_library_tree_is_its_own_include_root():
    src = collect(resources.library_tree() / "plc_project")
    assert src.root == resources.library_tree() and src.search == []


def test_only_the_library_folders_are_looked_up_in_the_tree(tmp_path):
    """docs/ is in the checkout beside st_lib/, but a project's `docs/...` include is its own."""
    entry = write_st('{#include "docs/architecture.md"}\n', tmp_path, "plc.st")
    assert collect(entry, root=tmp_path).missing == ["docs/architecture.md"]


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_a_user_project_anywhere_builds_and_runs_with_the_library(tmp_path, backend):
    res = build(user_project(tmp_path / "proj"), backend=backend, cache_dir=tmp_path / "cache", root=tmp_path / "proj")
    plc = Plc(res)
    plc.step(1)
    assert plc["MAIN.CH.NODEID"] == 3
    pous = {name: info["file"] for name, info in json.loads(res.manifest.read_text())["pous"].items()}
    assert pous["STATION"] == "src/station.st"
    assert pous["FB_LMCHANNEL"] == "st_lib/channel/channel.st"      # named by its include path, as iec2c does


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_an_explicit_root_resolves_the_project_includes(tmp_path, backend):
    """The entry may sit in another folder (a generated one) when the caller names the root."""
    user_project(tmp_path / "proj")
    entry = write_st('{#include "plc.st"}\n', tmp_path / "elsewhere", "entry.st")
    with pytest.raises(CompileError, match="plc.st"):
        build(entry, backend=backend, cache_dir=tmp_path / "cache", root=tmp_path / "elsewhere")
    res = build(entry, backend=backend, cache_dir=tmp_path / "cache", root=tmp_path / "proj")
    plc = Plc(res)
    plc.step(1)
    assert plc["MAIN.CH.NODEID"] == 3
