"""Demonstration data: trials of fork observations and knife actions.

A *trial* is one continuous demonstration; a :class:`Demonstrations` set is an
ordered list of trials sharing channel names and sample rate. The on-disk
formats (NPZ file, CSV folder) are described in ``shared/DESIGN.md``; loading
validates everything and raises :class:`DataFormatError` naming file, field and
row; saving is atomic.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterator, Sequence

import numpy as np

__all__ = ["DataFormatError", "Trial", "Demonstrations"]


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
        if self.mode is not None:
            self.mode = np.asarray(self.mode, dtype=int)
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
    """An ordered set of trials with shared channel names and sample rate [Hz]."""

    trials: list[Trial]
    rate_hz: float
    obs_names: list[str] = field(default_factory=list)
    act_names: list[str] = field(default_factory=list)
    vol_names: list[str] = field(default_factory=list)

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
