"""Which ST files a build reads: the entry file, the include root, and the `{#include}` closure.

The include root is the nearest ancestor of the entry file that holds `st_lib/linmot.st`, else the current
directory (docs/architecture.md 1), unless the caller names it. iec2c resolves `{#include "a/b.st"}` against
its -I folder, then its working directory, which is why it runs with the include root as its working
directory; the builtin compiler resolves them the same way. A root that holds no st_lib/ gets the library
tree (linmot_st.resources: the installed package's copy, or the checkout) on its search path, searched
first as iec2c searches its -I folder first. The closure found here feeds the build cache key.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field
from pathlib import Path

from linmot_st import resources

LIBRARY_MARKER = resources.LIBRARY_MARKER
PROJECT_ENTRY = "plc.st"

# MatIEC's include pragma; only at top level, so comments are removed before searching for it
INCLUDE_PRAGMA = re.compile(r'\{\s*#include\s+"([^"]+)"\s*\}')
COMMENT = re.compile(r"\(\*.*?\*\)", re.S)


class SourceError(Exception):
    """The entry file or project folder does not exist or is not usable."""


@dataclass
class Sources:
    entry: Path                 # absolute
    root: Path                  # include root, absolute
    files: list[Path] = field(default_factory=list)     # entry first, then includes in discovery order
    missing: list[str] = field(default_factory=list)    # include paths that resolve to no file
    search: list[Path] = field(default_factory=list)    # folders searched before the root (library_search)

    @property
    def in_tree(self) -> bool:
        """Whether the include root is a library tree (it holds st_lib/linmot.st), not just the cwd."""
        return (self.root / LIBRARY_MARKER).is_file()

    @property
    def writable_tree(self) -> bool:
        """A library tree whose build/ folder may hold the cache: not the installed package's copy."""
        return self.in_tree and not resources.is_installed_tree(self.root)

    @property
    def entry_rel(self) -> str:
        """The entry file as iec2c is given it: relative to the include root where possible."""
        return rel_name(self.entry, self.root)


def rel_name(path: Path, root: Path) -> str:
    try:
        return path.relative_to(root).as_posix()
    except ValueError:
        return str(path)


def resolve_entry(path: str | os.PathLike) -> Path:
    """A .st file, or a project folder whose entry file is plc.st."""
    p = Path(path).expanduser()
    if p.is_dir():
        entry = p / PROJECT_ENTRY
        if not entry.is_file():
            raise SourceError(f"{p}: a project folder needs an entry file {PROJECT_ENTRY}")
        return entry.resolve()
    if not p.exists():
        raise SourceError(f"{p}: no such file or folder")
    if p.suffix.lower() != ".st":
        raise SourceError(f"{p}: expected a .st file or a project folder")
    return p.resolve()


def include_root(entry: Path, cwd: Path | None = None) -> Path:
    for folder in entry.parents:
        if (folder / LIBRARY_MARKER).is_file():
            return folder
    return (cwd or Path.cwd()).resolve()


def library_search(root: Path) -> list[Path]:
    """The folders searched for an include before `root`: none when the root is a library tree itself,
    else the library tree, so that `{#include "st_lib/linmot.st"}` works in a project anywhere."""
    if (root / LIBRARY_MARKER).is_file():
        return []
    try:
        return [resources.library_tree()]
    except resources.LibraryNotFound:
        return []


def find_includes(text: str) -> list[str]:
    return INCLUDE_PRAGMA.findall(COMMENT.sub(" ", text))


def resolve_include(name: str, root: Path, search: list[Path] = ()) -> Path | None:
    """iec2c's order: its -I folder (given in `search`), then the working directory (the root). A search
    folder serves only what it shares as a library tree: st_lib/ and plc_project/ (the matiec backend's
    -I folder holds just those beside MatIEC's own library)."""
    shared = Path(name).parts[:1] and Path(name).parts[0] in resources.TREES
    for folder in [*(search if shared else ()), root]:
        candidate = folder / name
        if candidate.is_file():
            return candidate.resolve()
    return None


def collect(path: str | os.PathLike, cwd: Path | None = None, search: list[Path] | None = None,
            root: str | os.PathLike | None = None) -> Sources:
    """The sources of a build. `root` names the include root (default: include_root()); `search` the
    folders searched before it (default: library_search(root))."""
    entry = resolve_entry(path)
    if root is not None:
        root = Path(root).expanduser().resolve()
        if not root.is_dir():
            raise SourceError(f"{root}: the include root is not a folder")
    else:
        root = include_root(entry, cwd)
    search = library_search(root) if search is None else [Path(p) for p in search]
    sources = Sources(entry=entry, root=root, search=search)
    seen: set[Path] = set()
    pending = [entry]
    while pending:
        f = pending.pop(0)
        if f in seen:
            continue
        seen.add(f)
        sources.files.append(f)
        for name in find_includes(f.read_text(encoding="latin-1")):
            target = resolve_include(name, root, search)
            if target is None:
                if name not in sources.missing:
                    sources.missing.append(name)
            elif target not in seen:
                pending.append(target)
    return sources
