"""The test environment's tools, fetched from Debian's packages into a cache, never installed system-wide.

`ensure()` returns the `Tools` (a User-Mode Linux kernel and its modules, busybox, can-utils) from the cache,
fetching them first when the cache does not hold them: `apt-get download` of the packages below, then
`dpkg-deb -x` of each into one folder. When the package lists are empty (a fresh container) and we are
root, `apt-get update` runs once first. Anything that stops this (no apt-get, no network to the archive,
not root and no lists, an architecture without the package) raises `Unavailable` with the reason, which the
tests turn into a skip.

The cache is `$LINMOT_ST_VCAN_CACHE`, else `$XDG_CACHE_HOME/linmot-st/vcan` or `~/.cache/linmot-st/vcan`
(about 42 MB of packages, 120 MB unpacked), shared by every checkout on the machine; a lock file serialises
concurrent fetches (pytest -n 2).
"""

from __future__ import annotations

import fcntl
import json
import os
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

# Debian package -> what we take from it
PACKAGES = {
    "user-mode-linux": "the Linux kernel built to run as a process (usr/bin/linux.uml) and its modules",
    "busybox-static": "the guest init's tools: insmod, mount, ip, chroot, poweroff",
    "can-utils": "candump, cansend, cangen: the independent CAN client of the tests",
}
STAMP = "tools.json"
FETCH_TIMEOUT_S = 600


class Unavailable(Exception):
    """The environment cannot be provided here; str() says why (a test skip reason)."""


@dataclass(frozen=True)
class Tools:
    root: Path                   # the unpacked packages
    versions: dict               # package -> Debian version

    @property
    def kernel(self) -> Path:
        return self.root / "usr" / "bin" / "linux.uml"

    @property
    def busybox(self) -> Path:
        return self.root / "bin" / "busybox"

    @property
    def bin(self) -> Path:
        """can-utils' programs."""
        return self.root / "usr" / "bin"

    @property
    def modules(self) -> Path:
        """usr/lib/uml/modules/<kernel version>/kernel (the .ko files are loaded by path: no modprobe)."""
        found = sorted((self.root / "usr" / "lib" / "uml" / "modules").glob("*/kernel"))
        if not found:
            raise Unavailable(f"{self.root}: the user-mode-linux package holds no modules folder")
        return found[-1]

    def missing(self) -> list[str]:
        paths = [self.kernel, self.busybox, self.bin / "candump", self.bin / "cansend", self.bin / "cangen"]
        return [str(p) for p in paths if not p.is_file()]


def cache_dir() -> Path:
    env = os.environ.get("LINMOT_ST_VCAN_CACHE")
    if env:
        return Path(env).expanduser()
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg).expanduser() if xdg and Path(xdg).is_absolute() else Path.home() / ".cache"
    return base / "linmot-st" / "vcan"


def cached(cache: Path | None = None) -> Tools | None:
    """The tools if the cache holds a complete copy, else None (never fetches)."""
    cache = cache or cache_dir()
    try:
        stamp = json.loads((cache / STAMP).read_text())
    except (OSError, ValueError):
        return None
    tools = Tools(cache / "root", stamp.get("versions", {}))
    return None if tools.missing() else tools


def ensure(cache: Path | None = None, *, log=None) -> Tools:
    """The tools, fetched into the cache first if needed. Raises Unavailable with the reason."""
    cache = cache or cache_dir()
    tools = cached(cache)
    if tools is not None:
        return tools
    try:
        cache.mkdir(parents=True, exist_ok=True)
        lock = open(cache / "lock", "w")
    except OSError as exc:
        raise Unavailable(f"cannot create the cache folder {cache}: {exc.strerror or exc}") from None
    with lock:
        fcntl.flock(lock, fcntl.LOCK_EX)         # another process may be fetching: wait, then look again
        tools = cached(cache)
        if tools is None:
            tools = _fetch(cache, log or (lambda line: None))
    return tools


def _run(argv: list[str], cwd: Path, timeout: float = FETCH_TIMEOUT_S) -> subprocess.CompletedProcess:
    try:
        return subprocess.run(argv, cwd=cwd, capture_output=True, text=True, timeout=timeout,
                              env={**os.environ, "LC_ALL": "C", "DEBIAN_FRONTEND": "noninteractive"})
    except FileNotFoundError:
        raise Unavailable(f"{argv[0]} not found: the tools come from Debian's packages (a Debian or Ubuntu "
                          f"machine with apt)") from None
    except subprocess.TimeoutExpired:
        raise Unavailable(f"{' '.join(argv)} did not finish within {timeout:.0f} s") from None


def _last_lines(text: str, n: int = 3) -> str:
    return " | ".join(line.strip() for line in text.strip().splitlines()[-n:])


def _download(debs: Path, log) -> None:
    argv = ["apt-get", "download", *PACKAGES]
    res = _run(argv, debs)
    if res.returncode != 0 and os.geteuid() == 0:
        # a fresh container has no package lists: read them once, then try again
        log("apt-get download failed; running apt-get update")
        upd = _run(["apt-get", "update"], debs)
        if upd.returncode != 0:
            raise Unavailable(f"apt-get update failed: {_last_lines(upd.stderr or upd.stdout)}")
        res = _run(argv, debs)
    if res.returncode != 0:
        hint = "" if os.geteuid() == 0 else " (not root: apt-get update could not be tried)"
        raise Unavailable(f"apt-get download {' '.join(PACKAGES)} failed{hint}: "
                          f"{_last_lines(res.stderr or res.stdout)}")


def _fetch(cache: Path, log) -> Tools:
    staging = Path(tempfile.mkdtemp(prefix="staging-", dir=cache))
    try:
        debs, root = staging / "debs", staging / "root"
        debs.mkdir()
        root.mkdir()
        log(f"fetching {', '.join(PACKAGES)} into {cache}")
        _download(debs, log)
        versions = {}
        for deb in sorted(debs.glob("*.deb")):
            res = _run(["dpkg-deb", "-x", str(deb), str(root)], staging)
            if res.returncode != 0:
                raise Unavailable(f"dpkg-deb -x {deb.name} failed: {_last_lines(res.stderr)}")
            fields = _run(["dpkg-deb", "-f", str(deb), "Package", "Version"], staging).stdout
            info = dict(line.split(": ", 1) for line in fields.splitlines() if ": " in line)
            versions[info.get("Package", deb.name)] = info.get("Version", "?")
        tools = Tools(root, versions)
        if tools.missing():
            raise Unavailable(f"the unpacked packages lack {', '.join(tools.missing())}")
        tools.modules                                   # noqa: B018 - raises Unavailable when absent
        shutil.rmtree(cache / "root", ignore_errors=True)
        shutil.rmtree(debs)                             # the unpacked tree is all we use
        root.rename(cache / "root")
        (cache / STAMP).write_text(json.dumps({"versions": versions}, indent=1) + "\n")
        return Tools(cache / "root", versions)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
