"""Atomic file writes: a temporary file in the target's folder, then a rename; the project's JSON writer.

A reader never sees a half-written file, and a failed write leaves the previous
file (if any) untouched. The temporary file is created with ``os.open(...,
O_CREAT | O_EXCL, 0o666)`` and temporary folders with ``os.mkdir(..., 0o777)``,
so the kernel applies the process umask (and any default ACL of the folder)
itself: the result has the permissions an ordinary ``open(path, "w")`` or
``mkdir`` would give, and the umask is never changed (changing it to read it
would race with other threads). :mod:`tempfile` cannot be used for this: it
creates files 0600 and folders 0700.

:func:`write_json` is the one function that writes the project's JSON files (reports,
comparisons, tune results, bundle files): atomic, strict JSON (no NaN), a final newline.
"""

from __future__ import annotations

import json
import math
import os
import secrets
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Any, Callable

__all__ = ["NON_FINITE", "atomic_open", "default_dir_mode", "default_file_mode", "json_safe", "make_temp_dir",
           "write_json"]

#: what :func:`write_json` does with NaN and ±∞: write null, or refuse (ValueError)
NON_FINITE: tuple[str, ...] = ("null", "raise")

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


def json_safe(x: Any) -> Any:
    """``x`` with every non-finite float (in dicts, lists and tuples, recursively) as None: strict JSON."""
    if isinstance(x, dict):
        return {k: json_safe(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [json_safe(v) for v in x]
    if isinstance(x, float) and not math.isfinite(x):
        return None
    return x


def write_json(obj: Any, path: str | os.PathLike, *, indent: int | None = 2, non_finite: str = "null",
               default: Callable[[Any], Any] | None = None, fsync: bool = True) -> None:
    """Write ``obj`` to ``path`` as JSON with a final newline, atomically (:func:`atomic_open`).

    ``non_finite`` (:data:`NON_FINITE`): ``"null"`` writes NaN and ±∞ floats as null (the
    reports: an undefined figure), ``"raise"`` refuses them with a ValueError and leaves
    ``path`` as it was (files whose numbers must all be there, e.g. a model bundle's).
    ``default``: as :func:`json.dump`'s, for objects JSON does not know (None: TypeError).
    """
    if non_finite not in NON_FINITE:
        raise ValueError(f"write_json: non_finite must be one of {NON_FINITE}, got {non_finite!r}")
    data = json_safe(obj) if non_finite == "null" else obj
    text = json.dumps(data, indent=indent, allow_nan=False, default=default)  # fails before the file is touched
    with atomic_open(path, "w", fsync=fsync) as f:
        f.write(text + "\n")
