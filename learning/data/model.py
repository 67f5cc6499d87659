"""The data model: a :class:`Trial` is one continuous demonstration, a
:class:`Demonstrations` set an ordered list of trials sharing channel names and
sample rate. Sets are checked by the rules of :mod:`learning.data.checks`, once.
"""

from __future__ import annotations

import os
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from .checks import (
    Origin,
    as_integer,
    check_set,
    check_shapes,
    rate_value,
)

__all__ = ["Demonstrations", "Trial", "from_stacked_arrays"]

PathLike = str | os.PathLike


@dataclass
class Trial:
    """One continuous demonstration sampled at a fixed rate.

    Construction converts the arrays (float; ``mode`` to int, refusing non-integer
    labels); everything else is checked when the trial is part of a set that is
    validated, loaded or saved.

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
            self.mode = as_integer(self.mode, "mode", Origin(), context=f"trial {self.trial_id}: ")
        if self.voluntary is not None:
            self.voluntary = np.asarray(self.voluntary, dtype=float)

    def __len__(self) -> int:
        return int(self.obs.shape[0])

    @property
    def duration_s(self) -> float:
        """Duration [s] from first to last sample."""
        return float(self.t[-1] - self.t[0]) if len(self) > 1 else 0.0


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

    def names(self) -> dict[str, list[str]]:
        """Channel names per field: ``{"obs": …, "act": …, "voluntary": …}``."""
        return {"obs": self.obs_names, "act": self.act_names, "voluntary": self.vol_names}

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

    def obs_sequences(self) -> tuple[np.ndarray, np.ndarray]:
        """(N, d_o) observations of all trials stacked and (n_trials,) their lengths: the input of a
        sequence model over trials (hmmlearn's ``X, lengths``)."""
        return np.concatenate([tr.obs for tr in self.trials]), np.array([len(tr) for tr in self.trials])

    def select(self, trial_ids: Sequence[int]) -> Demonstrations:
        """A new set holding the trials with the given ids, in the given order."""
        by_id = {tr.trial_id: tr for tr in self.trials}
        missing = [i for i in trial_ids if i not in by_id]
        if missing:
            raise KeyError(f"no trial with id {missing[0]} (have {sorted(by_id)})")
        return self.with_trials([by_id[i] for i in trial_ids])

    def with_trials(self, trials: Sequence[Trial]) -> Demonstrations:
        """A new set with the given trials and this set's rate and channel names."""
        return Demonstrations(list(trials), self.rate_hz, list(self.obs_names),
                              list(self.act_names), list(self.vol_names))

    def renamed(self, mapping: dict[str, str]) -> Demonstrations:
        """A new set (the same trials) with channels renamed: ``mapping`` NAME → CHANNEL gives the
        channel CHANNEL the name NAME (``sim --map NAME=CHANNEL``). CHANNEL may be qualified by its
        field, ``obs:``, ``act:`` or ``voluntary:``, where a name is in more than one.

        Raises ValueError naming the entry: a channel the set does not have (listing those it has), one
        in two fields unqualified, a channel renamed twice, or a new name that another channel of
        the field keeps.
        """
        fields = self.names()
        new = {k: list(v) for k, v in fields.items()}
        seen: set[tuple[str, str]] = set()
        for name, channel in mapping.items():
            kind, sep, bare = str(channel).partition(":")
            if sep and kind in fields:
                kinds, channel = [kind], bare
            else:
                kinds = [k for k, names in fields.items() if channel in names]
            hits = [k for k in kinds if channel in fields[k]]
            if not hits:
                have = "; ".join(f"{k}: {', '.join(v) or 'none'}" for k, v in fields.items())
                raise ValueError(f"{name}={channel}: the data has no channel {channel!r} ({have})")
            if len(hits) > 1:
                raise ValueError(f"{name}={channel}: {channel!r} is a channel of {' and '.join(hits)}; write "
                                 f"{name}={hits[0]}:{channel} or {name}={hits[1]}:{channel}")
            kind = hits[0]
            if (kind, channel) in seen:
                raise ValueError(f"{name}={channel}: the {kind} channel {channel!r} is renamed twice")
            seen.add((kind, channel))
            new[kind][fields[kind].index(channel)] = str(name)
        for kind, names in new.items():
            twice = sorted({n for n in names if names.count(n) > 1})
            if twice:
                raise ValueError(f"after renaming, the {kind} channels name {twice} twice ({', '.join(names)}): "
                                 f"map the channel that has that name now too, or another")
        return Demonstrations(list(self.trials), self.rate_hz, new["obs"], new["act"], new["voluntary"])

    def validate(self, path: PathLike | None = None) -> Demonstrations:
        """Check the whole set (:func:`learning.data.checks.check_set`); raise
        :class:`DataFormatError` on the first problem.

        Rows in messages are rows of the trial named in the message. Returns ``self``.
        """
        lengths = [len(tr) for tr in self.trials]
        starts = tuple(int(s) for s in np.concatenate([[0], np.cumsum(lengths)[:-1]])) \
            if lengths else (0,)
        origin = Origin(path=None if path is None else str(path), part_starts=starts,
                        names=self.names())
        check_set(self.trials, self.rate_hz, self.names(), origin, starts)
        return self

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

    @classmethod
    def from_stacked(cls, obs: Any, act: Any, trial: Any, *, t: Any = None, rate_hz: Any = None,
                     subject: Any = None, mode: Any = None, voluntary: Any = None,
                     obs_names: Any = None, act_names: Any = None, vol_names: Any = None,
                     path: PathLike | None = None) -> Demonstrations:
        """Build and validate a set from flat (NPZ-layout) arrays; see :mod:`learning.data`.

        Errors name ``path`` (if given), the field and the row of the flat arrays.
        """
        arrays = {"obs": obs, "act": act, "trial": trial, "t": t, "rate_hz": rate_hz,
                  "subject": subject, "mode": mode, "voluntary": voluntary, "obs_names": obs_names,
                  "act_names": act_names, "vol_names": vol_names}
        return from_stacked_arrays(arrays, Origin(path=None if path is None else str(path)))


def _name_list(x: Any, fld: str, origin: Origin) -> list[str] | None:
    if x is None:
        return None
    a = np.asarray(x)
    if a.ndim != 1 or (a.size and a.dtype.kind not in "US"):
        raise origin.error(f"must be a 1-D array of strings, got dtype {a.dtype} shape {a.shape}", fld)
    return [v.decode() if isinstance(v, bytes) else str(v) for v in a.tolist()]


def from_stacked_arrays(arrays: dict[str, Any], origin: Origin) -> Demonstrations:
    """Cut flat arrays (the NPZ layout; absent fields None) into trials and check the set once.

    Here only what cutting needs is checked: numeric fields, one row per sample in
    every per-row field, integer ``trial``/``subject``/``mode``, contiguous trials,
    one subject per trial, a time base (``t`` or ``rate_hz``). The rest is
    :func:`~learning.data.checks.check_set`. Rows in errors are located by ``origin``.
    """
    def numeric(kind: str) -> np.ndarray | None:
        if arrays.get(kind) is None:
            return None
        a = np.asarray(arrays[kind])
        if a.dtype.kind not in "biuf":
            raise origin.error(f"must be numeric, got dtype {a.dtype}", kind)
        if a.ndim == 0:
            raise origin.error("must be an array with one row per sample, got a scalar", kind)
        return a

    for kind in ("obs", "act", "trial"):
        if arrays.get(kind) is None:
            raise origin.error("required field missing", kind)
    obs, act, trial = numeric("obs"), numeric("act"), numeric("trial")
    subject, mode, t, vol = numeric("subject"), numeric("mode"), numeric("t"), numeric("voluntary")
    assert obs is not None and act is not None and trial is not None  # for the type checker
    if obs.ndim != 2:
        raise origin.error(f"must be 2-D (T, d_o), got shape {obs.shape}", "obs")
    T = obs.shape[0]
    if T == 0:
        raise origin.error("empty data set (no samples)", "obs")
    check_shapes(T, {"act": (act, 2), "trial": (trial, 1), "subject": (subject, 1),
                     "mode": (mode, 1), "t": (t, 1), "voluntary": (vol, 2)}, origin)
    trial = as_integer(trial, "trial", origin)
    subject = None if subject is None else as_integer(subject, "subject", origin)
    mode = None if mode is None else as_integer(mode, "mode", origin)
    names = {"obs": _name_list(arrays.get("obs_names"), "obs_names", origin),
             "act": _name_list(arrays.get("act_names"), "act_names", origin),
             "voluntary": _name_list(arrays.get("vol_names"), "vol_names", origin)}
    rate = None if arrays.get("rate_hz") is None else rate_value(arrays["rate_hz"], origin)
    if t is None and rate is None:
        raise origin.error("neither 't' nor 'rate_hz' given; one is needed to know the time", "rate_hz")

    # Trials = runs of equal trial ids; each id once.
    change = np.flatnonzero(np.diff(trial) != 0) + 1
    starts = np.concatenate([[0], change]).astype(int)
    stops = np.concatenate([change, [T]]).astype(int)
    first_row: dict[int, int] = {}
    trials: list[Trial] = []
    for s, e in zip(starts.tolist(), stops.tolist()):
        tid = int(trial[s])
        if tid in first_row:
            raise origin.error(f"trial {tid} is not contiguous: it restarts here after other trials "
                               f"(first seen at row {origin.locate(first_row[tid])[1]})", "trial", row=s)
        first_row[tid] = s
        subj = -1
        if subject is not None:
            seg = subject[s:e]
            diff = np.flatnonzero(seg != seg[0])
            if diff.size:
                raise origin.error(f"trial {tid}: subject changes within the trial ({int(seg[0])} → "
                                   f"{int(seg[diff[0]])})", "subject", row=s + int(diff[0]))
            subj = int(seg[0])
        trials.append(Trial(obs=obs[s:e], act=act[s:e],
                            t=t[s:e] if t is not None else np.arange(e - s) / rate,
                            trial_id=tid, subject=subj,
                            mode=None if mode is None else mode[s:e],
                            voluntary=None if vol is None else vol[s:e]))

    dims = {"obs": obs.shape[1], "act": act.shape[1], "voluntary": None if vol is None else vol.shape[1]}
    full = {k: (v if v is not None else [str(j) for j in range(dims[k] or 0)]) for k, v in names.items()}
    origin = replace(origin, names=full)
    rate = check_set(trials, rate, full, origin, starts.tolist())
    return Demonstrations(trials, rate, full["obs"], full["act"], full["voluntary"])
