"""The PLC loader on every available backend: path access, force, instances, virtual clock, faults."""

from __future__ import annotations

import json
import shutil

import pytest

from linmot_st.plc import LayoutError, PathError, Plc, PlcFault
from linmot_st.toolchain.testing import BACKEND_PARAMS, build_text

PROGRAM = """
TYPE
  T_Bytes : ARRAY[0..7] OF BYTE;
  T_Grid : ARRAY[1..2, -1..1] OF INT;
  E_Mode : (M_IDLE, M_RUN, M_DONE);
  T_Rec : STRUCT
    Id : UINT;
    Flag : BOOL;
    Data : T_Bytes;
    Label : STRING;
  END_STRUCT;
  T_Recs : ARRAY[1..3] OF T_Rec;
END_TYPE

FUNCTION SafeDiv : DINT
  VAR_INPUT
    Num : DINT;
    Den : DINT;
  END_VAR
  SafeDiv := Num / Den;
END_FUNCTION

FUNCTION_BLOCK Accumulator
  VAR_INPUT
    Inc : DINT;
    Den : DINT;
  END_VAR
  VAR_OUTPUT
    Sum : DINT;
    Quot : DINT;
  END_VAR
  VAR
    Delay : TON;
    Buf : T_Bytes;
  END_VAR
  Sum := Sum + Inc;
  Quot := Sum / Den;
  Delay(IN := TRUE, PT := T#30ms);
END_FUNCTION_BLOCK

PROGRAM Main
  VAR_EXTERNAL
    Total : UDINT;
    Lamp : BOOL;
  END_VAR
  VAR
    Count : DINT;
    Idx : INT := 1;
    Grid : T_Grid;
    Recs : T_Recs;
    Mode : E_Mode := M_RUN;
    Acc : Accumulator;
    AccDen : DINT := 1;
    Elapsed : TIME;
    Done : BOOL;
    Ratio : LREAL;
    Name : STRING := 'main';
    FnDen : DINT := 1;
    FnOut : DINT;
  END_VAR
  VAR
    Start AT %IX0.0 : BOOL;
  END_VAR
  VAR
    Level AT %QW2 : INT;
  END_VAR
  Count := Count + 1;
  Total := Total + 1;
  Grid[2, Idx] := DINT_TO_INT(Count);
  Acc(Inc := 2, Den := AccDen);
  Elapsed := Acc.Delay.ET;
  Done := Acc.Delay.Q;
  Lamp := Done;
  IF Start THEN
    Level := DINT_TO_INT(Count);
  END_IF;
  FnOut := SafeDiv(Num := 10, Den := FnDen);
  Ratio := DINT_TO_LREAL(Count) / 2.0;
END_PROGRAM

CONFIGURATION Config0
  VAR_GLOBAL
    Total : UDINT;
  END_VAR
  RESOURCE Res0 ON PLC
    VAR_GLOBAL
      Shared : INT;
    END_VAR
    VAR_GLOBAL
      Lamp AT %QX1.0 : BOOL;
    END_VAR
    TASK MainTask(INTERVAL := T#10ms, PRIORITY := 0);
    PROGRAM Inst0 WITH MainTask : Main;
  END_RESOURCE
END_CONFIGURATION
"""
LINE_OF = {text: n for n, text in enumerate(PROGRAM.lstrip("\n").splitlines(), 1)}
DIV_IN_FUNCTION = LINE_OF["  SafeDiv := Num / Den;"]
DIV_IN_FB = LINE_OF["  Quot := Sum / Den;"]
INDEX_IN_PROGRAM = LINE_OF["  Grid[2, Idx] := DINT_TO_INT(Count);"]


@pytest.fixture(scope="module", params=BACKEND_PARAMS)
def built(request, tmp_path_factory):
    return build_text(PROGRAM, tmp_path_factory.mktemp(f"loader-{request.param}"), request.param)


@pytest.fixture
def plc(built):
    return Plc(built)


def test_initial_values_and_kinds(plc):
    assert plc["INST0.IDX"] == 1
    assert plc["INST0.MODE"] == "M_RUN"
    assert plc["INST0.NAME"] == "main"
    assert plc["INST0.DONE"] is False
    assert plc["INST0.ELAPSED"] == 0
    assert plc["INST0.ACC.DELAY.PT"] == 0
    assert plc.time_ns == 0 and plc.scan_count == 0
    assert plc.tick_ns == 10_000_000


