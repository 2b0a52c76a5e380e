"""Keep numba's on-disk compile cache consistent with the sources of the compiled code.

numba checks a cached function against the modification time of its own source file only. The
machine code of a jvl_gym step has its callees inlined: a family's firmware and plant, the
engine's drivers and a task's hooks, from many files. After an edit of a callee, the cached step
of the caller would still be loaded, with the old callee inside. So the package keeps one stamp:
a hash of every source file of the package that uses numba and of every file under the folders
that hold the facts compiled code freezes in as constants (a family's constants and register
table, the register formats: :data:`FROZEN_FOLDERS`). When the sources no longer match
the stamp, every cache file under the package is removed before anything compiles, and the stamp
is rewritten. An installed package that never changes computes the hash once per process (a few
milliseconds) and removes nothing.
"""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

__all__ = ["source_hash", "drop_stale_caches"]

#: the stamp file, beside the package's top-level ``__init__.py``
STAMP_NAME = "__pycache__/jvl_gym.compiled-sources"
#: numba's cache files: index and machine code
CACHE_SUFFIXES = (".nbi", ".nbc")


#: folders under the package whose Python and CSV files all count as compiled sources: numba
#: freezes the module-level numbers of a family (its constants, its register table's numbers and
#: ranges) and of the register formats into the machine code of the functions that read them
FROZEN_FOLDERS = ("families", "registers")
#: the files of :data:`FROZEN_FOLDERS` that count
FROZEN_SUFFIXES = (".py", ".csv")


def _compiled_source(root: Path, path: Path, text: bytes) -> bool:
    """True when ``path`` (text ``text``) can change the machine code of a compiled function."""
    if path.suffix == ".py" and (b"numba" in text or b"njit" in text):
        return True
    top = path.relative_to(root).parts[0]
    return top in FROZEN_FOLDERS and path.suffix in FROZEN_SUFFIXES


def source_hash(root: Path) -> str:
    """SHA-256 over the path and text of every file under ``root`` that compiled code depends
    on: the ``*.py`` files that use numba, and the ``*.py`` and ``*.csv`` files under
    :data:`FROZEN_FOLDERS`.

    Parameters
    ----------
    root : Path
        Package directory.

    Returns
    -------
    str
        Hex digest; it changes with any edit of compiled code (and only then).
    """
    digest = hashlib.sha256()
    paths = [p for suffix in FROZEN_SUFFIXES for p in root.rglob(f"*{suffix}")]
    for path in sorted(paths):
        text = path.read_bytes()
        if _compiled_source(root, path, text):
            digest.update(path.relative_to(root).as_posix().encode())
            digest.update(b"\0")
            digest.update(text)
    return digest.hexdigest()


def _cache_folders(root: Path) -> list[Path]:
    """Where numba keeps the caches of ``root``'s sources: beside them and, when
    ``NUMBA_CACHE_DIR`` is set, in its folder ``<dir name>_<SHA-1 of the dir's absolute path>``
    for each source folder (numba's ``_CacheLocator.get_suitable_cache_subpath``)."""
    folders = [root]
    user_dir = os.environ.get("NUMBA_CACHE_DIR")
    if user_dir:
        for folder in {p.parent for p in root.rglob("*.py")}:
            path = os.path.abspath(folder)
            hashed = hashlib.sha1(path.encode()).hexdigest()
            mirrored = Path(user_dir) / f"{os.path.basename(path)}_{hashed}"
            if mirrored.is_dir():
                folders.append(mirrored)
    return folders


def drop_stale_caches(root: Path) -> int:
    """Remove the numba cache files under ``root`` if its compiled sources changed since the
    stamp was written, then write the stamp.

    Parameters
    ----------
    root : Path
        Package directory.

    Returns
    -------
    int
        Number of cache files removed, beside the sources and under ``NUMBA_CACHE_DIR``. A
        read-only installation removes nothing and keeps working (numba then uses its own
        cache directory).
    """
    stamp = root / STAMP_NAME
    current = source_hash(root)
    try:
        if stamp.read_text() == current:
            return 0
    except OSError:
        pass
    removed = 0
    for folder in _cache_folders(root):
        for path in folder.rglob("*"):
            if path.suffix in CACHE_SUFFIXES:
                try:
                    path.unlink()
                    removed += 1
                except OSError:
                    pass
    try:
        stamp.parent.mkdir(exist_ok=True)
        partial = stamp.with_name(f"{stamp.name}.{os.getpid()}")
        partial.write_text(current)
        partial.replace(stamp)  # atomic: a concurrent process reads the old or the new stamp
    except OSError:
        pass
    return removed
