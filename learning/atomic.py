"""Atomic file writes: a temporary file in the target's folder, then a rename.

A reader never sees a half-written file, and a failed write leaves the previous
file (if any) untouched. The temporary file is created with ``os.open(...,
O_CREAT | O_EXCL, 0o666)`` and temporary folders with ``os.mkdir(..., 0o777)``,
so the kernel applies the process umask (and any default ACL of the folder)
itself: the result has the permissions an ordinary ``open(path, "w")`` or
``mkdir`` would give, and the umask is never changed (changing it to read it
would race with other threads). :mod:`tempfile` cannot be used for this: it
creates files 0600 and folders 0700.
"""

from __future__ import annotations

import os
import secrets
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO

__all__ = ["atomic_open", "default_dir_mode", "default_file_mode", "make_temp_dir"]

_ATTEMPTS = 100  # random names tried before giving up (a clash is ~2⁻⁴⁸ each)


def _temp_name(folder: str | os.PathLike, prefix: str, suffix: str) -> str:
    return os.path.join(folder, f"{prefix}{secrets.token_hex(6)}{suffix}")


def _create_temp_file(folder: str | os.PathLike, prefix: str, suffix: str) -> tuple[int, str]:
    """(fd, path) of a new, exclusively created file with mode 0o666 & ~umask."""
    flags = os.O_CREAT | os.O_EXCL | os.O_WRONLY | getattr(os, "O_CLOEXEC", 0) | getattr(os, "O_BINARY", 0)
    for _ in range(_ATTEMPTS):
        name = _temp_name(folder, prefix, suffix)
        try:
            return os.open(name, flags, 0o666), name
        except FileExistsError:
            continue
    raise FileExistsError(f"{folder}: no free temporary file name after {_ATTEMPTS} attempts")


def make_temp_dir(folder: str | os.PathLike, prefix: str = ".", suffix: str = ".tmp") -> str:
    """Create a new folder inside ``folder`` with mode 0o777 & ~umask; return its path."""
    for _ in range(_ATTEMPTS):
        name = _temp_name(folder, prefix, suffix)
        try:
            os.mkdir(name, 0o777)
            return name
        except FileExistsError:
            continue
    raise FileExistsError(f"{folder}: no free temporary folder name after {_ATTEMPTS} attempts")


def _umask() -> int:
    """The process umask, read without changing it.

    Linux reports it in /proc/self/status; elsewhere a probe file is created in a
    fresh temporary folder and its permissions are read back.
    """
    try:
        with open("/proc/self/status", encoding="ascii") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    with tempfile.TemporaryDirectory() as d:
        fd, name = _create_temp_file(d, "probe", "")
        os.close(fd)
        return 0o666 & ~os.stat(name).st_mode & 0o777


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
    fd, tmp = _create_temp_file(p.parent, f".{p.name}.", ".tmp")
    try:
        with os.fdopen(fd, mode, **({"encoding": "utf-8"} if mode == "w" else {})) as f:
            yield f
            f.flush()
            if fsync:
                os.fsync(f.fileno())
        os.replace(tmp, p)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise
