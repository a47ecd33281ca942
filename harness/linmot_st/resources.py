"""Where the ST library (st_lib/) and the PLC project (plc_project/) are, for every command that needs them.

In a source checkout (and its editable install) they sit at the repository root, beside harness/. A wheel
carries a copy of both inside this package (setup.py copies them at build time), so an installed
`linmot-st` finds them in site-packages/linmot_st/. `library_tree()` is the folder that holds both; the
toolchain puts it on the include path of a build whose own folder holds no st_lib/ (docs/toolchain.md,
"The library on the include path"), which is how a user's project outside any checkout, and every command
run from an empty folder, gets `{#include "st_lib/linmot.st"}` and `{#include "plc_project/..."}`.
"""

from __future__ import annotations

import os
from pathlib import Path

PACKAGE = Path(__file__).resolve().parent
CHECKOUT = PACKAGE.parents[1]                 # harness/linmot_st -> the repository root
LIBRARY_MARKER = Path("st_lib") / "linmot.st"
TREES = ("st_lib", "plc_project")              # the include path's folders (toolchain.sources)
PROJECT_TEMPLATE = Path("examples") / "user_project"   # what `linmot-st init` copies; a wheel carries it too


class LibraryNotFound(FileNotFoundError):
    """Neither this package nor a checkout around it holds st_lib/linmot.st (a broken install)."""


def library_tree() -> Path:
    """The folder that holds st_lib/ and plc_project/: this package when installed from a wheel or sdist,
    else the source checkout."""
    for folder in (PACKAGE, CHECKOUT):
        if (folder / LIBRARY_MARKER).is_file():
            return folder
    raise LibraryNotFound(f"st_lib/linmot.st is neither in {PACKAGE} (an installed linmot-st) nor in {CHECKOUT} "
                          "(a source checkout): reinstall linmot-st")


def project_template() -> Path:
    """The folder `linmot-st init` copies: examples/user_project of the library tree."""
    folder = library_tree() / PROJECT_TEMPLATE
    if not (folder / "plc.st").is_file():
        raise LibraryNotFound(f"{folder}: the project template is missing: reinstall linmot-st")
    return folder


def installed() -> bool:
    """True when the library comes with the installed package (not from a checkout)."""
    return (PACKAGE / LIBRARY_MARKER).is_file()


def is_installed_tree(folder: Path) -> bool:
    """Whether `folder` is the installed package's copy of the library: never a place to write builds in."""
    try:
        return folder.resolve() == PACKAGE and installed()
    except OSError:
        return False


def user_cache_dir() -> Path:
    """$XDG_CACHE_HOME/linmot-st, else ~/.cache/linmot-st: where builds and generated files go when no
    source checkout is there to hold them."""
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg).expanduser() if xdg and Path(xdg).is_absolute() else Path.home() / ".cache"
    return base / "linmot-st"


def work_dir(name: str) -> Path:
    """A folder for files a command generates (e.g. an entry file for another dataset): build/NAME in a
    checkout (`make clean` removes it), else NAME in the user's cache folder, never inside the installed
    package."""
    return (user_cache_dir() if installed() else CHECKOUT / "build") / name
