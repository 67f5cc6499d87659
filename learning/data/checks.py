"""The rules a demonstration data set must satisfy, each coded once.

Every way into a :class:`~learning.data.Demonstrations` goes through these
functions exactly once: the NPZ reader and the CSV reader both build stacked
arrays and call :func:`learning.data.model.from_stacked_arrays`, and
:meth:`Demonstrations.validate` checks sets built in memory. An error names
file, field and row; :class:`Origin` translates a row of the stacked arrays
into the file it came from and the row within that file, and a channel into
the field the user wrote (an NPZ field such as ``obs`` with its column, or a
CSV column such as ``obs_x``).
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

import numpy as np

from learning.errors import LearningError

__all__ = [
    "CHANNEL_PREFIX",
    "RATE_TOLERANCE",
    "DataFormatError",
    "Origin",
    "TrialFields",
    "as_integer",
    "check_rate",
    "check_set",
    "check_shapes",
    "check_trial",
    "first_non_integer",
    "infer_rate",
    "rate_value",
]


class TrialFields(Protocol):
    """What the checks read of a trial (:class:`learning.data.Trial` has these fields)."""

    trial_id: int
    t: np.ndarray
    obs: np.ndarray
    act: np.ndarray
    mode: np.ndarray | None
    voluntary: np.ndarray | None


#: Relative tolerance between a trial's median sample interval and 1 / rate_hz.
RATE_TOLERANCE = 0.05
#: CSV column prefix of each channel field.
CHANNEL_PREFIX = {"obs": "obs_", "act": "act_", "voluntary": "vol_"}
#: The name list of each channel field.
NAME_FIELD = {"obs": "obs_names", "act": "act_names", "voluntary": "vol_names"}


class DataFormatError(LearningError, ValueError):
    """A data set that cannot be used; the message names file, field and row."""

    def __init__(self, message: str, *, path: str | None = None, field: str | None = None,
                 row: int | None = None) -> None:
        parts = []
        if path is not None:
            parts.append(str(path))
        if field is not None:
            parts.append(f"field '{field}'")
        if row is not None:
            parts.append(f"row {row}")
        prefix = ", ".join(parts)
        super().__init__(f"{prefix}: {message}" if prefix else message)
        self.path = path
        self.field = field
        self.row = row


@dataclass(frozen=True)
class Origin:
    """Where the rows being checked come from, so that an error names file, field and row.

    The rows are the concatenation of *parts*, each starting at ``part_starts[k]``:
    an NPZ file is one part; a CSV folder has one part per file (rows counted
    within the file); a set built in memory has one part per trial (rows counted
    within the trial).

    Attributes:
        path: the data set (NPZ file, CSV folder) or None; named by errors without a row.
        part_starts: first row of each part, ascending, starting at 0.
        part_paths: the file of each part (None: ``path`` for every part).
        csv_columns: name channel fields by CSV column (``obs_x``) instead of by
            NPZ field and column index (``obs``, "in column 0 ('x')").
        names: channel names per field ("obs", "act", "voluntary").
    """

    path: str | None = None
    part_starts: tuple[int, ...] = (0,)
    part_paths: tuple[str | None, ...] | None = None
    csv_columns: bool = False
    names: Mapping[str, Sequence[str]] = field(default_factory=dict)

    def locate(self, row: int) -> tuple[str | None, int]:
        """(file, row within that file's part) of a stacked row."""
        k = max(bisect_right(self.part_starts, row) - 1, 0)
        path = self.path if self.part_paths is None else self.part_paths[k]
        return path, row - self.part_starts[k]

    def field_name(self, kind: str, col: int | None = None) -> str:
        """The field the user wrote: NPZ field name, or CSV column name."""
        if not self.csv_columns:
            return kind
        if kind in CHANNEL_PREFIX:
            if col is None:
                return f"{CHANNEL_PREFIX[kind]}*"
            names = list(self.names.get(kind, ()))
            return CHANNEL_PREFIX[kind] + (names[col] if col < len(names) else str(col))
        if kind == "trial":
            # A CSV file has no trial column: its trial is the file, its rows the data rows.
            return "obs"
        return kind

    def error(self, message: str, kind: str, *, row: int | None = None, col: int | None = None,
              at: int | None = None) -> DataFormatError:
        """A :class:`DataFormatError` for stacked ``row`` (or for the part holding row ``at``)."""
        if row is not None:
            path, local = self.locate(row)
        else:
            path, local = (self.path if at is None else self.locate(at)[0]), None
        if col is not None and not self.csv_columns:
            names = list(self.names.get(kind, ()))
            message += f" in column {col}" + (f" ('{names[col]}')" if col < len(names) else "")
        return DataFormatError(message, path=path, field=self.field_name(kind, col), row=local)


def first_non_integer(values: np.ndarray) -> int | None:
    """Index of the first value that is not a finite integer, or None."""
    v = np.asarray(values)
    if v.dtype.kind in "iub":
        return None
    if v.dtype.kind != "f":
        return 0
    bad = ~np.isfinite(v) | (v != np.round(v))
    idx = np.flatnonzero(bad)
    return int(idx[0]) if idx.size else None


def as_integer(values: Any, kind: str, origin: Origin, *, start: int = 0,
               context: str = "") -> np.ndarray:
    """``values`` as int64 labels; a non-integer value is an error at its row."""
    a = np.asarray(values)
    bad = first_non_integer(a.reshape(-1))
    if bad is not None:
        raise origin.error(f"{context}{kind} must be integer, got {a.reshape(-1)[bad]!r}", kind,
                           row=start + bad)
    return a.astype(np.int64)


def check_shapes(n_rows: int, fields: Mapping[str, tuple[np.ndarray | None, int]],
                 origin: Origin, *, start: int = 0, context: str = "") -> None:
    """Every field (array, ndim) has ``ndim`` dimensions and ``n_rows`` rows (as ``obs``)."""
    for kind, (a, ndim) in fields.items():
        if a is None:
            continue
        if a.ndim != ndim:
            want = "(T,)" if ndim == 1 else "(T, d)"
            raise origin.error(f"{context}{kind} must have shape {want}, got shape {a.shape}",
                               kind, at=start)
        if a.shape[0] != n_rows:
            raise origin.error(f"{context}{kind} has {a.shape[0]} rows but obs has {n_rows} "
                               f"(shape {a.shape})", kind, row=start + min(n_rows, a.shape[0]))


def check_trial(tr: TrialFields, start: int, origin: Origin) -> None:
    """One trial's content: shapes, ≥ 2 samples, finite values, strictly increasing
    time, mode labels ≥ −1. ``start``: stacked row of the trial's first sample."""
    context = f"trial {tr.trial_id}: "

    def fail(message: str, kind: str, row: int | None = None, col: int | None = None) -> None:
        raise origin.error(context + message, kind, row=None if row is None else start + row,
                           col=col, at=start)

    if tr.obs.ndim != 2:
        fail(f"obs must be 2-D (T, d_o), got shape {tr.obs.shape}", "obs")
    T = len(tr)
    if T == 0:
        fail("empty trial (no samples)", "obs")
    if T == 1:
        fail("single-sample trial (need at least 2 samples)", "trial", 0)
    check_shapes(T, {"act": (tr.act, 2), "t": (tr.t, 1), "mode": (tr.mode, 1),
                     "voluntary": (tr.voluntary, 2)}, origin, start=start, context=context)

    # NaN / inf: the first bad row over all fields (ties: obs, act, t, voluntary).
    found: list[tuple[int, int, str, int | None]] = []
    for order, (kind, arr) in enumerate((("obs", tr.obs), ("act", tr.act), ("t", tr.t),
                                         ("voluntary", tr.voluntary))):
        if arr is None:
            continue
        finite = np.isfinite(arr).reshape(T, -1)
        if finite.all():
            continue
        row = int(np.flatnonzero(~finite.all(axis=1))[0])
        col = int(np.flatnonzero(~finite[row])[0]) if arr.ndim == 2 else None
        found.append((row, order, kind, col))
    if found:
        row, _, kind, col = min(found)
        arr = {"obs": tr.obs, "act": tr.act, "t": tr.t, "voluntary": tr.voluntary}[kind]
        fail(f"non-finite value {arr[row] if col is None else arr[row, col]}", kind, row, col)

    bad = np.flatnonzero(np.diff(tr.t) <= 0)
    if bad.size:
        r = int(bad[0]) + 1
        fail(f"time not strictly increasing: t = {tr.t[r]!r} s after {tr.t[r - 1]!r} s", "t", r)
    if tr.mode is not None:
        bad = np.flatnonzero(tr.mode < -1)
        if bad.size:
            fail(f"mode label {int(tr.mode[bad[0]])} < -1 (-1 means unknown)", "mode", int(bad[0]))


def rate_value(rate_hz: Any, origin: Origin) -> float:
    """``rate_hz`` as a finite positive float [Hz]."""
    r = np.asarray(rate_hz)
    if r.size != 1 or r.dtype.kind not in "biuf":
        raise origin.error(f"rate_hz must be a number, got {rate_hz!r}", "rate_hz")
    rate = float(r.reshape(()))
    if not (math.isfinite(rate) and rate > 0):
        raise origin.error(f"rate_hz must be finite and > 0, got {rate!r}", "rate_hz")
    return rate


def infer_rate(times: Sequence[np.ndarray]) -> float:
    """Sample rate [Hz] = 1 / median interval over all trials, rounded to 9 significant digits."""
    dt = np.concatenate([np.diff(t) for t in times])
    return float(f"{1.0 / float(np.median(dt)):.9g}")


def check_rate(tr: TrialFields, start: int, rate_hz: float, origin: Origin) -> None:
    """The trial's median sample interval is 1 / rate_hz within :data:`RATE_TOLERANCE`."""
    med = float(np.median(np.diff(tr.t)))
    if abs(med * rate_hz - 1.0) > RATE_TOLERANCE:
        raise origin.error(f"trial {tr.trial_id}: median sample interval {med:.6g} s does not match "
                           f"rate_hz = {rate_hz:.6g} Hz (expected {1.0 / rate_hz:.6g} s)", "t",
                           at=start)


def check_names(names: Mapping[str, Sequence[str]], origin: Origin) -> None:
    """Channel names: unique, non-empty, without surrounding spaces, commas, quotes or newlines."""
    for kind, fld in NAME_FIELD.items():
        nm = list(names.get(kind, ()))
        if len(set(nm)) != len(nm):
            dup = next(n for n in nm if nm.count(n) > 1)
            raise DataFormatError(f"duplicate channel name '{dup}'", path=origin.path, field=fld)
        for n in nm:
            if not n or n != n.strip() or any(c in n for c in ',"\n\r'):
                raise DataFormatError(f"channel name {n!r} must be non-empty, without surrounding "
                                      "spaces, commas, quotes or newlines", path=origin.path, field=fld)


def check_set(trials: Sequence[TrialFields], rate_hz: Any, names: Mapping[str, Sequence[str]],
              origin: Origin, starts: Sequence[int]) -> float:
    """Check a whole set once; return its rate [Hz] (inferred from ``t`` when ``rate_hz`` is None).

    Rules: at least one trial, a valid rate, valid channel names, unique trial
    ids, every trial's content (:func:`check_trial`), channel counts equal to the
    name counts, optional fields (mode, voluntary) in all trials or none, and
    every trial's sample interval matching the rate (:func:`check_rate`).
    ``starts``: the stacked row of each trial's first sample.
    """
    if not trials:
        raise origin.error("no trials", "trial")
    rate = None if rate_hz is None else rate_value(rate_hz, origin)
    check_names(names, origin)
    has_mode = trials[0].mode is not None
    has_vol = trials[0].voluntary is not None
    seen: set[int] = set()
    for tr, s in zip(trials, starts):
        if tr.trial_id in seen:
            raise origin.error(f"duplicate trial id {tr.trial_id}", "trial", at=s)
        seen.add(tr.trial_id)
        check_trial(tr, s, origin)
        if (tr.mode is not None) != has_mode:
            raise origin.error(f"trial {tr.trial_id}: mode labels present in some trials only",
                               "mode", at=s)
        if (tr.voluntary is not None) != has_vol:
            raise origin.error(f"trial {tr.trial_id}: voluntary channel present in some trials only",
                               "voluntary", at=s)
        for kind, arr in (("obs", tr.obs), ("act", tr.act), ("voluntary", tr.voluntary)):
            n = len(names.get(kind, ()))
            if arr is not None and arr.shape[1] != n:
                raise origin.error(f"{n} names but {arr.shape[1]} channels (trial {tr.trial_id} has "
                                   f"{arr.shape[1]} {kind} channels)", NAME_FIELD[kind], at=s)
    if not has_vol and names.get("voluntary"):
        raise origin.error(f"{len(names['voluntary'])} vol_names but no voluntary channel",
                           "vol_names")
    if rate is None:
        rate = infer_rate([tr.t for tr in trials])
    for tr, s in zip(trials, starts):
        check_rate(tr, s, rate, origin)
    return rate
