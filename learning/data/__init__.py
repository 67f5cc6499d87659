"""Demonstration data: trials of fork observations and knife actions.

A *trial* is one continuous demonstration; a :class:`Demonstrations` set is an
ordered list of trials sharing channel names and sample rate. Loading checks
everything once, by the rules of :mod:`learning.data.checks`, and raises
:class:`DataFormatError` naming file, field and row; saving is atomic.

Modules: :mod:`~learning.data.model` (``Trial``, ``Demonstrations``),
:mod:`~learning.data.checks` (the rules), :mod:`~learning.data.npz` and
:mod:`~learning.data.csv` (the formats), :mod:`~learning.data.splits`
(train/test splits by trial or subject).

Conventions
-----------
* Rows are counted from 0. In an NPZ file a row is an index into the stacked
  arrays (``obs[row]``); in a CSV file it is the data row (the first line after
  the header is row 0; the message also gives the 1-based file line).
* NPZ fields: ``obs`` (T, d_o), ``act`` (T, d_u), ``trial`` int (T,) (required);
  ``subject`` int (T,), ``mode`` int (T,) (−1 = unknown), ``voluntary`` (T, d_v),
  ``t`` (T,) [s], ``obs_names`` / ``act_names`` / ``vol_names`` string arrays,
  ``rate_hz`` scalar [Hz] (optional). Without ``t`` the time is built from
  ``rate_hz`` (each trial starts at 0 s); without ``rate_hz`` it is inferred from
  ``t`` (1 / median sample interval); one of the two is required. Any other field
  is an error.
* CSV folder: one file per trial named ``trial_<id>.csv`` (``<id>`` an integer,
  the trial id; ``trial_007.csv`` → 7; other ``*.csv`` files are an error, other
  files are ignored). Columns: ``t`` [s] (required), ``obs_<name>`` and
  ``act_<name>`` (at least one each), optional ``mode``, ``subject`` (constant in
  a file) and ``vol_<name>``. Header order defines channel order; every file must
  have the same columns. The rate is inferred from ``t``.
* A trial's sample interval must match ``1 / rate_hz`` within 5 % (median).
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
