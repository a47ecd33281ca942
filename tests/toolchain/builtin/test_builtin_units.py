"""The builtin backend's C cut into translation units (toolchain/builtin/units.py): a program cut into three
units runs as the uncut one; a fault in a POU of the second or third unit names that POU and its line (a
division by zero through the name strings, the scan watchdog through the debug info); FBs defined in one
unit are called from another; the library exports nothing new; the cut does not depend on Python's hash
seed; a unit cut from a big program keeps the program's optimisation level."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys

import pytest

from linmot_st.plc import Plc, PlcFault
from linmot_st.toolchain import cc
from linmot_st.toolchain.builtin import units
from linmot_st.toolchain.testing import build_text


def _padding(var: str, n: int) -> str:
    return "\n".join(f"  {var} := {var} + {k % 7 + 1};" for k in range(n))


# three FBs of decreasing size: units.split gives each its own unit, heaviest first (FB_Acc, FB_Div, FB_Spin)
PROGRAM = f"""
FUNCTION Twice : DINT
  VAR_INPUT X : DINT; END_VAR
  Twice := X * 2;
END_FUNCTION

FUNCTION Mix : DINT
  VAR_INPUT A : DINT; B : DINT; END_VAR
  VAR T : DINT; END_VAR
  T := Twice(A) + B;
  IF T > 100000 THEN T := T MOD 1000; END_IF;
  Mix := T;
END_FUNCTION

FUNCTION_BLOCK FB_Acc
  VAR_INPUT In : DINT; END_VAR
  VAR_OUTPUT Sum : DINT; END_VAR
  VAR_EXTERNAL G : DINT; END_VAR
  VAR P : DINT; END_VAR
{_padding("P", 90)}
  Sum := Mix(Sum, In) + P MOD 7;
  G := G + 1;
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_Div
  VAR_INPUT D : DINT; END_VAR
  VAR_OUTPUT Q : DINT; END_VAR
  VAR P : DINT; END_VAR
{_padding("P", 60)}
  Q := 1000 / D;
  Q := Q + Twice(D);
END_FUNCTION_BLOCK

FUNCTION_BLOCK FB_Spin
  VAR_INPUT Go : BOOL; END_VAR
  VAR_OUTPUT N : DINT; END_VAR
  VAR P : DINT; END_VAR
{_padding("P", 30)}
  N := N + 1;
  IF Go THEN
    WHILE TRUE DO
      N := N + 1;
    END_WHILE;
  END_IF;
END_FUNCTION_BLOCK

PROGRAM Main
  VAR
    acc : FB_Acc; dv : FB_Div; spin : FB_Spin;
    D : DINT := 3; Go : BOOL; K : DINT; R : DINT; S : DINT;
  END_VAR
  K := K + 1;
  acc(In := K);
  dv(D := D);
  spin(Go := Go);
  R := dv.Q + Mix(K, acc.Sum);
  S := spin.N;
END_PROGRAM

