"""`linmot-st init DIR`: copy the project template (examples/user_project) into a new folder."""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

# what a test run leaves in the template's folder, never part of a new project
IGNORED = ("__pycache__", "*.pyc", ".pytest_cache", ".cache", "plc-tests.xml", "build")


def register(subparsers) -> None:
    p = subparsers.add_parser("init", help="create a PLC project of your own that uses the library, with tests and CI",
                              description=__doc__.splitlines()[0])
    p.add_argument("dir", metavar="DIR", help="the folder to create (it must not exist, or be empty)")
    p.set_defaults(func=cmd_init)


def create(folder: Path) -> list[Path]:
    """Copy the template into `folder`; returns the files written. FileExistsError if it holds anything."""
    from linmot_st.resources import project_template

    template = project_template()
    if folder.exists() and (not folder.is_dir() or any(folder.iterdir())):
        raise FileExistsError(f"{folder}: exists and is not an empty folder")
    shutil.copytree(template, folder, ignore=shutil.ignore_patterns(*IGNORED), dirs_exist_ok=True)
    return sorted(p for p in folder.rglob("*") if p.is_file())


def cmd_init(args) -> int:
    folder = Path(args.dir).expanduser()
    try:
        files = create(folder)
    except (OSError, FileNotFoundError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    print(f"created {folder}: {len(files)} files (a station that commissions its axis from drive.pvl, "
          "tests in Python and ST, CI for GitHub and GitLab)")
    print(f"next: cd {folder} && pytest    (README.md says what is where)")
    return 0
