"""The runner of the SocketCAN test environment (linmot_st_vcan): a command run in a User-Mode Linux guest with
vcan0 and vcan1, its exit status, output and kernel log; what happens where the tools cannot be fetched."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from linmot_st_vcan import GuestStartError, Machine, Unavailable, ensure, native
from linmot_st_vcan.fetch import Tools


@pytest.fixture(scope="module")
def tools() -> Tools:
    if os.environ.get("LINMOT_ST_VCAN", "").strip().lower() in ("off", "native"):
        pytest.skip(f"LINMOT_ST_VCAN={os.environ['LINMOT_ST_VCAN']}: no guest")
    try:
        tools = ensure()
    except Unavailable as exc:
        pytest.skip(f"no SocketCAN guest here: {exc}")
    # a kernel that panics before its init runs cannot host any guest here (the reason names the kernel's own
    # line); the runner's behaviour is tested where a guest boots
    try:
        Machine(tools).run(["true"], timeout_s=60)
    except GuestStartError as exc:
        if "cannot run on this host" in str(exc):
            pytest.skip(f"no SocketCAN guest here: {exc}")
    return tools


def test_a_command_runs_in_the_guest_with_vcan_and_the_hosts_files(tools, tmp_path):
    out = tmp_path / "written-by-the-guest"
    script = ("cat /sys/class/net/vcan0/type /sys/class/net/vcan1/type /sys/class/net/vcan1/flags && "
              f"python -c 'import can, sys; print(sys.prefix)' && pwd && echo \"$MARK\" > {out} && "
              "touch /usr/not-on-the-host && echo bye >&2 && exit 7")
    run = Machine(tools).run(["sh", "-c", script], cwd=tmp_path, env={"MARK": "from the host"}, timeout_s=120,
                             writable=(tmp_path,), work_dir=tmp_path / "guest")
    assert run.returncode == 7 and not run.timed_out, run.describe()
    kind0, kind1, flags1 = run.output.split()[:3]
    assert kind0 == kind1 == "280" and int(flags1, 16) & 1          # ARPHRD_CAN, IFF_UP
    assert sys.prefix in run.output and str(tmp_path) in run.output and run.output.rstrip().endswith("bye")
    assert out.read_text() == "from the host\n"                  # a writable folder is the host's
    assert not Path("/usr/not-on-the-host").exists()             # the rest of the guest's writes vanish
    assert "vcan: Virtual CAN interface driver" in run.kernel_log
    assert (run.work_dir / "kernel.log").read_text() == run.kernel_log


def test_a_guest_that_cannot_set_up_says_why_with_its_kernel_log(tools, tmp_path):
    with pytest.raises(GuestStartError, match="cannot bring up this-name-is-too-long-for-linux") as exc:
        Machine(tools, interfaces=("vcan0", "this-name-is-too-long-for-linux")).run(["true"], timeout_s=120,
                                                                                    work_dir=tmp_path)
    assert "Virtual CAN interface driver" in exc.value.kernel_log


def test_the_command_is_stopped_at_its_timeout(tools, tmp_path):
    run = Machine(tools).run(["sleep", "60"], timeout_s=5, work_dir=tmp_path)
    assert run.timed_out and run.returncode is None and run.seconds < 20


def test_a_kernel_panic_before_init_is_named_with_the_kernels_line():
    from linmot_st_vcan.uml import _panic
    log = ("Run /tmp/x/init as init process\nuserspace - ptrace set fp regs failed, errno = 14\n"
           "Kernel panic - not syncing: Attempted to kill init! exitcode=0x0000000b\n Stack:\n")
    assert _panic(log) == ("the kernel cannot run on this host: userspace - ptrace set fp regs failed, errno = 14"
                           " -> Kernel panic - not syncing: Attempted to kill init! exitcode=0x0000000b")
    assert _panic("Run /tmp/x/init as init process\n") == ""


def test_no_apt_means_unavailable_with_the_reason(tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path))                   # no apt-get, no dpkg-deb
    with pytest.raises(Unavailable, match="apt-get not found"):
        ensure(tmp_path / "cache")


def test_socketcan_tests_skip_with_the_reason_where_the_tools_cannot_be_fetched(tmp_path):
    if native():
        pytest.skip("this kernel has vcan0: the socketcan tests run here without a guest")
    fake = tmp_path / "bin"
    fake.mkdir()
    (fake / "apt-get").write_text("#!/bin/sh\necho 'E: Failed to fetch: no network here' >&2\nexit 100\n")
    (fake / "apt-get").chmod(0o755)
    (tmp_path / "test_x.py").write_text(textwrap.dedent("""
        import pytest

        @pytest.mark.socketcan
        def test_needs_vcan0():
            raise AssertionError("must not run on a kernel without vcan0")
    """))
    env = dict(os.environ, PATH=f"{fake}:{os.environ['PATH']}", LINMOT_ST_VCAN_CACHE=str(tmp_path / "cache"),
               COLUMNS="300")
    env.pop("LINMOT_ST_VCAN", None)
    res = subprocess.run([sys.executable, "-m", "pytest", "-p", "linmot_st_vcan.pytest_plugin", "-p", "no:cacheprovider",
                          "-rs", "-o", "markers=socketcan", "test_x.py"], cwd=tmp_path, env=env, capture_output=True,
                         text=True, timeout=120)
    assert res.returncode == 0 and "1 skipped" in res.stdout, res.stdout + res.stderr
    skip = next(line for line in res.stdout.splitlines() if line.startswith("SKIPPED"))
    assert "test_x.py:" in skip and "no SocketCAN guest here: apt-get " in skip and "no network here" in skip, skip