CONFIGURATION Config0
  VAR_GLOBAL G : DINT; END_VAR
  RESOURCE Res0 ON PLC
    TASK T1(INTERVAL := T#1ms, PRIORITY := 0);
    PROGRAM Inst0 WITH T1 : Main;
  END_RESOURCE
END_CONFIGURATION
"""

DIV_LINE = next(k for k, line in enumerate(PROGRAM.lstrip("\n").splitlines(), 1) if "1000 / D" in line)
WATCH = ["INST0.K", "INST0.R", "INST0.S", "INST0.ACC.SUM", "INST0.DV.Q", "CONFIG0.G"]


@pytest.fixture
def cut_in_three(monkeypatch):
    """Every program cut into three units; FUNCTIONs longer than 300 characters dealt out, not copied."""
    monkeypatch.setattr(units, "SPLIT_WEIGHT", 0)
    monkeypatch.setattr(units, "UNIT_WEIGHT", 1)
    monkeypatch.setattr(units, "MAX_UNITS", 3)
    monkeypatch.setattr(units, "COPY_MAX_CHARS", 300)


def _unit_defining(res, function: str) -> str:
    """The name of the unit defining a C function."""
    found = [p.name for p in sorted(res.c_dir.glob("*.c"))
             if re.search(rf"^[^ ].*\b{function}\([^;]*$", p.read_text(), re.M)]
    assert len(found) == 1, (function, found)
    return found[0]


def _run(res, scans: int = 40) -> list[list]:
    plc = Plc(res)
    out = []
    for _ in range(scans):
        plc.step(1)
        out.append([plc[v] for v in WATCH])
    return out


@pytest.fixture
def builds(tmp_path, monkeypatch, cut_in_three):
    cut = build_text(PROGRAM, tmp_path / "cut", "builtin")
    monkeypatch.undo()
    whole = build_text(PROGRAM, tmp_path / "whole", "builtin")
    return whole, cut


def test_a_program_cut_into_three_units_runs_as_the_uncut_one(builds):
    whole, cut = builds
    assert [p.name for p in sorted(whole.c_dir.glob("*.c"))] == ["plc_builtin.c"]     # small: one unit
    assert [p.name for p in sorted(cut.c_dir.glob("*.c"))] == ["plc_builtin.c", "plc_builtin1.c", "plc_builtin2.c"]
    runs = _run(whole), _run(cut)
    assert runs[0] == runs[1]
    assert runs[0][-1][0] == 40 and runs[0][-1][5] == 40       # 40 scans; FB_Acc's writes reached the global


def test_fbs_defined_in_one_unit_are_called_from_another(builds):
    _, cut = builds
    where = {fb: _unit_defining(cut, f"{fb}_body__") for fb in ("FB_ACC", "FB_DIV", "FB_SPIN", "MAIN")}
    assert (where["FB_ACC"], where["FB_DIV"], where["FB_SPIN"]) == ("plc_builtin.c", "plc_builtin1.c",
                                                                    "plc_builtin2.c")
    header = (cut.c_dir / units.HEADER_NAME).read_text()
    for fb in ("FB_ACC", "FB_DIV", "FB_SPIN"):
        if where[fb] != where["MAIN"]:        # called from MAIN's unit: hidden, declared in the header
            assert re.search(rf'visibility\("hidden"\)\)\) void {fb}_body__\(', header)
    assert len(set(where.values())) == 3
    # the small FUNCTION Twice is a static copy in each unit that calls it; Mix (longer) is defined once
    copies = [p.name for p in sorted(cut.c_dir.glob("*.c")) if re.search(r"^static DINT TWICE\(", p.read_text(), re.M)]
    assert len(copies) >= 2
    _unit_defining(cut, "MIX")


def test_faults_in_other_units_name_their_pou_and_line(builds):
    _, cut = builds
    assert _unit_defining(cut, "FB_DIV_body__") != "plc_builtin.c"
    plc = Plc(cut)
    plc.step(2)
    plc["INST0.D"] = 0
    with pytest.raises(PlcFault) as info:
        plc.step(1)
    assert (info.value.kind, info.value.pou, info.value.line) == (1, "FB_DIV", DIV_LINE)
    assert info.value.file.endswith("prog.st")

    assert _unit_defining(cut, "FB_SPIN_body__") == "plc_builtin2.c"
    plc.reset()
    plc.watchdog_ns = 50_000_000
    plc["INST0.GO"] = True
    with pytest.raises(PlcFault) as info:         # no site of its own: found by address in the debug info
        plc.step(1)
    assert (info.value.kind, info.value.pou) == (5, "FB_SPIN") and info.value.file.endswith("prog.st")


@pytest.mark.skipif(not shutil.which("nm"), reason="needs nm")
def test_the_cut_library_exports_what_the_uncut_one_does(builds):
    def exports(res):
        out = subprocess.run(["nm", "-D", "--defined-only", str(res.library)], capture_output=True, text=True,
                             check=True).stdout
        return sorted(line.split()[-1] for line in out.splitlines())
    whole, cut = builds
    assert exports(whole) == exports(cut)
    assert "FB_DIV_body__" not in exports(cut) and "config_run__" in exports(cut)


def test_the_cut_does_not_depend_on_the_hash_seed(tmp_path):
    code = ("import hashlib, json, sys; from pathlib import Path\n"
            "from linmot_st.toolchain.builtin import compile_text, units\n"
            "units.SPLIT_WEIGHT, units.UNIT_WEIGHT, units.MAX_UNITS, units.COPY_MAX_CHARS = 0, 1, 3, 300\n"
            "out = compile_text(sys.stdin.read(), Path(sys.argv[1]), 'prog.st')\n"
            "files = sorted(out.c_files) + [Path(sys.argv[1]) / units.HEADER_NAME]\n"
            "print(json.dumps({p.name: hashlib.sha256(p.read_bytes()).hexdigest() for p in files}))\n")
    seen = []
    for seed in ("1", "2"):
        env = dict(os.environ, PYTHONHASHSEED=seed)
        proc = subprocess.run([sys.executable, "-c", code, str(tmp_path / seed)], input=PROGRAM, env=env,
                              capture_output=True, text=True, check=True)
        seen.append(json.loads(proc.stdout))
    assert len(seen[0]) == 4 and seen[0] == seen[1]


def test_a_unit_cut_from_a_big_program_keeps_its_optimisation_level(tmp_path):
    unit = tmp_path / "u.c"
    unit.write_text("void f(void)\n{\n}\n" * 10)
    assert cc.size_flags(unit) == []
    assert cc.size_flags(unit, lines=cc.LARGE_UNIT_LINES + 1)[0] == "-O0"
    assert cc.program_lines([unit, unit]) == 60
