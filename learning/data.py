"""Demonstration data: trials of fork observations and knife actions.

A *trial* is one continuous demonstration; a :class:`Demonstrations` set is an
ordered list of trials sharing channel names and sample rate. The on-disk
formats (NPZ file, CSV folder) are described in ``docs/design.md``; loading
validates everything and raises :class:`DataFormatError` naming file, field and
row; saving is atomic.

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

import csv
import math
import os
import re
import shutil
import tempfile
import warnings
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator, Mapping, Sequence

import numpy as np

from .atomic import atomic_open, default_dir_mode

__all__ = [
    "DataFormatError",
    "Trial",
    "Demonstrations",
    "load",
    "save",
    "load_npz",
    "save_npz",
    "load_csv_folder",
    "save_csv_folder",
]

PathLike = str | os.PathLike

#: Every field an NPZ file may hold.
NPZ_FIELDS: tuple[str, ...] = ("obs", "act", "trial", "subject", "mode", "voluntary", "t",
                               "obs_names", "act_names", "vol_names", "rate_hz")
#: Relative tolerance between a trial's median sample interval and 1 / rate_hz.
RATE_TOLERANCE = 0.05
_CSV_NAME = re.compile(r"^trial_(-?\d+)\.csv$")
_PREFIX = {"obs": "obs_", "act": "act_", "voluntary": "vol_"}


class DataFormatError(ValueError):
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


def _first_non_integer(values: np.ndarray) -> int | None:
    """Index of the first value that is not a finite integer, or None."""
    v = np.asarray(values)
    if v.dtype.kind in "iub":
        return None
    if v.dtype.kind != "f":
        return 0
    bad = ~np.isfinite(v) | (v != np.round(v))
    idx = np.flatnonzero(bad)
    return int(idx[0]) if idx.size else None


@dataclass
class Trial:
    """One continuous demonstration sampled at a fixed rate.

    Attributes:
        obs: (T, d_o) observation (fork pose [m, rad] and force [N]).
        act: (T, d_u) action (knife pose [m, rad] and force [N]).
        t: (T,) time [s], strictly increasing.
        trial_id: integer id of the trial, unique in a data set.
        subject: integer subject id (-1 = unknown).
        mode: (T,) int ground-truth task mode per sample (-1 = unknown), or None.
        voluntary: (T, d_v) voluntary command channel (wearer's shoulder motion), or None.
    """

    obs: np.ndarray
    act: np.ndarray
    t: np.ndarray
    trial_id: int = 0
    subject: int = -1
    mode: np.ndarray | None = None
    voluntary: np.ndarray | None = None

    def __post_init__(self) -> None:
        self.obs = np.asarray(self.obs, dtype=float)
        self.act = np.asarray(self.act, dtype=float)
        self.t = np.asarray(self.t, dtype=float)
        self.trial_id = int(self.trial_id)
        self.subject = int(self.subject)
        if self.mode is not None:
            mode = np.asarray(self.mode)
            bad = _first_non_integer(mode)
            if bad is not None:
                raise DataFormatError(
                    f"trial {self.trial_id}: mode must be an integer label, got {mode.reshape(-1)[bad]!r}",
                    field="mode", row=bad)
            self.mode = mode.astype(int)
        if self.voluntary is not None:
            self.voluntary = np.asarray(self.voluntary, dtype=float)

    def __len__(self) -> int:
        return int(self.obs.shape[0])

    @property
    def duration_s(self) -> float:
        """Duration [s] from first to last sample."""
        return float(self.t[-1] - self.t[0]) if len(self) > 1 else 0.0


def _check_trial(tr: Trial, *, rate_hz: float | None, names: Mapping[str, Sequence[str]],
                 path: str | None, offset: int = 0, csv_style: bool = False) -> None:
    """Check one trial's content; rows are reported as ``offset + local row``.

    ``csv_style`` names fields by CSV column (``obs_x``) instead of NPZ field (``obs``).
    """
    tid = tr.trial_id

    def fail(msg: str, fld: str, row: int | None = None) -> None:
        raise DataFormatError(f"trial {tid}: {msg}", path=path, field=fld,
                              row=None if row is None else offset + row)

    def colfield(kind: str, j: int) -> str:
        nm = list(names.get(kind, []))
        label = nm[j] if j < len(nm) else str(j)
        return f"{_PREFIX[kind]}{label}" if csv_style else kind

    def coldesc(kind: str, j: int) -> str:
        nm = list(names.get(kind, []))
        return "" if csv_style else f" in column {j}" + (f" ('{nm[j]}')" if j < len(nm) else "")

    if tr.obs.ndim != 2:
        fail(f"obs must be 2-D (T, d_o), got shape {tr.obs.shape}", "obs")
    T = len(tr)
    if T == 0:
        fail("empty trial (no samples)", "obs")
    if T == 1:
        fail("single-sample trial (need at least 2 samples)", "obs", 0)
    if tr.act.ndim != 2:
        fail(f"act must be 2-D (T, d_u), got shape {tr.act.shape}", "act")
    if tr.act.shape[0] != T:
        fail(f"act has {tr.act.shape[0]} rows but obs has {T}", "act", min(T, tr.act.shape[0]))
    if tr.t.ndim != 1 or tr.t.shape[0] != T:
        fail(f"t must have shape ({T},), got {tr.t.shape}", "t", min(T, tr.t.reshape(-1).shape[0]))
    if tr.mode is not None and (tr.mode.ndim != 1 or tr.mode.shape[0] != T):
        fail(f"mode must have shape ({T},), got {tr.mode.shape}", "mode",
             min(T, tr.mode.reshape(-1).shape[0]))
    if tr.voluntary is not None and (tr.voluntary.ndim != 2 or tr.voluntary.shape[0] != T):
        fail(f"voluntary must have shape ({T}, d_v), got {tr.voluntary.shape}", "voluntary",
             min(T, tr.voluntary.shape[0]) if tr.voluntary.ndim >= 1 else None)

    # NaN / inf: report the first bad row over all fields (ties: obs, act, t, voluntary).
    candidates: list[tuple[int, int, str, int | None]] = []
    for order, (kind, arr) in enumerate((("obs", tr.obs), ("act", tr.act), ("t", tr.t),
                                         ("voluntary", tr.voluntary))):
        if arr is None:
            continue
        finite = np.isfinite(arr)
        if finite.all():
            continue
        a2 = finite.reshape(T, -1)
        row = int(np.flatnonzero(~a2.all(axis=1))[0])
        col = int(np.flatnonzero(~a2[row])[0]) if arr.ndim == 2 else None
        candidates.append((row, order, kind, col))
    if candidates:
        row, _, kind, col = min(candidates)
        arr = {"obs": tr.obs, "act": tr.act, "t": tr.t, "voluntary": tr.voluntary}[kind]
        val = arr[row] if col is None else arr[row, col]
        if col is None:
            fail(f"non-finite value {val}", kind, row)
        fail(f"non-finite value {val}{coldesc(kind, col)}", colfield(kind, col), row)

    dt = np.diff(tr.t)
    bad = np.flatnonzero(dt <= 0)
    if bad.size:
        r = int(bad[0]) + 1
        fail(f"time not strictly increasing: t = {tr.t[r]!r} s after {tr.t[r - 1]!r} s", "t", r)
    if rate_hz is not None:
        med = float(np.median(dt))
        if abs(med * rate_hz - 1.0) > RATE_TOLERANCE:
            fail(f"median sample interval {med:.6g} s does not match rate_hz = {rate_hz:.6g} Hz "
                 f"(expected {1.0 / rate_hz:.6g} s)", "t")
    if tr.mode is not None:
        bad = np.flatnonzero(tr.mode < -1)
        if bad.size:
            fail(f"mode label {int(tr.mode[bad[0]])} < -1 (-1 means unknown)", "mode", int(bad[0]))


@dataclass
class Demonstrations:
    """An ordered set of trials with shared channel names and sample rate [Hz].

    Empty name lists are filled with defaults ``"0", "1", …`` on construction.
    """

    trials: list[Trial]
    rate_hz: float
    obs_names: list[str] = field(default_factory=list)
    act_names: list[str] = field(default_factory=list)
    vol_names: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        self.trials = list(self.trials)
        self.obs_names = [str(n) for n in self.obs_names]
        self.act_names = [str(n) for n in self.act_names]
        self.vol_names = [str(n) for n in self.vol_names]
        if self.trials:
            first = self.trials[0]
            if not self.obs_names and first.obs.ndim == 2:
                self.obs_names = [str(j) for j in range(first.obs.shape[1])]
            if not self.act_names and first.act.ndim == 2:
                self.act_names = [str(j) for j in range(first.act.shape[1])]
            if not self.vol_names and first.voluntary is not None and first.voluntary.ndim == 2:
                self.vol_names = [str(j) for j in range(first.voluntary.shape[1])]

    def __len__(self) -> int:
        return len(self.trials)

    def __iter__(self) -> Iterator[Trial]:
        return iter(self.trials)

    def __getitem__(self, i: int) -> Trial:
        return self.trials[i]

    @property
    def n_samples(self) -> int:
        return int(sum(len(tr) for tr in self.trials))

    @property
    def obs_dim(self) -> int:
        return int(self.trials[0].obs.shape[1])

    @property
    def act_dim(self) -> int:
        return int(self.trials[0].act.shape[1])

    @property
    def subjects(self) -> list[int]:
        return sorted({tr.subject for tr in self.trials})

    @property
    def trial_ids(self) -> list[int]:
        return [tr.trial_id for tr in self.trials]

    @property
    def has_modes(self) -> bool:
        return all(tr.mode is not None for tr in self.trials) and len(self.trials) > 0

    @property
    def has_voluntary(self) -> bool:
        return all(tr.voluntary is not None for tr in self.trials) and len(self.trials) > 0

    def stacked(self) -> dict[str, np.ndarray]:
        """Concatenate all trials into flat arrays (the NPZ layout): obs, act, t, trial, subject[, mode, voluntary]."""
        out = {
            "obs": np.concatenate([tr.obs for tr in self.trials]),
            "act": np.concatenate([tr.act for tr in self.trials]),
            "t": np.concatenate([tr.t for tr in self.trials]),
            "trial": np.concatenate([np.full(len(tr), tr.trial_id, dtype=int) for tr in self.trials]),
            "subject": np.concatenate([np.full(len(tr), tr.subject, dtype=int) for tr in self.trials]),
        }
        if self.has_modes:
            out["mode"] = np.concatenate([tr.mode for tr in self.trials])
        if self.has_voluntary:
            out["voluntary"] = np.concatenate([tr.voluntary for tr in self.trials])
        return out

    def select(self, trial_ids: Sequence[int]) -> "Demonstrations":
        """A new set holding the trials with the given ids, in the given order."""
        by_id = {tr.trial_id: tr for tr in self.trials}
        missing = [i for i in trial_ids if i not in by_id]
        if missing:
            raise KeyError(f"no trial with id {missing[0]} (have {sorted(by_id)})")
        return Demonstrations([by_id[i] for i in trial_ids], self.rate_hz,
                              list(self.obs_names), list(self.act_names), list(self.vol_names))

    def with_trials(self, trials: Sequence[Trial]) -> "Demonstrations":
        """A new set with the given trials and this set's rate and channel names."""
        return Demonstrations(list(trials), self.rate_hz, list(self.obs_names),
                              list(self.act_names), list(self.vol_names))

    # ------------------------------------------------------------------ checks

    def validate(self, path: PathLike | None = None) -> "Demonstrations":
        """Check the whole set; raise :class:`DataFormatError` on the first problem.

        Rows in messages are rows of the trial named in the message. Returns ``self``.
        """
        p = None if path is None else str(path)
        if not self.trials:
            raise DataFormatError("no trials", path=p, field="trial")
        try:
            rate = float(self.rate_hz)
        except (TypeError, ValueError):
            raise DataFormatError(f"rate_hz must be a number, got {self.rate_hz!r}",
                                  path=p, field="rate_hz") from None
        if not (math.isfinite(rate) and rate > 0):
            raise DataFormatError(f"rate_hz must be finite and > 0, got {rate!r}", path=p, field="rate_hz")
        self._check_names(p)
        seen: set[int] = set()
        has_mode = self.trials[0].mode is not None
        has_vol = self.trials[0].voluntary is not None
        names = {"obs": self.obs_names, "act": self.act_names, "voluntary": self.vol_names}
        for tr in self.trials:
            if tr.trial_id in seen:
                raise DataFormatError(f"duplicate trial id {tr.trial_id}", path=p, field="trial")
            seen.add(tr.trial_id)
            _check_trial(tr, rate_hz=rate, names=names, path=p)
            for kind, arr, nm in (("obs", tr.obs, self.obs_names), ("act", tr.act, self.act_names)):
                if arr.shape[1] != len(nm):
                    raise DataFormatError(
                        f"trial {tr.trial_id}: {arr.shape[1]} {kind} channels but {len(nm)} {kind}_names",
                        path=p, field=kind)
            if (tr.mode is not None) != has_mode:
                raise DataFormatError(f"trial {tr.trial_id}: mode labels present in some trials only",
                                      path=p, field="mode")
            if (tr.voluntary is not None) != has_vol:
                raise DataFormatError(f"trial {tr.trial_id}: voluntary channel present in some trials only",
                                      path=p, field="voluntary")
            if tr.voluntary is not None and tr.voluntary.shape[1] != len(self.vol_names):
                raise DataFormatError(
                    f"trial {tr.trial_id}: {tr.voluntary.shape[1]} voluntary channels but "
                    f"{len(self.vol_names)} vol_names", path=p, field="voluntary")
        if not has_vol and self.vol_names:
            raise DataFormatError(f"{len(self.vol_names)} vol_names but no voluntary channel",
                                  path=p, field="vol_names")
        return self

    def _check_names(self, p: str | None) -> None:
        for fld, nm in (("obs_names", self.obs_names), ("act_names", self.act_names),
                        ("vol_names", self.vol_names)):
            if len(set(nm)) != len(nm):
                dup = next(n for n in nm if nm.count(n) > 1)
                raise DataFormatError(f"duplicate channel name '{dup}'", path=p, field=fld)
            for n in nm:
                if not n or n != n.strip() or any(c in n for c in ',"\n\r'):
                    raise DataFormatError(
                        f"channel name {n!r} must be non-empty, without surrounding spaces, "
                        f"commas, quotes or newlines", path=p, field=fld)

    # ----------------------------------------------------------------- summary

    def summary(self) -> dict[str, Any]:
        """Plain-Python (JSON-ready) summary of the set.

        Keys: ``n_trials``, ``n_samples``, ``subjects``, ``duration_s`` (samples / rate
        [s]), ``duration_s_per_subject`` ({subject: s}), ``rate_hz``, ``obs_names``,
        ``act_names``, ``vol_names``, ``mode_counts`` ({label: samples} or None).
        """
        per_subject: dict[int, float] = {}
        for tr in self.trials:
            per_subject[tr.subject] = per_subject.get(tr.subject, 0.0) + len(tr) / float(self.rate_hz)
        mode_counts = None
        if self.has_modes:
            labels, counts = np.unique(np.concatenate([tr.mode for tr in self.trials]), return_counts=True)
            mode_counts = {int(k): int(c) for k, c in zip(labels, counts)}
        return {
            "n_trials": len(self.trials),
            "n_samples": self.n_samples,
            "subjects": [int(s) for s in self.subjects],
            "duration_s": float(self.n_samples / float(self.rate_hz)),
            "duration_s_per_subject": {int(k): float(v) for k, v in sorted(per_subject.items())},
            "rate_hz": float(self.rate_hz),
            "obs_names": list(self.obs_names),
            "act_names": list(self.act_names),
            "vol_names": list(self.vol_names),
            "mode_counts": mode_counts,
        }

    # ---------------------------------------------------------- construction

    @classmethod
    def from_stacked(cls, obs: Any, act: Any, trial: Any, *, t: Any = None, rate_hz: Any = None,
                     subject: Any = None, mode: Any = None, voluntary: Any = None,
                     obs_names: Any = None, act_names: Any = None, vol_names: Any = None,
                     path: PathLike | None = None) -> "Demonstrations":
        """Build and validate a set from flat (NPZ-layout) arrays; see the module docstring.

        Errors name ``path`` (if given), the field and the row of the flat arrays.
        """
        p = None if path is None else str(path)

        def err(msg: str, fld: str, row: int | None = None) -> DataFormatError:
            return DataFormatError(msg, path=p, field=fld, row=row)

        def numeric(x: Any, fld: str) -> np.ndarray:
            a = np.asarray(x)
            if a.dtype.kind not in "biuf":
                raise err(f"must be numeric, got dtype {a.dtype}", fld)
            return a

        obs_a = numeric(obs, "obs")
        if obs_a.ndim != 2:
            raise err(f"must be 2-D (T, d_o), got shape {obs_a.shape}", "obs")
        T = obs_a.shape[0]
        if T == 0:
            raise err("empty data set (no samples)", "obs")
        act_a = numeric(act, "act")
        if act_a.ndim != 2:
            raise err(f"must be 2-D (T, d_u), got shape {act_a.shape}", "act")
        if act_a.shape[0] != T:
            raise err(f"act has {act_a.shape[0]} rows but obs has {T}", "act", min(T, act_a.shape[0]))

        def column(x: Any, fld: str, integer: bool) -> np.ndarray | None:
            if x is None:
                return None
            a = numeric(x, fld)
            if a.ndim != 1 or a.shape[0] != T:
                n = a.reshape(-1).shape[0] if a.ndim else 1
                raise err(f"must have shape ({T},) like obs, got {a.shape}", fld, min(T, n) if a.ndim == 1 else None)
            if integer:
                bad = _first_non_integer(a)
                if bad is not None:
                    raise err(f"must be integer, got {a[bad]!r}", fld, bad)
                return a.astype(np.int64)
            return a.astype(float)

        trial_a = column(trial, "trial", True)
        subject_a = column(subject, "subject", True)
        mode_a = column(mode, "mode", True)
        t_a = column(t, "t", False)
        vol_a = None
        if voluntary is not None:
            vol_a = numeric(voluntary, "voluntary")
            if vol_a.ndim != 2 or vol_a.shape[0] != T:
                raise err(f"must have shape ({T}, d_v) like obs, got {vol_a.shape}", "voluntary",
                          min(T, vol_a.shape[0]) if vol_a.ndim >= 1 and vol_a.shape[0] != T else None)

        def name_list(x: Any, fld: str, n: int | None) -> list[str] | None:
            if x is None:
                return None
            a = np.asarray(x)
            if a.ndim != 1 or (a.size and a.dtype.kind not in "US"):
                raise err(f"must be a 1-D array of strings, got dtype {a.dtype} shape {a.shape}", fld)
            names = [v.decode() if isinstance(v, bytes) else str(v) for v in a.tolist()]
            if n is not None and len(names) != n:
                raise err(f"{len(names)} names but {n} channels", fld)
            return names

        onames = name_list(obs_names, "obs_names", obs_a.shape[1])
        anames = name_list(act_names, "act_names", act_a.shape[1])
        vnames = name_list(vol_names, "vol_names", None if vol_a is None else vol_a.shape[1])
        if vol_a is None and vnames:
            raise err(f"{len(vnames)} vol_names but no voluntary field", "vol_names")

        rate: float | None = None
        if rate_hz is not None:
            r = np.asarray(rate_hz)
            if r.size != 1 or r.dtype.kind not in "biuf":
                raise err(f"must be a numeric scalar, got {r!r}", "rate_hz")
            rate = float(r.reshape(()))
            if not (math.isfinite(rate) and rate > 0):
                raise err(f"must be finite and > 0, got {rate!r}", "rate_hz")
        if t_a is None and rate is None:
            raise err("neither 't' nor 'rate_hz' given; one is needed to know the time", "rate_hz")

        # Segments of contiguous trial ids.
        change = np.flatnonzero(np.diff(trial_a) != 0) + 1
        starts = np.concatenate([[0], change])
        stops = np.concatenate([change, [T]])
        seen: dict[int, int] = {}
        for s in starts:
            tid = int(trial_a[s])
            if tid in seen:
                raise err(f"trial {tid} is not contiguous: it restarts here after other trials "
                          f"(first seen at row {seen[tid]})", "trial", int(s))
            seen[tid] = int(s)

        trials: list[Trial] = []
        for s, e in zip(starts, stops):
            s, e = int(s), int(e)
            tid = int(trial_a[s])
            if e - s < 2:
                raise err(f"trial {tid}: single-sample trial (need at least 2 samples)", "trial", s)
            subj = -1
            if subject_a is not None:
                seg = subject_a[s:e]
                diff = np.flatnonzero(seg != seg[0])
                if diff.size:
                    raise err(f"trial {tid}: subject changes within the trial ({int(seg[0])} → "
                              f"{int(seg[diff[0]])})", "subject", s + int(diff[0]))
                subj = int(seg[0])
            tt = t_a[s:e] if t_a is not None else np.arange(e - s) / rate
            trials.append(Trial(obs=obs_a[s:e].astype(float), act=act_a[s:e].astype(float), t=tt,
                                trial_id=tid, subject=subj,
                                mode=None if mode_a is None else mode_a[s:e],
                                voluntary=None if vol_a is None else vol_a[s:e].astype(float)))

        # Content checks with rows in the flat arrays, before rate inference.
        names = {"obs": onames or [], "act": anames or [], "voluntary": vnames or []}
        for tr, s in zip(trials, starts):
            _check_trial(tr, rate_hz=None, names=names, path=p, offset=int(s))
        if rate is None:
            rate = _infer_rate([tr.t for tr in trials])
        for tr, s in zip(trials, starts):
            _check_trial(tr, rate_hz=rate, names=names, path=p, offset=int(s))
        demos = cls(trials, rate, onames or [], anames or [], vnames or [])
        return demos.validate(p)


def _infer_rate(times: Sequence[np.ndarray]) -> float:
    """Sample rate [Hz] = 1 / median interval over all trials, rounded to 9 significant digits."""
    dt = np.concatenate([np.diff(t) for t in times])
    return float(f"{1.0 / float(np.median(dt)):.9g}")


# ---------------------------------------------------------------------- NPZ


def load_npz(path: PathLike) -> Demonstrations:
    """Load and validate an NPZ data set (fields: see the module docstring)."""
    p = str(path)
    if not os.path.isfile(p):
        raise DataFormatError("no such file", path=p)
    if not zipfile.is_zipfile(p):
        with open(p, "rb") as f:
            single = f.read(6) == b"\x93NUMPY"
        raise DataFormatError("not an NPZ archive (a single .npy array?)" if single else
                              "not an NPZ archive (not a zip file; expected numpy.savez output)", path=p)
    try:
        npz = np.load(p, allow_pickle=False)
    except (OSError, ValueError, zipfile.BadZipFile, EOFError) as e:
        raise DataFormatError(f"not a readable NPZ file ({e})", path=p) from None
    if not isinstance(npz, np.lib.npyio.NpzFile):
        raise DataFormatError("not an NPZ archive (a single .npy array?)", path=p)
    with npz:
        keys = list(npz.files)
        for k in keys:
            if k not in NPZ_FIELDS:
                raise DataFormatError(f"unknown field (allowed: {', '.join(NPZ_FIELDS)})", path=p, field=k)
        for k in ("obs", "act", "trial"):
            if k not in keys:
                raise DataFormatError("required field missing", path=p, field=k)
        arrays: dict[str, np.ndarray] = {}
        for k in keys:
            try:
                arrays[k] = npz[k]
            except (ValueError, OSError, zipfile.BadZipFile, EOFError) as e:
                raise DataFormatError(f"cannot be read without pickle ({e})", path=p, field=k) from None
    return Demonstrations.from_stacked(path=p, **arrays)


def _npz_arrays(demos: Demonstrations) -> dict[str, np.ndarray]:
    arrays = demos.stacked()
    arrays["obs_names"] = np.array(demos.obs_names, dtype=str)
    arrays["act_names"] = np.array(demos.act_names, dtype=str)
    if demos.has_voluntary:
        arrays["vol_names"] = np.array(demos.vol_names, dtype=str)
    arrays["rate_hz"] = np.array(float(demos.rate_hz))
    return arrays


def save_npz(demos: Demonstrations, path: PathLike) -> None:
    """Validate, then write an NPZ file atomically (temporary file in the same folder, then rename)."""
    p = Path(path)
    demos.validate()
    arrays = _npz_arrays(demos)
    with atomic_open(p, "wb") as f:
        np.savez(f, **arrays)


# ---------------------------------------------------------------------- CSV


def _csv_header(path: str) -> list[str]:
    with open(path, newline="", encoding="utf-8-sig") as f:  # tolerate a byte-order mark
        first = f.readline()
    if not first.strip():
        raise DataFormatError("empty file (no header line)", path=path)
    return [c.strip() for c in next(csv.reader([first]))]


def _csv_body(path: str, ncols: int, header: list[str]) -> np.ndarray:
    """Numeric body (rows, ncols); a bad cell raises naming its column and row."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # "empty input file"
            data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2, dtype=float,
                              comments=None, encoding="utf-8")
        if data.size == 0:
            return np.zeros((0, ncols))
        if data.shape[1] == ncols:
            return data
    except ValueError:
        pass
    # Slow path: locate the problem.
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.reader(f)
        next(reader)
        for row, cells in enumerate(reader):
            if not cells:
                raise DataFormatError("blank line", path=path, row=row)
            if len(cells) != ncols:
                raise DataFormatError(f"{len(cells)} values but the header has {ncols} columns "
                                      f"(file line {row + 2})", path=path, row=row)
            for name, cell in zip(header, cells):
                try:
                    float(cell)
                except ValueError:
                    raise DataFormatError(f"not a number: {cell!r} (file line {row + 2})",
                                          path=path, field=name, row=row) from None
    raise DataFormatError("cannot parse the file as comma-separated numbers", path=path)


def _read_csv_trial(path: str, tid: int) -> tuple[Trial, dict[str, list[str]], tuple[bool, bool]]:
    header = _csv_header(path)
    cols: dict[str, list[int]] = {"obs": [], "act": [], "voluntary": []}
    names: dict[str, list[str]] = {"obs": [], "act": [], "voluntary": []}
    special: dict[str, int] = {}
    seen: set[str] = set()
    for j, c in enumerate(header):
        if c in seen:
            raise DataFormatError("duplicate column", path=path, field=c)
        seen.add(c)
        if c in ("t", "mode", "subject"):
            special[c] = j
            continue
        for kind, pre in _PREFIX.items():
            if c.startswith(pre) and len(c) > len(pre):
                cols[kind].append(j)
                names[kind].append(c[len(pre):])
                break
        else:
            raise DataFormatError("unknown column (allowed: t, mode, subject, obs_*, act_*, vol_*)",
                                  path=path, field=c)
    if "t" not in special:
        raise DataFormatError("required column missing", path=path, field="t")
    for kind in ("obs", "act"):
        if not cols[kind]:
            raise DataFormatError(f"no {_PREFIX[kind]}* column", path=path, field=f"{_PREFIX[kind]}*")
    data = _csv_body(path, len(header), header)
    if data.shape[0] == 0:
        raise DataFormatError(f"trial {tid}: empty trial (no data rows)", path=path, field="t")
    subject = -1
    if "subject" in special:
        s = data[:, special["subject"]]
        bad = _first_non_integer(s)
        if bad is not None:
            raise DataFormatError(f"subject must be an integer, got {s[bad]!r}", path=path,
                                  field="subject", row=bad)
        diff = np.flatnonzero(s != s[0])
        if diff.size:
            raise DataFormatError(f"subject changes within the trial ({int(s[0])} → {int(s[diff[0]])})",
                                  path=path, field="subject", row=int(diff[0]))
        subject = int(s[0])
    mode = None
    if "mode" in special:
        m = data[:, special["mode"]]
        bad = _first_non_integer(m)
        if bad is not None:
            raise DataFormatError(f"mode must be an integer label, got {m[bad]!r}", path=path,
                                  field="mode", row=bad)
        mode = m.astype(np.int64)
    tr = Trial(obs=data[:, cols["obs"]], act=data[:, cols["act"]], t=data[:, special["t"]],
               trial_id=tid, subject=subject, mode=mode,
               voluntary=data[:, cols["voluntary"]] if cols["voluntary"] else None)
    _check_trial(tr, rate_hz=None, names=names, path=path, csv_style=True)
    return tr, names, ("mode" in special, "subject" in special)


def load_csv_folder(path: PathLike) -> Demonstrations:
    """Load and validate a CSV folder (one ``trial_<id>.csv`` per trial; see the module docstring)."""
    p = str(path)
    if not os.path.isdir(p):
        raise DataFormatError("no such folder", path=p)
    files: list[tuple[int, str]] = []
    for name in sorted(os.listdir(p)):
        if not name.lower().endswith(".csv"):
            continue
        m = _CSV_NAME.match(name)
        if m is None:
            raise DataFormatError("CSV file name must be trial_<integer id>.csv", path=os.path.join(p, name))
        files.append((int(m.group(1)), os.path.join(p, name)))
    if not files:
        raise DataFormatError("no trial_<id>.csv files", path=p)
    files.sort()
    for (a, fa), (b, fb) in zip(files, files[1:]):
        if a == b:
            raise DataFormatError(f"trial id {a} also given by {os.path.basename(fa)}", path=fb, field="trial")
    trials: list[Trial] = []
    ref: tuple[dict[str, list[str]], tuple[bool, bool], str] | None = None
    for tid, fp in files:
        tr, names, optional = _read_csv_trial(fp, tid)
        if ref is None:
            ref = (names, optional, fp)
        else:
            for kind in ("obs", "act", "voluntary"):
                if names[kind] != ref[0][kind]:
                    raise DataFormatError(
                        f"{_PREFIX[kind]}* columns {names[kind]} differ from {ref[0][kind]} in "
                        f"{os.path.basename(ref[2])}", path=fp, field=f"{_PREFIX[kind]}*")
            for k, (here, there) in zip(("mode", "subject"), zip(optional, ref[1])):
                if here != there:
                    raise DataFormatError(
                        f"column {'present' if here else 'absent'} here but "
                        f"{'present' if there else 'absent'} in {os.path.basename(ref[2])}",
                        path=fp, field=k)
        trials.append(tr)
    assert ref is not None
    rate = _infer_rate([tr.t for tr in trials])
    names = ref[0]
    for tr, (_, fp) in zip(trials, files):
        _check_trial(tr, rate_hz=rate, names=names, path=fp, csv_style=True)
    demos = Demonstrations(trials, rate, names["obs"], names["act"], names["voluntary"])
    return demos.validate(p)


def _write_csv_trial(demos: Demonstrations, tr: Trial, path: str, with_subject: bool) -> None:
    header = ["t"] + [f"obs_{n}" for n in demos.obs_names] + [f"act_{n}" for n in demos.act_names]
    blocks = [tr.t[:, None], tr.obs, tr.act]
    fmt = ["%.17g"] * (1 + tr.obs.shape[1] + tr.act.shape[1])
    if tr.voluntary is not None:
        header += [f"vol_{n}" for n in demos.vol_names]
        blocks.append(tr.voluntary)
        fmt += ["%.17g"] * tr.voluntary.shape[1]
    if tr.mode is not None:
        header.append("mode")
        blocks.append(tr.mode[:, None].astype(float))
        fmt.append("%d")
    if with_subject:
        header.append("subject")
        blocks.append(np.full((len(tr), 1), float(tr.subject)))
        fmt.append("%d")
    with open(path, "w", newline="", encoding="utf-8") as f:
        np.savetxt(f, np.hstack(blocks), fmt=fmt, delimiter=",", header=",".join(header), comments="")
        f.flush()
        os.fsync(f.fileno())


def save_csv_folder(demos: Demonstrations, path: PathLike) -> None:
    """Validate, then write one ``trial_<id:03d>.csv`` per trial atomically.

    Files are written into a temporary folder beside ``path`` that is then renamed.
    An existing target folder is replaced only if it holds nothing but
    ``trial_*.csv`` files (otherwise ``FileExistsError``); it is moved aside first
    and deleted after the rename, so a failure leaves it intact. A ``subject``
    column is written when any subject is known (≠ −1).
    """
    p = Path(path)
    demos.validate()
    if p.exists():
        if not p.is_dir():
            raise FileExistsError(f"{p}: exists and is not a folder")
        foreign = [n for n in os.listdir(p) if not _CSV_NAME.match(n)]
        if foreign:
            raise FileExistsError(f"{p}: folder holds other files ({foreign[0]!r}); not replacing it")
    p.parent.mkdir(parents=True, exist_ok=True)
    with_subject = any(tr.subject != -1 for tr in demos.trials)
    tmp = tempfile.mkdtemp(prefix=f".{p.name}.", suffix=".tmp", dir=p.parent)
    os.chmod(tmp, default_dir_mode())  # mkdtemp gives 0700; the result is an ordinary folder
    old: str | None = None
    try:
        for tr in demos.trials:
            _write_csv_trial(demos, tr, os.path.join(tmp, f"trial_{tr.trial_id:03d}.csv"), with_subject)
        if p.exists():
            old = tempfile.mkdtemp(prefix=f".{p.name}.", suffix=".old", dir=p.parent)
            os.rmdir(old)
            os.replace(p, old)
        os.replace(tmp, p)
    except BaseException:
        if os.path.isdir(tmp):
            shutil.rmtree(tmp, ignore_errors=True)
        if old is not None and os.path.isdir(old) and not p.exists():
            os.replace(old, p)  # put the previous folder back
            old = None
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


# ------------------------------------------------------------------ dispatch


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
