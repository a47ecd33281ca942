"""`linmot-st emulate`: bad input gives one `linmot-st emulate: error: ...` line and exit status 2
(arguments) or 1 (the bus cannot be opened); SIGTERM stops it like Ctrl-C (drive detached, bus shut down, "stopped" line, status 0)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import uuid

import pytest

from linmot_st.cli import main


def _emulate(capsys, *args: str) -> tuple[int, str, str]:
    try:
        rc = main(["emulate", *args])
    except SystemExit as exc:           # argparse's own checks (types): the same one-line style
        rc = exc.code
    out, err = capsys.readouterr()
    return rc, out, err


E = "linmot-st emulate: error: "


@pytest.mark.parametrize("args, rc, message", [
    (["--interface", "nosuch", "--channel", "x"], 2,
     E + "--interface nosuch --channel x: python-can has no interface 'nosuch'"),
    (["--interface", "udp_multicast", "--channel", "239.0.0.1"], 2,
     E + "--interface udp_multicast --channel 239.0.0.1: the udp_multicast interface is not supported"),
    (["--interface", "virtual", "--channel", "x", "--node-id", "0"], 2, E + "argument --node-id: 0: must be 1..127"),
    (["--interface", "virtual", "--channel", "x", "--node-id", "128"], 2,
     E + "argument --node-id: 128: must be 1..127"),
    (["--interface", "pcan", "--channel", "x", "--bitrate", "0"], 2, E + "argument --bitrate: 0: not a CAN bit rate"),
    (["--interface", "pcan", "--channel", "x", "--bitrate", "300000"], 2,
     E + "argument --bitrate: 300000: not a CAN bit rate"),
    (["--interface", "virtual", "--channel", "x", "--profile", "/nonexistent/drive.json"], 2,
     E + "--profile /nonexistent/drive.json: No such file or directory"),
])
def test_bad_arguments_give_one_error_line(capsys, args, rc, message):
    got_rc, out, err = _emulate(capsys, *args, "--duration", "0")
    assert got_rc == rc
    assert err.startswith(message), err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert out == ""                       # nothing was served


def test_bad_profile_content(capsys, tmp_path):
    bad = tmp_path / "drive.json"
    bad.write_text("{ not json")
    rc, _, err = _emulate(capsys, "--interface", "virtual", "--channel", "x", "--profile", str(bad), "--duration", "0")
    assert rc == 2 and err.startswith(f"{E}--profile {bad}:1: not JSON") and err.count("\n") == 1
    bad.write_text('{"identity": {}}')
    rc, _, err = _emulate(capsys, "--interface", "virtual", "--channel", "x", "--profile", str(bad), "--duration", "0")
    assert rc == 2 and err.startswith(f"{E}--profile {bad}: missing key 'layers'") and err.count("\n") == 1


def test_bus_that_cannot_be_opened(capsys):
    # no SocketCAN on this machine (OSError: address family), or no such interface where there is
    rc, out, err = _emulate(capsys, "--interface", "socketcan", "--channel", "nosuchcan7", "--duration", "0")
    assert rc == 1 and err.startswith(f"{E}cannot open socketcan channel nosuchcan7: ") and err.count("\n") == 1
    assert "Traceback" not in err and out == ""


def test_duration_zero_serves_and_stops(capsys):
    rc, out, err = _emulate(capsys, "--interface", "virtual", "--channel", f"cli-{uuid.uuid4().hex[:8]}",
                            "--fast", "--duration", "0")
    assert rc == 0 and err == ""
    assert out.splitlines()[0].startswith("E1100 node 1 on virtual:") and "stopped in NMT state" in out


def test_sigterm_stops_like_ctrl_c():
    env = dict(os.environ, PYTHONUNBUFFERED="1")
    proc = subprocess.Popen([sys.executable, "-m", "linmot_st.cli", "emulate", "--interface", "virtual",
                             "--channel", f"cli-{uuid.uuid4().hex[:8]}", "--fast"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        first = proc.stdout.readline()          # printed once the bus is open: the handler is installed
        assert first.startswith("E1100 node 1 on virtual:"), first + proc.stderr.read()
        proc.send_signal(signal.SIGTERM)
        out, err = proc.communicate(timeout=20)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 0, err
    assert "Traceback" not in err and err == ""
    assert out.strip().startswith("E1100 node 1 stopped in NMT state")


def test_a_b1100_is_served_at_its_default_node_id_63(capsys):
    rc, out, err = _emulate(capsys, "--interface", "virtual", "--channel", f"cli-{uuid.uuid4().hex[:8]}",
                            "--drive", "b1100", "--duration", "0", "--fast")
    assert rc == 0, err
    assert out.startswith("B1100 node 63 on virtual:")
