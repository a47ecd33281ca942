"""A compiled PLC, loaded from a build: init, reset, step(n) in virtual time, variables by path, faults.

Each Plc loads a private copy of the shared library (dlopen returns the same handle for the same file,
so two Plc objects on one path would share their variables). The copy is deleted as soon as it is mapped.
Libraries are never unloaded: the glue's signal handlers chain to one another across instances.
"""

from __future__ import annotations

import ctypes
import json
import os
import shutil
import tempfile
from pathlib import Path
from typing import Any

from . import coverage
from .access import PathError, Resolver
from .faults import PlcFault, locate_with_debug_info
from .layout import Layout, LayoutError
from .variable import Var, make_var

ABI_VERSION = 3

_ABI = {
    "plc_abi_version": ([], ctypes.c_int),
    "plc_init": ([], None),
    "plc_step": ([ctypes.c_ulong], ctypes.c_ulong),
    "plc_step_idle": ([ctypes.c_ulong, ctypes.c_ulonglong, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p,
                       ctypes.c_void_p, ctypes.c_int, ctypes.c_void_p], ctypes.c_ulong),
    "plc_fault_kind": ([], ctypes.c_int),
    "plc_fault_pou": ([], ctypes.c_char_p),
    "plc_fault_file": ([], ctypes.c_char_p),
    "plc_fault_line": ([], ctypes.c_int),
    "plc_fault_pc": ([], ctypes.c_ulong),
    "plc_root_addr": ([ctypes.c_int], ctypes.c_void_p),
    "plc_type_size": ([ctypes.c_int], ctypes.c_ulong),
    "plc_time_ns": ([], ctypes.c_ulonglong),
    "plc_set_time_ns": ([ctypes.c_ulonglong], None),
    "plc_tick_ns": ([], ctypes.c_ulonglong),
    "plc_scan_count": ([], ctypes.c_ulonglong),
    "plc_set_watchdog_ns": ([ctypes.c_ulonglong], None),
    "plc_watchdog_ns": ([], ctypes.c_ulonglong),
}


def _build_paths(build: Any) -> tuple[Path, Path]:
    """(library, manifest) from a BuildResult, a build folder, or a (library, manifest) pair."""
    if hasattr(build, "library") and hasattr(build, "manifest"):
        return Path(build.library), Path(build.manifest)
    if isinstance(build, (tuple, list)) and len(build) == 2:
        return Path(build[0]), Path(build[1])
    folder = Path(build)
    if folder.is_dir():
        libs = sorted(folder.glob("*.so"))
        if len(libs) != 1:
            raise FileNotFoundError(f"{folder}: expected one .so beside manifest.json, found {len(libs)}")
        return libs[0], folder / "manifest.json"
    raise TypeError(f"cannot load a PLC from {build!r}: pass a build result, a build folder or (library, manifest)")


class IdleWatch:
    """The variables whose change ends a run of idle scans (Plc.step_idle), as the C arrays the glue reads."""

    def __init__(self, variables: list[Var]) -> None:
        self.variables = list(variables)
        self.count = len(self.variables)
        self.addrs = (ctypes.c_void_p * max(1, self.count))(*[v.address for v in self.variables])
        self.sizes = (ctypes.c_ulong * max(1, self.count))(*[v.nbytes for v in self.variables])
        self.shadow = ctypes.create_string_buffer(max(1, sum(v.nbytes for v in self.variables)))


_NO_WATCH = IdleWatch([])


