"""Atomic file writes: a temporary file in the target's folder, then a rename.

A reader never sees a half-written file, and a failed write leaves the previous
file (if any) untouched. :func:`tempfile.mkstemp` creates files readable by the
owner only (mode 0600); the result here gets the permissions an ordinary
``open(path, "w")`` would give (0666 less the process umask).
"""

from __future__ import annotations

import os
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Iterator

__all__ = ["atomic_open", "default_file_mode", "default_dir_mode"]


def _umask() -> int:
    mask = os.umask(0o022)  # the only portable way to read it: set, then restore
    os.umask(mask)
    return mask


def default_file_mode() -> int:
    """Permissions of a newly created ordinary file: ``0o666 & ~umask``."""
    return 0o666 & ~_umask()


def default_dir_mode() -> int:
    """Permissions of a newly created folder: ``0o777 & ~umask``."""
    return 0o777 & ~_umask()


@contextmanager
def atomic_open(path: str | os.PathLike, mode: str = "w", *, fsync: bool = True
                ) -> Iterator[IO]:
    """Open a temporary file beside ``path``; on success rename it onto ``path``.

    ``mode`` is ``"w"`` (text, UTF-8) or ``"wb"``. The parent folder is created if
    missing. On any exception the temporary file is removed and ``path`` is left
    as it was.
    """
    if mode not in ("w", "wb"):
        raise ValueError(f"atomic_open: mode must be 'w' or 'wb', got {mode!r}")
    p = Path(path)
    p.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=p.parent, prefix=f".{p.name}.", suffix=".tmp")
    try:
        with os.fdopen(fd, mode, **({"encoding": "utf-8"} if mode == "w" else {})) as f:
            yield f
            f.flush()
            if fsync:
                os.fsync(f.fileno())
        os.chmod(tmp, default_file_mode())
        os.replace(tmp, p)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
