"""Demonstration data: trials of fork observations and knife actions.

A *trial* is one continuous demonstration; a :class:`Demonstrations` set is an ordered list of
trials sharing channel names and sample rate [Hz]. Loading checks everything once, by the rules of
:mod:`learning.data.checks`, and raises :class:`DataFormatError` naming file, field and row (rows
count from 0: an index into the stacked NPZ arrays, or the CSV data row, with its 1-based file line);
saving is atomic.

Formats: an NPZ file (``obs`` (T, d_o), ``act`` (T, d_u), ``trial`` int (T,); optional ``subject``,
``mode`` (−1 = unknown), ``voluntary`` (T, d_v), ``t`` [s], ``obs_names`` / ``act_names`` /
``vol_names``, ``rate_hz``; one of ``t`` and ``rate_hz`` required, any other field an error), or a
folder of ``trial_<id>.csv`` files (columns ``t`` [s], ``obs_<name>``, ``act_<name>``, optional
``mode``, ``subject``, ``vol_<name>``; header order is channel order). A trial's median sample
interval must match 1 / ``rate_hz`` within 5 %. The full table: docs/design.md, "Data format".

Modules: :mod:`~learning.data.model` (``Trial``, ``Demonstrations``), :mod:`~learning.data.checks`
(the rules), :mod:`~learning.data.npz` and :mod:`~learning.data.csv` (the formats),
:mod:`~learning.data.splits` (train/test splits by trial or subject).
"""

from __future__ import annotations

import os

from .checks import RATE_TOLERANCE, DataFormatError
from .csv import csv_bytes_estimate, load_csv_folder, save_csv_folder
from .model import Demonstrations, PathLike, Trial
from .npz import NPZ_FIELDS, load_npz, npz_arrays, save_npz
from .splits import split_by_subject, split_by_trial

__all__ = [
    "NPZ_FIELDS",
    "RATE_TOLERANCE",
    "DataFormatError",
    "Demonstrations",
    "Trial",
    "load",
    "load_csv_folder",
    "load_npz",
    "save",
    "saved_bytes_estimate",
    "save_csv_folder",
    "save_npz",
    "split_by_subject",
    "split_by_trial",
]


def load(path: PathLike) -> Demonstrations:
    """Load a data set: a ``.npz`` file or a CSV folder."""
    p = str(path)
    if os.path.isdir(p):
        return load_csv_folder(p)
    if p.lower().endswith(".npz"):
        return load_npz(p)
    if not os.path.exists(p):
        raise DataFormatError("no such file or folder", path=p)
    raise DataFormatError("unknown format: expected a .npz file or a folder of trial_<id>.csv files", path=p)


def save(demos: Demonstrations, path: PathLike) -> None:
    """Save by suffix: ``.npz`` → NPZ file, anything else → CSV folder. Atomic."""
    if str(path).lower().endswith(".npz"):
        save_npz(demos, path)
    else:
        save_csv_folder(demos, path)


def saved_bytes_estimate(demos: Demonstrations, path: PathLike) -> float:
    """About how many bytes :func:`save` writes for ``demos`` at ``path`` (by suffix, as :func:`save`):
    an NPZ file's arrays plus its archive headers (uncompressed: within 1 %), a CSV folder's rows as
    formatted (:func:`learning.data.csv.csv_bytes_estimate`)."""
    if str(path).lower().endswith(".npz"):
        arrays = npz_arrays(demos)
        return float(sum(a.nbytes + 250 for a in arrays.values()))
    return csv_bytes_estimate(demos)