def test_step_runs_scans_and_advances_virtual_time(plc):
    plc.step(5)
    assert plc.scan_count == 5
    assert plc.time_ns == 5 * plc.tick_ns
    assert plc["INST0.COUNT"] == 5
    assert plc["CONFIG0.TOTAL"] == 5          # a configuration global, through the program's VAR_EXTERNAL
    assert plc["INST0.TOTAL"] == 5
    assert plc["INST0.ACC.SUM"] == 10          # FB instance member
    assert plc["INST0.RATIO"] == 2.5


def test_ton_sees_the_virtual_clock(plc):
    # IN rises in scan 1 at t = 0; with a 10 ms tick and PT = 30 ms, Q rises in scan 4 (t = 30 ms)
    seen = []
    for _ in range(5):
        plc.step(1)
        seen.append((plc["INST0.DONE"], plc["INST0.ELAPSED"]))
    assert seen == [(False, 0), (False, 10_000_000), (False, 20_000_000), (True, 30_000_000), (True, 30_000_000)]


def test_paths_are_case_insensitive_and_suffixes_suffice(plc):
    plc.step(2)
    assert plc["config0.res0.inst0.count"] == plc["Inst0.Count"] == plc["INST0.COUNT"] == 2
    assert plc["Shared"] == plc["CONFIG0.RES0.SHARED"] == 0
    with pytest.raises(PathError, match="has no member NOPE"):
        plc["INST0.NOPE"]
    with pytest.raises(PathError, match="no variable"):
        plc["NOPE.X"]
    with pytest.raises(PathError, match="out of its bounds"):
        plc["INST0.GRID[3, 0]"]
    with pytest.raises(PathError, match="dimension"):
        plc["INST0.GRID[1]"]


def test_arrays_keep_their_declared_bounds(plc):
    plc["INST0.IDX"] = -1
    plc.step(1)
    assert plc["INST0.GRID[2, -1]"] == 1
    assert plc["INST0.GRID[2][-1]"] == 1
    assert plc["INST0.GRID"] == [[0, 0, 0], [1, 0, 0]]
    plc["INST0.GRID[1, 1]"] = -7
    assert plc["INST0.GRID"][0] == [0, 0, -7]
    plc["INST0.GRID"] = [[1, 2, 3], [4, 5, 6]]
    assert plc["INST0.GRID[2, 0]"] == 5
    with pytest.raises(TypeError):
        plc["INST0.GRID"] = [[1, 2, 3]]


def test_structs_arrays_of_structs_strings_enums(plc):
    plc["INST0.RECS[2].DATA[7]"] = 0xAB
    plc["INST0.RECS[2].LABEL"] = "drive 1"
    plc["INST0.RECS[2].FLAG"] = True
    rec = plc["INST0.RECS[2]"]
    assert rec == {"ID": 0, "FLAG": True, "DATA": [0, 0, 0, 0, 0, 0, 0, 0xAB], "LABEL": "drive 1"}
    plc["INST0.RECS[3]"] = {"id": 513, "label": "x"}
    assert plc["INST0.RECS[3].ID"] == 513 and plc["INST0.RECS[3].LABEL"] == "x"
    plc["INST0.MODE"] = "m_done"
    assert plc["INST0.MODE"] == "M_DONE"
    with pytest.raises(ValueError):
        plc["INST0.MODE"] = "FAST"
    with pytest.raises(ValueError):
        plc["INST0.RECS[1].LABEL"] = "x" * 127
    fb = plc["INST0.ACC"]
    assert set(fb) >= {"INC", "DEN", "SUM", "QUOT", "DELAY", "BUF"}
    assert fb["DELAY"]["PT"] == 0


def test_integer_writes_are_range_checked(plc):
    plc["INST0.COUNT"] = -(2**31)
    with pytest.raises(ValueError, match="out of its range"):
        plc["INST0.COUNT"] = 2**31
    with pytest.raises(TypeError):
        plc["INST0.COUNT"] = 1.5
    with pytest.raises(ValueError):
        plc["INST0.RECS[1].DATA[0]"] = 256


def test_located_variables(plc):
    plc["%IX0.0"] = True
    plc.step(3)
    assert plc["%QW2"] == 3
    assert plc["INST0.LEVEL"] == 3       # the same cell, through the program's located variable
    assert plc["INST0.START"] is True
    plc["INST0.START"] = False
    assert plc["%IX0.0"] is False


def test_located_global(plc):
    plc.step(3)
    assert plc["%QX1.0"] is False and plc["CONFIG0.RES0.LAMP"] is False
    plc.step(1)                           # Done rises in scan 4
    assert plc["%QX1.0"] is True and plc["CONFIG0.RES0.LAMP"] is True and plc["INST0.LAMP"] is True


