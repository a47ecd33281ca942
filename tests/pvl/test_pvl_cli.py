"""`linmot-st pvl show FILE`."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from linmot_st.cli import main
from repo_paths import EXAMPLES


def test_show_two_axes(capsys):
    assert main(["pvl", "show", str(EXAMPLES / "two_axes.pvl")]) == 0
    out = capsys.readouterr().out
    assert "2 parameter layers, 3 curves, 3 command-table entries" in out
    assert "Layer 1 (Operating System): tree OSTREE1100OS__V3S0_b1, tree ID 1, version 3.0, revision b1: 16 parameters" in out
    assert "Layer 2 (Motion Control SW): tree MCTREE1100DSW4_HC_V3S0_b1, tree ID 4612, version 3.0" in out
    assert r"string 03E8h OS\Controller Name = 'LinMot-ST Demo' (stringlets 03E9h..03F0h)" in out
    assert r"string 03F2h OS\User Comment = 'X Axis Left' (stringlets 03F3h..03FAh)" in out
    assert "1194h  00000002h  Motion Control SW\\Motor Configuration\\Motor Type  = P01" in out
    assert "03F3h" not in out.split("string 03F2h")[1].split("\n", 1)[1]   # stringlets folded into their string
    assert " 23  Example_Curve                 10  20000 (200 ms)         position vs time (0003h)" in out
    assert "position vs encoder position (0103h)" in out
    assert "  1  Go_Out            0100h    2" in out


def test_show_verbose_lists_everything(capsys):
    assert main(["pvl", "show", "-v", str(EXAMPLES / "seed_parameters.pvl")]) == 0
    out = capsys.readouterr().out
    assert "03F3h  78412058h  OS\\User Comment_1  = X Ax" in out
    assert main(["pvl", "show", "--verbose", str(EXAMPLES / "seed_curve.pvl")]) == 0
    out = capsys.readouterr().out
    assert "XDimUUID 001Ah, YDimUUID 0005h, wizard type 0301h" in out
    assert "setpoints 0..1000000 (0.1 um)" in out


def test_show_errors(tmp_path, capsys):
    text = (EXAMPLES / "seed_curve.pvl").read_text("latin-1")
    bad = tmp_path / "bad.pvl"
    bad.write_text(text.replace("@CurveID,23", "@CurveID,24").replace("0004000Ah", "0004000Bh"), "latin-1")
    assert main(["pvl", "show", str(bad)]) == 1
    err = capsys.readouterr().err.splitlines()
    assert err == [f"{bad}:12: curve 23: info block says 11 setpoints, the data block holds 10",
                   f"{bad}:18: the info block's curve ID is 23, @CurveID (line 6) is 24",
                   f"{bad}: 2 error(s)"]


def test_show_missing_file(tmp_path, capsys):
    assert main(["pvl", "show", str(tmp_path / "nope.pvl")]) == 1
    assert "No such file" in capsys.readouterr().err


def test_pvl_without_command_prints_help(capsys):
    assert main(["pvl"]) == 2
    assert "show" in capsys.readouterr().out


def test_console_script():
    exe = Path(sys.executable).with_name("linmot-st")
    res = subprocess.run([str(exe), "pvl", "show", str(EXAMPLES / "seed_curve.pvl")], capture_output=True, text=True)
    assert res.returncode == 0 and "Example_Curve" in res.stdout
