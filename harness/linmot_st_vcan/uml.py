"""Run one command inside a User-Mode Linux kernel that has a real SocketCAN stack and vcan interfaces.

    from linmot_st_vcan import Machine
    run = Machine().run(["candump", "-n", "1", "vcan0"], timeout_s=60)
    run.returncode, run.output, run.kernel_log

The guest is the Debian `user-mode-linux` kernel (fetch.py) started as an ordinary process. Its root is the
host's root through hostfs (so the host's Python, the project's venv and the checkout are there unchanged),
seen through an overlay whose upper layer is a tmpfs: the guest can write anywhere, and those writes vanish
with it. Only the run's work folder (and any `writable` path) is mounted read-write from the host, so what
the command writes there is seen by the host. The guest's init (a busybox script written for each run) loads
the CAN modules by path (can, can-raw, can-dev, vcan, overlay: there is no modprobe), adds and brings up the
vcan interfaces, builds that root, runs the command there with the host's environment, records its exit
status and powers off. The kernel log (the console) goes to `kernel.log` in the work folder.

Facts and figures of this route: /work/shared/spec/vcan-uml.md and docs/bus.md ("A real SocketCAN stack").
"""

from __future__ import annotations

import os
import shlex
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from .fetch import Tools, Unavailable, ensure

INTERFACES = ("vcan0", "vcan1")
BOOT_TIMEOUT_S = 60
MODULES = ("net/can/can", "net/can/can-raw", "drivers/net/can/dev/can-dev", "drivers/net/can/vcan",
           "fs/overlayfs/overlay")
# host variables that describe the host's own pytest or terminal session, not the command's environment
_DROP_ENV = ("PYTEST_CURRENT_TEST", "PYTEST_XDIST_WORKER", "PYTEST_XDIST_WORKER_COUNT", "PYTEST_XDIST_TESTRUNUID",
             "TERM", "COLUMNS", "LINES", "DISPLAY")


class GuestStartError(Unavailable):
    """The kernel ran but never reached the command (no CAN modules, no vcan, no overlay...); the kernel
    log says why. A subclass of Unavailable: where no guest ever started, tests skip with this reason."""

    def __init__(self, reason: str, kernel_log: str = "") -> None:
        super().__init__(reason)
        self.kernel_log = kernel_log


@dataclass
class GuestRun:
    returncode: int | None       # the command's exit status; None when it was stopped by the timeout
    output: str                  # its stdout and stderr, interleaved
    kernel_log: str              # the guest console: kernel messages and the init's own lines
    work_dir: Path               # host folder, read-write in the guest at the same path
    seconds: float               # wall time from start to power-off
    timed_out: bool = False

    @property
    def ok(self) -> bool:
        return self.returncode == 0

    def describe(self) -> str:
        """The run in words, for a failure message: status, output, the end of the kernel log."""
        status = (f"stopped by the timeout after {self.seconds:.0f} s" if self.timed_out
                  else f"exit status {self.returncode}")
        tail = "\n".join(self.kernel_log.splitlines()[-40:])
        return (f"guest command: {status} ({self.seconds:.1f} s)\n--- output ---\n{self.output}"
                f"\n--- kernel log (last 40 lines; all of it in {self.work_dir / 'kernel.log'}) ---\n{tail}\n")


FAIL_MARK = "linmot-st init failed: "       # the init's line on the console when it cannot set the guest up
INIT = """#!{busybox} sh
# PID 1 of the guest (written by linmot_st_vcan.uml for one run)
B={busybox}
W={work}
fail() {{ echo "{fail_mark}$*"; $B poweroff -f; }}
for m in {modules}; do $B insmod {moddir}/$m.ko || fail "insmod $m failed"; done
for i in {interfaces}; do
  $B ip link add dev $i type vcan && $B ip link set up $i || fail "cannot bring up $i"
done
R=$W/guest-root
$B mount -t tmpfs -o mode=0755 tmpfs $R || fail "tmpfs"
$B mkdir $R/upper $R/work $R/merged
$B mount -t overlay overlay -o lowerdir=/,upperdir=$R/upper,workdir=$R/work $R/merged || fail "overlay root"
N=$R/merged
$B mount -t proc proc $N/proc && $B mount -t sysfs sysfs $N/sys && $B mount -t devtmpfs devtmpfs $N/dev \\
  || fail "proc, sys, dev"
$B mkdir -p $N/dev/pts $N/dev/shm
$B mount -t devpts devpts $N/dev/pts; $B mount -t tmpfs tmpfs $N/dev/shm
for d in {writable}; do $B mount -t hostfs none $N$d -o $d || fail "hostfs $d"; done
echo started > $N$W/started
$B chroot $N $B sh $W/command.sh > $N$W/output 2>&1 < /dev/null
echo $? > $N$W/rc
$B sync
for d in {writable_reversed}; do $B umount $N$d; done
$B poweroff -f
"""


def _panic(kernel_log: str) -> str:
    """The kernel's own reason when it panicked before init ran, e.g. the UML kernels of Debian 12 and 13 on a
    host whose CPU has AMX: 'userspace - ptrace set fp regs failed, errno = 14' (measured on these machines:
    the host's extended FPU state does not fit what UML hands to ptrace), then 'Kernel panic'."""
    lines = kernel_log.splitlines()
    for i, line in enumerate(lines):
        if line.startswith("Kernel panic"):
            before = next((b.strip() for b in reversed(lines[:i]) if b.strip() and not b.startswith(" ")), "")
            return f"the kernel cannot run on this host: {before + ' -> ' if before else ''}{line.strip()}"
    return ""