def test_bound_accessor(plc):
    count = plc.var("INST0.COUNT")
    start = plc.var("%IX0.0")
    start.value = True
    plc.step(2)
    assert count.value == 2
    count.value = 100
    plc.step(1)
    assert count.value == 101
    assert plc["%QW2"] == 101


def test_raw_bytes_of_a_byte_array(plc):
    buf = plc.var("INST0.ACC.BUF")
    assert buf.nbytes == 8 and buf.read_bytes() == bytes(8)
    buf.write_bytes(b"\x01\x02\x03")
    assert plc["INST0.ACC.BUF"] == [1, 2, 3, 0, 0, 0, 0, 0]
    with pytest.raises(ValueError):
        buf.write_bytes(bytes(9))


def test_force_pins_a_variable_until_unforced(plc):
    plc.force("INST0.COUNT", 40)
    plc.step(3)
    assert plc["INST0.COUNT"] == 40          # the program's writes are skipped
    assert plc.var("INST0.COUNT").forced
    plc.unforce("INST0.COUNT")
    plc.step(1)
    assert plc["INST0.COUNT"] == 41
    plc.force("INST0.ACC.SUM", 1000)         # an FB member
    plc.step(2)
    assert plc["INST0.ACC.SUM"] == 1000
    with pytest.raises(TypeError, match="cannot be forced"):
        plc.force("INST0.GRID[1, 0]", 1)


def test_force_a_global_written_through_var_external(plc):
    """A forced global holds against writes through VAR_EXTERNAL (MatIEC's __SET_EXTERNAL checks the
    global's force flag too), on both backends."""
    plc.force("CONFIG0.TOTAL", 7)
    plc.step(2)
    assert plc["CONFIG0.TOTAL"] == 7


def test_reset_restores_initial_state(plc):
    plc.force("INST0.COUNT", 9)
    plc["INST0.IDX"] = 0
    plc.step(4)
    plc.reset()
    assert plc.scan_count == 0 and plc.time_ns == 0
    assert plc["INST0.COUNT"] == 0 and plc["INST0.IDX"] == 1 and plc["INST0.NAME"] == "main"
    assert not plc.var("INST0.COUNT").forced
    plc.step(1)
    assert plc["INST0.COUNT"] == 1


def test_instances_are_independent(built):
    a, b = Plc(built), Plc(built)
    a.step(10)
    b.step(3)
    a["INST0.NAME"] = "a"
    assert (a["INST0.COUNT"], b["INST0.COUNT"]) == (10, 3)
    assert (a["CONFIG0.TOTAL"], b["CONFIG0.TOTAL"]) == (10, 3)
    assert b["INST0.NAME"] == "main"
    assert (a.time_ns, b.time_ns) == (100_000_000, 30_000_000)


def test_instances_of_one_build_share_its_types_and_not_its_memory(built):
    # the second Plc of a build takes the resolved types of the first (plc/layout.py: no ctypes class made twice);
    # its variables are its own all the same, and a manifest with other declarations gets types of its own
    from linmot_st.plc import layout

    a, b = Plc(built), Plc(built)
    assert a.layout.resolve("MAIN") is b.layout.resolve("MAIN")
    assert a.var("INST0.COUNT").address != b.var("INST0.COUNT").address
    manifest = json.loads(json.dumps(a.manifest))
    manifest["types"]["T_EXTRA"] = {"kind": "struct", "fields": [{"name": "X", "type": "INT"}]}
    assert layout.Layout(manifest).resolve("MAIN") is not a.layout.resolve("MAIN")
    assert len(layout._shared) <= layout.SHARED_LAYOUTS


def test_time_can_be_set(plc):
    plc.time_ns = 5_000_000_000
    plc.step(1)
    assert plc.time_ns == 5_010_000_000


@pytest.mark.parametrize("var, pou, line", [
    ("INST0.FNDEN", "SAFEDIV", DIV_IN_FUNCTION),
    ("INST0.ACCDEN", "ACCUMULATOR", DIV_IN_FB),
])
def test_division_by_zero_raises_plc_fault(plc, var, pou, line):
    plc.step(2)
    plc[var] = 0
    with pytest.raises(PlcFault) as info:
        plc.step(10)
    fault = info.value
    assert fault.kind == 1 and "division by zero" in str(fault)
    assert fault.pou == pou
    assert fault.line in (0, line)           # the line where the backend knows it
    assert plc.scan_count == 2               # scans before the fault completed
    with pytest.raises(PlcFault):            # a faulted PLC stays stopped
        plc.step(1)
    plc.reset()
    plc.step(3)
    assert plc["INST0.COUNT"] == 3