class Plc:
    """One independent PLC instance. See docs/architecture.md section 2."""

    def __init__(self, build: Any):
        self.library, self.manifest_path = _build_paths(build)
        self.manifest = json.loads(self.manifest_path.read_text())
        self.backend = self.manifest.get("backend", "")
        self._lib = self._load_private_copy(self.library)
        coverage.register(self._lib, self.library)      # a coverage build: its counters are written on request
        for name, (args, res) in _ABI.items():
            try:
                fn = getattr(self._lib, name)
            except AttributeError:
                raise LayoutError(f"{self.library} does not export {name}: not a linmot-st PLC build") from None
            fn.argtypes, fn.restype = args, res
        if self._lib.plc_abi_version() != ABI_VERSION:
            raise LayoutError(f"{self.library}: glue ABI {self._lib.plc_abi_version()}, expected {ABI_VERSION}")
        self.layout = Layout(self.manifest)
        self._check_sizes()
        roots = [(r["path"], r["type"], self._lib.plc_root_addr(i) or 0)
                 for i, r in enumerate(self.manifest.get("roots", []))]
        for path, _, addr in roots:
            if not addr:
                raise LayoutError(f"{self.library}: root {path} has no address")
        self._root_spans = [(addr, self.layout.resolve(t).size) for _, t, addr in roots]
        self._resolver = Resolver(self.layout, roots)
        self._pous = {p.upper() for p in self.manifest.get("pous", {})}
        self._vars: dict[str, Var] = {}
        self._step_fn = self._lib.plc_step
        self._step_idle_fn = self._lib.plc_step_idle
        self._lib.plc_init()
        self._check_fault()

    @staticmethod
    def _load_private_copy(library: Path) -> ctypes.CDLL:
        folder = tempfile.mkdtemp(prefix="linmot-st-plc-")
        copy = os.path.join(folder, library.name)
        try:
            shutil.copyfile(library, copy)
            return ctypes.CDLL(copy, mode=os.RTLD_LOCAL | os.RTLD_NOW)
        finally:
            shutil.rmtree(folder, ignore_errors=True)

    def _check_sizes(self) -> None:
        bad = []
        for i, ref in enumerate(self.manifest.get("size_checks", [])):
            expected = self._lib.plc_type_size(i)
            actual = self.layout.resolve(ref).size
            if expected != actual:
                bad.append(f"{ref}: C sizeof {expected}, manifest layout {actual}")
        if bad:
            raise LayoutError(f"{self.library}: the manifest does not describe the compiled C "
                              f"(rebuild it; if it persists the backend is at fault): " + "; ".join(bad))

    # ---- running ---------------------------------------------------------------------------------------

    def step(self, n: int = 1) -> None:
        """Run n scans in C. Raises PlcFault if one faults (the scans before it have run)."""
        if self._step_fn(n) != n:
            self._check_fault()

    def step_idle(self, n: int, until_ns: int, rx_count: Var, tx_count: Var, watch: IdleWatch | None = None) -> int:
        """Idle scans in C: up to n scans with rx_count := 0 before each, ending before a scan that would start
        at or after until_ns, after the scan that made tx_count non-zero or changed a watched variable
        (`watch`), or at a fault (PlcFault). Returns the scans run. rx_count and tx_count are INT variables
        (a T_CanMailbox's RxCount and TxCount)."""
        if n <= 0:
            return 0
        w = watch or _NO_WATCH
        done = self._step_idle_fn(n, until_ns, rx_count.address, tx_count.address, w.addrs, w.sizes, w.count,
                                  w.shadow)
        if done < n and self._lib.plc_fault_kind():
            self._check_fault()
        return done

    def reset(self) -> None:
        """Cold restart: every root variable zeroed (force flags too), initialised again, time 0."""
        for addr, size in self._root_spans:
            ctypes.memset(addr, 0, size)
        self._lib.plc_init()
        self._check_fault()

    def _check_fault(self) -> None:
        kind = self._lib.plc_fault_kind()
        if not kind:
            return
        pou = (self._lib.plc_fault_pou() or b"").decode(errors="replace")
        file = (self._lib.plc_fault_file() or b"").decode(errors="replace")
        line = self._lib.plc_fault_line()
        pc = self._lib.plc_fault_pc()
        if not file and pc:
            found = locate_with_debug_info(self.library, pc, self._pous)
            if found:
                pou, file, line = found
                file = self._source_name(file)
        if file.endswith(".c"):
            # a position in generated C (the builtin backend's C has no #line): name the POU's ST file
            info = {k.upper(): v for k, v in self.manifest.get("pous", {}).items()}.get(pou.upper(), {})
            file, line = info.get("file", ""), 0
        raise PlcFault(kind, pou, file, line, pc, int(self._lib.plc_scan_count()) + 1)

    def _source_name(self, file: str) -> str:
        """The debug info may hold an absolute path; report it as the manifest names the file."""
        for info in self.manifest.get("pous", {}).values():
            name = info.get("file", "")
            if name and (file == name or file.endswith("/" + name)):
                return name
        return file

    @property
    def faulted(self) -> bool:
        return bool(self._lib.plc_fault_kind())

    @property
    def time_ns(self) -> int:
        return int(self._lib.plc_time_ns())

    @time_ns.setter
    def time_ns(self, t: int) -> None:
        self._lib.plc_set_time_ns(t)

    @property
    def tick_ns(self) -> int:
        return int(self._lib.plc_tick_ns())

    @property
    def scan_count(self) -> int:
        return int(self._lib.plc_scan_count())

    @property
    def watchdog_ns(self) -> int:
        """The scan watchdog: CPU time one scan may take before it ends as a PlcFault (kind 5); 0 = off.
        Default 1 s (docs/toolchain.md)."""
        return int(self._lib.plc_watchdog_ns())

    @watchdog_ns.setter
    def watchdog_ns(self, ns: int) -> None:
        if ns < 0:
            raise ValueError(f"watchdog {ns} ns: must be >= 0 (0 turns it off)")
        self._lib.plc_set_watchdog_ns(int(ns))

    # ---- variables -------------------------------------------------------------------------------------

    def var(self, path: str) -> Var:
        """The bound accessor of a path (resolved once, then cached)."""
        v = self._vars.get(path)
        if v is None:
            v = make_var(self._resolver.resolve(path), self)
            self._vars[path] = v
        return v

    def __getitem__(self, path: str) -> Any:
        return self.var(path).value

    def __setitem__(self, path: str, value: Any) -> None:
        self.var(path).value = value

    def __contains__(self, path: str) -> bool:
        try:
            self.var(path)
        except PathError:
            return False
        return True

    def force(self, path: str, value: Any) -> None:
        self.var(path).force(value)

    def unforce(self, path: str) -> None:
        self.var(path).unforce()

    def roots(self) -> list[str]:
        return [r["path"] for r in self.manifest.get("roots", [])]

    def __repr__(self) -> str:
        return f"<Plc {self.library.name} ({self.backend}) scan {self.scan_count} t={self.time_ns} ns>"
