"""The user's PLC project as the pytest plugin sees it: where it is, what to build, the drives of a rig.

Everything comes from ini options (pyproject.toml [tool.pytest.ini_options], pytest.ini, ...) with the
defaults of a project made by `linmot-st init`; `--linmot-backend` overrides the backend. Builds are cached
twice: on disk by content (the toolchain's cache) and per session here, so a test session builds each
entry file once per backend.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import pytest

from linmot_st.toolchain import BuildResult, build, choose_backend

# ini name -> (help, default)
INI = {
    "linmot_st_root": ("include root of the project's ST (default: the pytest rootdir)", ""),
    "linmot_st_entry": ("the PLC program's entry file, relative to the root", "plc.st"),
    "linmot_st_mailbox": ("the IEC path of the PLC's T_CanMailbox", "CONFIG0.RES0.CAN0"),
    "linmot_st_backend": ("ST compiler: auto (MatIEC where installed), matiec or builtin", "auto"),
    "linmot_st_nodes": ("node IDs of the emulated drives of a rig, e.g. 1 2", "1"),
    "linmot_st_bitrate": ("bit rate of the simulated bus in bit/s", "500000"),
    "linmot_st_timings": ("drive timings: real (the E1100's, in virtual time) or fast", "real"),
    "linmot_st_st_files": ("file name patterns of tests written in ST", "test_*.st"),
    "linmot_st_st_scans": ("scan budget of an ST test without its own MaxScans or Timeout", "10000"),
    "linmot_st_st_task": ("task interval of the ST test runner", "T#1ms"),
}


def ini(config: pytest.Config, name: str) -> str:
    value = config.getini(name)
    return (value if isinstance(value, str) else " ".join(value)).strip() or INI[name][1]


@dataclass
class Project:
    root: Path
    entry: str = "plc.st"
    mailbox: str = "CONFIG0.RES0.CAN0"
    backend: str = "auto"
    nodes: tuple[int, ...] = (1,)
    bitrate: int = 500_000
    timings: str = "real"
    st_files: tuple[str, ...] = ("test_*.st",)
    st_scans: int = 10_000
    st_task: str = "T#1ms"
    _builds: dict = field(default_factory=dict, repr=False)

    @classmethod
    def from_config(cls, config: pytest.Config) -> Project:
        root = ini(config, "linmot_st_root")
        base = Path(str(config.rootpath))
        backend = config.getoption("linmot_backend", None) or ini(config, "linmot_st_backend")
        return cls(
            root=(base / root).resolve() if root else base.resolve(),
            entry=ini(config, "linmot_st_entry"),
            mailbox=ini(config, "linmot_st_mailbox"),
            backend=backend,
            nodes=tuple(int(n, 0) for n in ini(config, "linmot_st_nodes").replace(",", " ").split()),
            bitrate=int(ini(config, "linmot_st_bitrate")),
            timings=ini(config, "linmot_st_timings"),
            st_files=tuple(ini(config, "linmot_st_st_files").split()),
            st_scans=int(ini(config, "linmot_st_st_scans")),
            st_task=ini(config, "linmot_st_st_task"),
        )

    def backend_of(self, backend: str | None = None) -> str:
        return choose_backend(backend or self.backend)

    def build(self, entry: str | Path | None = None, backend: str | None = None) -> BuildResult:
        """The BuildResult of an entry file (default the project's), relative to the root or absolute."""
        chosen = self.backend_of(backend)
        path = Path(entry) if entry is not None else Path(self.entry)
        path = path if path.is_absolute() else self.root / path
        key = (str(path), chosen)
        if key not in self._builds:
            try:
                self._builds[key] = build(path, backend=chosen, root=self.root)
            except Exception as exc:        # noqa: BLE001 - every test of this build fails the same way
                self._builds[key] = exc
        got = self._builds[key]
        if isinstance(got, Exception):
            raise got
        return got


_PROJECT = pytest.StashKey[Project]()


def project_of(config: pytest.Config) -> Project:
    """The session's Project, made once from its config (the plugin's fixtures and the ST tests share it)."""
    if _PROJECT not in config.stash:
        config.stash[_PROJECT] = Project.from_config(config)
    return config.stash[_PROJECT]