def test_index_out_of_range_raises_plc_fault(plc):
    plc["INST0.IDX"] = 2
    with pytest.raises(PlcFault) as info:
        plc.step(1)
    assert info.value.kind == 2 and info.value.pou == "MAIN"
    assert info.value.line in (0, INDEX_IN_PROGRAM)


def test_fault_lines_are_known(built, plc):
    """Both backends know the ST line of a fault (MatIEC: through iec2c's #line and gcc -g)."""
    plc["INST0.ACCDEN"] = 0
    with pytest.raises(PlcFault) as info:
        plc.step(1)
    assert info.value.line == DIV_IN_FB
    assert info.value.file.endswith("prog.st")


def test_a_manifest_that_does_not_match_the_c_is_refused(built, tmp_path):
    manifest = json.loads(built.manifest.read_text())
    checked = [t for t in manifest["size_checks"] if manifest["types"].get(t, {}).get("kind") == "struct"]
    assert checked, "the manifest checks the size of its struct types"
    manifest["types"][checked[0]]["fields"].append({"name": "EXTRA", "type": "LINT"})
    shutil.copyfile(built.library, tmp_path / built.library.name)
    (tmp_path / "manifest.json").write_text(json.dumps(manifest))
    with pytest.raises(LayoutError, match=f"does not describe the compiled C.*{checked[0]}"):
        Plc(tmp_path)


def test_roots_and_repr(plc):
    roots = plc.roots()
    assert "CONFIG0.RES0.INST0" in roots and "CONFIG0.TOTAL" in roots and "%IX0.0" in roots
    assert "INST0.COUNT" in plc and "INST0.NOPE" not in plc
    assert "scan 0" in repr(plc)


@pytest.mark.matiec
def test_backends_agree_on_layout_and_values(tmp_path):
    """Both backends describe the same variables with the same types, and compute the same values."""
    from linmot_st.toolchain import builtin_available, matiec_available
    if not (matiec_available() and builtin_available()):
        pytest.skip("needs both backends (MatIEC's iec2c and the builtin compiler)")
    seen = {}
    for backend in ("matiec", "builtin"):
        res = build_text(PROGRAM, tmp_path / backend, backend)
        manifest = json.loads(res.manifest.read_text())
        plc = Plc(res)
        plc["%IX0.0"] = True
        plc.step(10)
        plc["INST0.RECS[2].LABEL"] = "x"
        seen[backend] = (sorted(manifest["types"]), sorted(plc.roots()), {r: plc[r] for r in plc.roots()})
    assert seen["matiec"] == seen["builtin"]


FORCE_EXTERNALS = """
FUNCTION_BLOCK Writer
  VAR_EXTERNAL
    G : INT;
    L : INT;
  END_VAR
  G := G + 1;
  L := L + 1;
END_FUNCTION_BLOCK

PROGRAM Main
  VAR_EXTERNAL
    G : INT;
  END_VAR
  VAR
    W : Writer;
  END_VAR
  W();
  G := G + 10;
END_PROGRAM

CONFIGURATION Config0
  VAR_GLOBAL
    G : INT;
  END_VAR
  RESOURCE Res0 ON PLC
    VAR_GLOBAL
      L AT %MW4 : INT;
    END_VAR
    TASK T1(INTERVAL := T#10ms, PRIORITY := 0);
    PROGRAM Inst0 WITH T1 : Main;
  END_RESOURCE
END_CONFIGURATION
"""


@pytest.mark.parametrize("backend", BACKEND_PARAMS)
def test_forced_globals_hold_against_every_external_write(backend, tmp_path):
    """The global's force flag guards writes through any VAR_EXTERNAL bound to it: in a program, in an FB
    instance, and for a located global; the external's own flag guards them too."""
    plc = Plc(build_text(FORCE_EXTERNALS, tmp_path, backend))
    plc.step(1)
    assert (plc["CONFIG0.G"], plc["CONFIG0.RES0.L"], plc["%MW4"]) == (11, 1, 1)
    plc.force("CONFIG0.G", 100)
    plc.force("CONFIG0.RES0.L", 50)
    plc.step(3)
    assert (plc["CONFIG0.G"], plc["CONFIG0.RES0.L"], plc["%MW4"]) == (100, 50, 50)
    plc.unforce("CONFIG0.G")
    plc.unforce("CONFIG0.RES0.L")
    plc.step(1)
    assert (plc["CONFIG0.G"], plc["%MW4"]) == (111, 51)
    plc.force("INST0.W.G", 5)          # the FB's own external: its writes stop; the program's go on
    plc.step(1)
    assert plc["CONFIG0.G"] == 15
