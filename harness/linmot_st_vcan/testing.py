"""Helpers of the socketcan tests: they run where the interfaces exist (inside the guest, or on a Linux
machine with vcan), each program in its own process, as a user would run them.

    with EmulatedDrives([1, 2], tmp_path) as drives:        # `linmot-st emulate` per node, booted
        with Candump(tmp_path / "bus.log") as dump:          # candump -L of the whole bus
            res = linmot_st("commission", "examples/two_axes.pvl", "--axes", "2", "--bus", "socketcan:vcan0",
                            "--no-emulate")
    drives.drive(1)            # an E1100Drive holding node 1's memory as its process left it
    dump.messages()            # the recording (sentinels aside), read back with python-can's LogReader

A new job over vcan (the motion job, say) is one more test of this shape: its command in `linmot_st(...)`,
then assertions on `res` and on `drives.memory(n)` / `drives.drive(n)`.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
BOOT_TIMEOUT_S = 60          # `linmot-st emulate` starting in the guest (imports) and booting (20 ms with --fast)
STOP_TIMEOUT_S = 30


def linmot_st(*args: str, timeout_s: float = 240, cwd: Path = REPO) -> subprocess.CompletedProcess:
    """`linmot-st ARGS` in a new process (this venv's Python), stdout and stderr captured as text."""
    return subprocess.run([sys.executable, "-m", "linmot_st.cli", *args], capture_output=True, text=True,
                          timeout=timeout_s, cwd=cwd, env=dict(os.environ, PYTHONUNBUFFERED="1"))


def can_utility(name: str) -> str:
    """The path of a can-utils program (candump, cansend, cangen): PATH (the guest puts the cache's there)."""
    path = shutil.which(name)
    if path is None:
        raise FileNotFoundError(f"{name} (can-utils) is not on PATH")
    return path


def _stop(proc: subprocess.Popen, sig: int, timeout_s: float = STOP_TIMEOUT_S) -> int:
    if proc.poll() is None:
        proc.send_signal(sig)
        try:
            proc.wait(timeout_s)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()
    return proc.returncode


class EmulatedDrives:
    """`linmot-st emulate --interface socketcan --channel CH --node-id N --fast --dump-memory ...` for each
    node, each in its own process; entering waits until every drive has sent its boot-up message, leaving
    stops them with SIGTERM (their exit status and logs are kept, the memory dumps read)."""

    def __init__(self, node_ids, work: Path, *, channel: str = "vcan0", extra_args: tuple = (),
                 model: str = "E1100") -> None:
        self.node_ids = list(node_ids)
        self.model = model                 # `emulate --drive MODEL` (emulator/models.py)
        self.work = Path(work)
        self.channel = channel
        self.extra_args = tuple(extra_args)
        self.procs: dict[int, subprocess.Popen] = {}
        self.returncodes: dict[int, int] = {}
        self._memory: dict[int, dict] = {}

    def log(self, node: int) -> str:
        path = self.work / f"emulate{node}.log"
        return path.read_text(errors="replace") if path.exists() else ""

    def logs(self) -> str:
        return "\n".join(f"--- linmot-st emulate, node {n} ---\n{self.log(n)}" for n in self.node_ids)

    def __enter__(self) -> EmulatedDrives:
        import can

        self.work.mkdir(parents=True, exist_ok=True)
        filters = [{"can_id": 0x700 + n, "can_mask": 0x7FF, "extended": False} for n in self.node_ids]
        with can.Bus(interface="socketcan", channel=self.channel, can_filters=filters) as bus:
            for n in self.node_ids:        # the listener is open before any drive can boot
                with open(self.work / f"emulate{n}.log", "w") as log:
                    self.procs[n] = subprocess.Popen(
                        [sys.executable, "-m", "linmot_st.cli", "emulate", "--interface", "socketcan",
                         "--channel", self.channel, "--node-id", str(n), "--fast",
                         "--dump-memory", str(self.work / f"drive{n}.json"), "--drive", self.model,
                         *self.extra_args],
                        stdout=log, stderr=subprocess.STDOUT, cwd=REPO, env=dict(os.environ, PYTHONUNBUFFERED="1"))
            waiting, deadline = set(self.node_ids), time.monotonic() + BOOT_TIMEOUT_S
            while waiting and time.monotonic() < deadline:
                msg = bus.recv(timeout=0.5)
                if msg is not None and bytes(msg.data) == b"\x00":
                    waiting.discard(msg.arbitration_id - 0x700)
                gone = [n for n in waiting if self.procs[n].poll() is not None]
                if gone:
                    break
        if waiting:
            self.__exit__(None, None, None)
            raise RuntimeError(f"no boot-up message from node(s) {sorted(waiting)} within {BOOT_TIMEOUT_S} s\n"
                               + self.logs())
        return self

    def __exit__(self, *exc) -> None:
        for n, proc in self.procs.items():
            self.returncodes[n] = _stop(proc, signal.SIGTERM)

    def memory(self, node: int) -> dict:
        """The node's memory as its process wrote it when stopped (emulator/linmot/memory.py)."""
        if node not in self._memory:
            from linmot_st.emulator.linmot.memory import read
            path = self.work / f"drive{node}.json"
            if not path.exists():
                raise FileNotFoundError(f"node {node} left no memory dump (exit status "
                                        f"{self.returncodes.get(node)})\n{self.log(node)}")
            self._memory[node] = read(path)
        return self._memory[node]

    def drive(self, node: int):
        """A drive of the model (its default profile, as `linmot-st emulate` serves it) holding the node's memory."""
        from linmot_st.emulator.linmot.memory import load
        from linmot_st.emulator.models import make_drive
        drive = make_drive(self.model, node)
        load(drive, self.memory(node))
        return drive

    def drives(self) -> dict:
        return {n: self.drive(n) for n in self.node_ids}

    def clean_exit(self) -> str:
        """'' when every drive process stopped with status 0 and no traceback; else what went wrong."""
        bad = [n for n in self.node_ids if self.returncodes.get(n) != 0 or "Traceback" in self.log(n)]
        return "" if not bad else (f"emulate of node(s) {bad}: exit status "
                                   f"{[self.returncodes.get(n) for n in bad]}\n" + self.logs())


SENTINEL_ID = 0x1FFFFFFF       # an extended identifier: ignored by the PLC and the drives, left out of messages()


class Candump:
    """`candump -L CHANNEL[,filters]` writing to `path` while the block runs; `messages()` reads the file back
    with python-can's LogReader. Entering returns once candump records (a sentinel frame it was sent is in
    the file: its output is line-buffered with coreutils' stdbuf), leaving once it has recorded everything
    sent before (a second sentinel), then stops it with SIGINT."""

    def __init__(self, path: Path, channel: str = "vcan0", *, filters: tuple = (), timeout_s: float = 30) -> None:
        self.path = Path(path)
        self.channel = channel
        self.spec = ",".join([channel, *filters, *((f"{SENTINEL_ID:08X}:{SENTINEL_ID:08X}",) if filters else ())])
        self.timeout_s = timeout_s
        self.proc: subprocess.Popen | None = None
        self.returncode: int | None = None

    def _sentinel(self, bus, tag: bytes, repeat: bool) -> None:
        import can
        line = f"{SENTINEL_ID:08X}#{tag.hex().upper()}"
        deadline = time.monotonic() + self.timeout_s
        sent = False
        while time.monotonic() < deadline:
            if repeat or not sent:
                bus.send(can.Message(arbitration_id=SENTINEL_ID, is_extended_id=True, data=tag))
                sent = True
            time.sleep(0.05)
            if line in self.path.read_text(errors="replace"):
                return
            if self.proc.poll() is not None:
                break
        raise RuntimeError(f"candump {self.spec} did not record its sentinel {line} within {self.timeout_s} s "
                           f"(exit status {self.proc.poll()}): {self.proc.stderr.read().decode() if self.proc.poll() is not None else ''}")

    def __enter__(self) -> Candump:
        import can
        stdbuf = shutil.which("stdbuf")
        if stdbuf is None:
            raise FileNotFoundError("stdbuf (coreutils) is not on PATH: candump's output would not be line-buffered")
        self._file = open(self.path, "w")
        self.proc = subprocess.Popen([stdbuf, "-oL", can_utility("candump"), "-L", self.spec],
                                     stdout=self._file, stderr=subprocess.PIPE)
        with can.Bus(interface="socketcan", channel=self.channel) as bus:
            self._sentinel(bus, b"start", repeat=True)
        return self

    def __exit__(self, *exc) -> None:
        import can
        try:
            with can.Bus(interface="socketcan", channel=self.channel) as bus:
                self._sentinel(bus, b"end", repeat=False)
        finally:
            self.returncode = _stop(self.proc, signal.SIGINT)
            self._file.close()

    def messages(self) -> list:
        import can
        return [m for m in can.LogReader(str(self.path)) if not (m.is_extended_id and m.arbitration_id == SENTINEL_ID)]


def sdo_frames(frames, node: int) -> list[tuple[int, bytes]]:
    """(COB-ID, data) of the node's SDO requests (600h+n) and answers (580h+n), in order, from Frames or
    python-can Messages; heartbeats, NMT, PDOs and everything else left out."""
    out = []
    for f in frames:
        can_id = getattr(f, "can_id", None)
        if can_id is None:
            if f.is_extended_id or f.is_error_frame or f.is_remote_frame:
                continue
            can_id = f.arbitration_id
        if can_id in (0x600 + node, 0x580 + node):
            out.append((can_id, bytes(f.data)))
    return out


# Flash polls (2000h sub 42h, sub 80h read) answered "busy" (04h in byte 4): how many there are depends on how
# long the drive's flash write takes in wall time against the PLC's scans, so they are the one part of the
# SDO sequence that a real-time run cannot share with the simulated bus.
_POLLS = {(0x00, 0x20, 0x42), (0x00, 0x20, 0x80)}


def without_busy_polls(frames: list[tuple[int, bytes]]) -> list[tuple[int, bytes]]:
    """The SDO sequence of sdo_frames() minus each flash poll answered busy, with the request it answers."""
    out: list[tuple[int, bytes]] = []
    for can_id, data in frames:
        busy = (0x580 <= can_id < 0x600 and data[:1] == b"\x43" and tuple(data[1:4]) in _POLLS
                and data[4] == 0x04)
        if busy and out and out[-1][0] == can_id + 0x80 and out[-1][1][:4] == b"\x40" + data[1:4]:
            out.pop()
            continue
        out.append((can_id, data))
    return out
