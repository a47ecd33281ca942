"""The content-addressed build cache.

An entry is a folder named by the SHA-256 of everything a build depends on: the content of each source
read (entry file and includes), the backend and its version, the C compiler and its flags, the glue
sources and the code of the toolchain that generates C. A build writes into a private staging folder and
renames it into place, so concurrent builders (pytest -n 2) never see half an entry.

The key is computed from the sources found by scanning `{#include}` pragmas. The backend also reports
what it actually read; those files and their hashes are stored in the entry and checked on a hit, so a
source the scan missed still invalidates the entry.
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import tempfile
from pathlib import Path

from linmot_st.resources import user_cache_dir

KEY_VERSION = "linmot-st-cache-1"
LIBRARY_NAME = "libplc.so"
MANIFEST_NAME = "manifest.json"
META_NAME = "meta.json"


def default_dir(root: Path, in_tree: bool = True) -> Path:
    """$LINMOT_ST_CACHE; else build/cache in a library tree (`make clean` removes it); else, for a file
    outside any tree, the user's cache folder ($XDG_CACHE_HOME/linmot-st or ~/.cache/linmot-st) rather
    than a build/ folder in whatever directory the command ran from (so too for the installed package's copy
of the library, which is no place to write)."""
    env = os.environ.get("LINMOT_ST_CACHE")
    if env:
        return Path(env).expanduser()
    if in_tree:
        return root / "build" / "cache"
    return user_cache_dir()


def file_digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def make_key(parts: dict) -> str:
    blob = json.dumps({"version": KEY_VERSION, **parts}, sort_keys=True).encode()
    return hashlib.sha256(blob).hexdigest()


class Cache:
    def __init__(self, folder: Path):
        self.folder = folder

    def entry(self, key: str) -> Path:
        return self.folder / key[:2] / key

    def lookup(self, key: str) -> Path | None:
        """The entry folder if it is complete and every source it recorded is unchanged."""
        entry = self.entry(key)
        meta_path = entry / META_NAME
        try:
            meta = json.loads(meta_path.read_text())
        except (OSError, ValueError):
            return None
        if not (entry / LIBRARY_NAME).is_file() or not (entry / MANIFEST_NAME).is_file():
            return None
        for path, digest in meta.get("sources_read", {}).items():
            p = Path(path)
            try:
                if file_digest(p) != digest:
                    return None
            except OSError:
                return None
        return entry

    def staging(self) -> Path:
        self.folder.mkdir(parents=True, exist_ok=True)
        return Path(tempfile.mkdtemp(prefix="staging-", dir=self.folder))

    def commit(self, key: str, staging: Path, meta: dict) -> Path:
        (staging / META_NAME).write_text(json.dumps(meta, indent=1, sort_keys=True))
        entry = self.entry(key)
        entry.parent.mkdir(parents=True, exist_ok=True)
        if entry.exists() and self.lookup(key) is not None:
            # a concurrent builder committed the same build first: keep theirs, which may be in use
            shutil.rmtree(staging, ignore_errors=True)
            return entry
        if entry.exists():   # stale: a source the include scan missed has changed since
            old = entry.with_name(entry.name + f".old-{os.getpid()}-{id(staging)}")
            try:
                os.rename(entry, old)
                shutil.rmtree(old, ignore_errors=True)
            except OSError:
                pass
        try:
            os.rename(staging, entry)
        except OSError:   # a concurrent builder committed the same key first: use theirs
            shutil.rmtree(staging, ignore_errors=True)
        return entry

    def discard(self, staging: Path) -> None:
        shutil.rmtree(staging, ignore_errors=True)
