"""What every subcommand is built from: the :class:`Command` record, errors, argument types.

A subcommand module defines a :class:`Command` (name, one-line help, a function
that adds its arguments to an ``argparse`` parser, a function that runs it and
returns the exit status) and :data:`mpcshare.cli.COMMANDS` lists it. It imports
from here, never from :mod:`mpcshare.cli` (which imports the subcommand modules).

Exit status: 0 success, 1 unusable input (:class:`CommandError`, one clear message
on stderr), 2 usage error (argparse, including the argument types below).
"""

from __future__ import annotations

import argparse
import math
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from learning.data import DataFormatError, Demonstrations, load
from mpcshare.errors import MpcshareError

__all__ = ["Command", "CommandError", "positive_int", "positive_float", "nonnegative_float", "percentile",
           "prepare_output_folder", "load_or_fail", "human_bytes", "remove_empty_output_folders"]


class CommandError(MpcshareError, RuntimeError):
    """A subcommand cannot go on; the message is printed and the exit status is 1."""


@dataclass(frozen=True)
class Command:
    """A subcommand: its name, one-line help, how it adds its arguments, and what it runs.

    ``run(args)`` returns the exit status; it raises :class:`CommandError` for input
    it cannot use (the message is printed, exit status 1).
    """

    name: str
    help: str
    add_arguments: Callable[[argparse.ArgumentParser], None]
    run: Callable[[argparse.Namespace], int]


# ------------------------------------------------------- argument types
# argparse turns an ArgumentTypeError into "argument --x: <message>" and exit status 2.

def _number(text: str, kind: type, ok: Callable[[float], bool], what: str) -> float:
    try:
        value = kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
    if (isinstance(value, float) and not math.isfinite(value)) or not ok(value):
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
    return value


def positive_int(text: str) -> int:
    """argparse type: an integer ≥ 1."""
    return int(_number(text, int, lambda v: v >= 1, "an integer >= 1"))


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0."""
    return float(_number(text, float, lambda v: v > 0, "a number > 0"))


def nonnegative_float(text: str) -> float:
    """argparse type: a finite number ≥ 0."""
    return float(_number(text, float, lambda v: v >= 0, "a number >= 0"))


# ------------------------------------------------------- files

def percentile(text: str) -> float:
    """argparse type: a percentile, a number from 0 to 100."""
    return float(_number(text, float, lambda v: 0 <= v <= 100, "a number from 0 to 100"))


#: the folders :func:`prepare_output_folder` created during the present command, in creation order
_CREATED: list[Path] = []


def prepare_output_folder(path: str | Path) -> Path:
    """Create the output folder (and parents) or raise :class:`CommandError` saying why.

    Checked before any long work starts, so that a typo in ``--out`` does not
    cost a whole analysis. The folders it creates are remembered: a command that fails
    leaves none of them behind empty (:func:`remove_empty_output_folders`, called by the CLI).
    """
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise CommandError(f"--out {out}: exists and is not a folder")
    new = [p for p in (out, *out.parents) if not p.exists()][::-1]  # outermost first
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CommandError(f"--out {out}: cannot create the folder ({exc.strerror or exc})") from exc
    _CREATED.extend(new)
    if not os.access(out, os.W_OK | os.X_OK):
        raise CommandError(f"--out {out}: folder is not writable")
    return out


def remove_empty_output_folders(keep: bool = False) -> list[Path]:
    """After a command: unless ``keep``, remove the folders :func:`prepare_output_folder` created that hold
    no file (their empty sub-folders too, deepest first); forget them either way. Returns those removed."""
    created, removed = list(_CREATED), []
    _CREATED.clear()
    if keep:
        return removed
    for top in reversed(created):
        if not top.is_dir():
            continue
        for sub in sorted((p for p in top.rglob("*") if p.is_dir()), key=lambda p: len(p.parts), reverse=True):
            if not any(sub.iterdir()):
                sub.rmdir()
                removed.append(sub)
        if not any(top.iterdir()):
            top.rmdir()
            removed.append(top)
    return removed


def human_bytes(n: float) -> str:
    """A size for a person: ``"830 kB"``, ``"14 MB"``, ``"1.2 GB"`` (decimal units, two significant digits
    or more)."""
    for unit, scale in (("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= scale:
            v = n / scale
            return f"{v:.1f} {unit}" if v < 10 else f"{v:.0f} {unit}"
    return f"{n:.0f} bytes"


def load_or_fail(path: str) -> Demonstrations:
    """Load a data set or raise :class:`CommandError` with the loader's clear message."""
    try:
        return load(path)
    except DataFormatError as exc:
        # the loader's message starts with the file it names: say the path once
        said = exc.path is not None and str(exc).startswith(str(exc.path))
        raise CommandError(f"cannot use {exc}" if said else f"cannot use {path}: {exc}") from exc
    except OSError as exc:
        raise CommandError(f"cannot read {path}: {exc}") from exc