def _q(path: Path | str) -> str:
    return shlex.quote(str(path))


class Machine:
    """Starts a guest per `run()`. `tools`: from fetch.ensure() (the default fetches into the cache)."""

    def __init__(self, tools: Tools | None = None, *, mem_mb: int = 1024,
                 interfaces: tuple[str, ...] = INTERFACES) -> None:
        self.tools = tools or ensure()
        self.mem_mb = mem_mb
        self.interfaces = interfaces

    def command_path(self) -> str:
        """PATH inside the guest: the venv's bin folder, can-utils, then the host's PATH."""
        venv_bin = str(Path(sys.executable).parent)
        rest = [p for p in os.environ.get("PATH", "/usr/bin:/bin").split(":") if p and p != venv_bin]
        return ":".join([venv_bin, str(self.tools.bin), *rest])

    def run(self, argv: list[str], *, cwd: Path | str | None = None, env: dict | None = None,
            timeout_s: float = 300, work_dir: Path | None = None, writable: tuple = ()) -> GuestRun:
        """Run argv in a fresh guest; returns a GuestRun. The work folder (default a new one in the temporary
        folder, left there with the kernel log, the output and the init script) is read-write in the guest at
        its host path, as is every folder in `writable` (created if absent). Raises GuestStartError when the
        guest never reached the command."""
        work = Path(work_dir or tempfile.mkdtemp(prefix="linmot-st-vcan-")).resolve()
        work.mkdir(parents=True, exist_ok=True)
        for name in ("rc", "output", "started", "kernel.log"):
            (work / name).unlink(missing_ok=True)
        (work / "guest-root").mkdir(exist_ok=True)
        # the guest's memory file and UML's runtime files; a short path (UML keeps it in a small buffer)
        tmp = Path(tempfile.mkdtemp(prefix="uml-"))
        mounts = [work]
        for w in writable:
            p = Path(w).resolve()
            p.mkdir(parents=True, exist_ok=True)
            if p not in mounts:
                mounts.append(p)
        environment = {k: v for k, v in os.environ.items() if k not in _DROP_ENV}
        environment.update(env or {})
        environment.update(PATH=self.command_path(), LINMOT_ST_VCAN_GUEST="1")
        (work / "command.sh").write_text(
            f"cd {_q(cwd or os.getcwd())} || exit 126\n"
            + "".join(f"export {k}={shlex.quote(v)}\n" for k, v in environment.items() if k.isidentifier())
            + "exec " + " ".join(shlex.quote(a) for a in argv) + "\n")
        init = work / "init"
        init.write_text(INIT.format(
            busybox=_q(self.tools.busybox), work=_q(work), fail_mark=FAIL_MARK, moddir=_q(self.tools.modules),
            modules=" ".join(MODULES), interfaces=" ".join(self.interfaces),
            writable=" ".join(_q(m) for m in mounts), writable_reversed=" ".join(_q(m) for m in reversed(mounts))))
        init.chmod(0o755)
        kernel_args = [str(self.tools.kernel), f"mem={self.mem_mb}M", "root=/dev/root", "rootfstype=hostfs",
                       "rootflags=/", "ro", f"init={init}", f"uml_dir={tmp}", "con0=null,fd:1", "con=null",
                       "ssl=null"]
        uml_env = {"PATH": "/usr/bin:/bin", "TMPDIR": str(tmp), "TMP": str(tmp), "TEMP": str(tmp)}
        t0 = time.monotonic()
        timed_out = False
        with open(work / "kernel.log", "wb") as klog:
            try:
                proc = subprocess.Popen(kernel_args, stdin=subprocess.DEVNULL, stdout=klog, stderr=subprocess.STDOUT,
                                        env=uml_env, start_new_session=True)
            except OSError as exc:
                raise GuestStartError(f"cannot start {self.tools.kernel}: {exc.strerror or exc}") from None
            try:
                # a kernel that cannot run here may hang instead of dying: give up when the command has not
                # started within BOOT_TIMEOUT_S (it starts in about 2 s)
                while proc.poll() is None:
                    elapsed = time.monotonic() - t0
                    if elapsed > timeout_s or (elapsed > BOOT_TIMEOUT_S and not (work / "started").exists()):
                        timed_out = True
                        break
                    time.sleep(0.1)
            finally:
                # the kernel's helper processes share its process group; none may outlive the run
                try:
                    os.killpg(proc.pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
                proc.wait()
        seconds = time.monotonic() - t0
        shutil.rmtree(tmp, ignore_errors=True)
        kernel_log = (work / "kernel.log").read_text(errors="replace")
        if not (work / "started").exists():
            failed = [line[len(FAIL_MARK):] for line in kernel_log.splitlines() if line.startswith(FAIL_MARK)]
            why = failed[0].strip() if failed else _panic(kernel_log) or (
                "timed out before the command started" if timed_out else
                f"the kernel stopped (exit status {proc.returncode}) before the command started")
            raise GuestStartError(f"User-Mode Linux guest: {why}", kernel_log)
        rc_file = work / "rc"
        returncode = None if timed_out or not rc_file.exists() else int(rc_file.read_text().strip() or -1)
        output = (work / "output").read_text(errors="replace") if (work / "output").exists() else ""
        return GuestRun(returncode, output, kernel_log, work, seconds, timed_out)
