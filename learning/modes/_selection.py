"""Number of task modes by held-out log-likelihood over whole trials."""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from ._hmm import check_sequences, split_sequences
from ._task_modes import TaskModes

__all__ = ["ModeSelection", "select_n_modes"]


@dataclass
class ModeSelection:
    """Result of :func:`select_n_modes`.

    heldout_loglik[i]: held-out log-likelihood per sample of ``candidates[i]`` (every
    sample is held out exactly once). heldout_se[i]: standard error over folds of its
    difference to the best candidate. bic[i]: BIC of the model fitted on all data.
    n_modes: the choice (see ``rule``); n_modes_max: the held-out maximum; n_modes_bic:
    the BIC minimum. estimators: candidate → TaskModes fitted on all data.
    """

    candidates: list[int]
    heldout_loglik: list[float]
    heldout_se: list[float]
    bic: list[float]
    n_modes: int
    n_modes_max: int
    n_modes_bic: int
    rule: str
    cv: str
    n_folds: int
    converged: list[bool]
    estimators: dict[int, TaskModes] = field(default_factory=dict, repr=False)

    @property
    def best_estimator(self) -> TaskModes:
        """The TaskModes with ``n_modes`` states fitted on all data."""
        return self.estimators[self.n_modes]

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready summary (no estimators)."""
        return {"candidates": self.candidates, "heldout_loglik": self.heldout_loglik,
                "heldout_se": self.heldout_se, "bic": self.bic, "n_modes": self.n_modes,
                "n_modes_max": self.n_modes_max, "n_modes_bic": self.n_modes_bic,
                "rule": self.rule, "cv": self.cv, "n_folds": self.n_folds,
                "converged": self.converged}


def _fit_score(params: dict[str, Any], X: np.ndarray, lengths: np.ndarray,
               train: np.ndarray, test: np.ndarray | None) -> tuple[Any, ...]:
    segs = split_sequences(np.arange(len(X)), lengths)
    idx = np.concatenate([segs[i] for i in train])
    est = TaskModes(**params).fit(X[idx], lengths[train])
    if test is None:
        return est, est.bic(X, lengths)
    tidx = np.concatenate([segs[i] for i in test])
    return est.score(X[tidx], lengths[test]), len(tidx), est.converged_


def select_n_modes(X: np.ndarray, lengths: Sequence[int] | None = None,
                   candidates: Sequence[int] = range(2, 7), cv: int | str = 5, seed: int = 0,
                   rule: Literal["max", "1se"] = "1se", n_jobs: int | None = None,
                   progress: bool = False, **params: Any) -> ModeSelection:
    """Choose the number of modes by held-out log-likelihood over whole trials.

    Folds split trials, never samples: ``cv="loto"`` leaves one trial out at a time; an int
    k gives k folds of shuffled trials (k is capped at the number of trials). For each
    candidate K a :class:`TaskModes` (``params`` passed through, scaler/PCA refitted on the
    training trials) is fitted per fold and scored on the held-out trials; then once on
    all data for the BIC (second opinion) and ``estimators``.

    ``rule="max"`` picks the highest held-out log-likelihood per sample; ``"1se"`` (default)
    the fewest modes whose held-out log-likelihood is within one standard error (paired
    over folds) of that maximum — extra modes that do not clearly generalise are not kept.
    Cost: len(candidates)·(folds+1) fits; ``n_jobs`` runs them in parallel.
    """
    X, lengths = check_sequences(X, lengths)
    cands = sorted({int(k) for k in candidates})
    if not cands or cands[0] < 1:
        raise ValueError(f"candidates must be positive integers, got {list(candidates)}")
    if rule not in ("max", "1se"):
        raise ValueError(f"rule must be 'max' or '1se', got {rule!r}")
    n_trials = len(lengths)
    if n_trials < 2:
        raise ValueError("held-out selection needs at least 2 trials (lengths has 1)")
    if cv == "loto":
        folds = [np.array([i]) for i in range(n_trials)]
        cv_name = "leave-one-trial-out"
    elif isinstance(cv, (int, np.integer)) and cv >= 2:
        from sklearn.model_selection import KFold
        k = min(int(cv), n_trials)
        folds = [te for _, te in KFold(k, shuffle=True, random_state=seed).split(np.arange(n_trials))]
        cv_name = f"{k}-fold by trial"
    else:
        raise ValueError(f"cv must be 'loto' or an int >= 2, got {cv!r}")
    params = {**params, "seed": seed}
    all_trials = np.arange(n_trials)
    tasks = [(k, f) for k in cands for f in range(len(folds))] + [(k, None) for k in cands]

    def job(k: int, f: int | None):
        test = None if f is None else folds[f]
        train = all_trials if f is None else np.setdiff1d(all_trials, test)
        return _fit_score({**params, "n_modes": k}, X, lengths, train, test)

    from sklearn.utils.parallel import Parallel, delayed
    results: Iterator[Any]
    if n_jobs in (None, 1):
        results = (job(k, f) for k, f in tasks)
    else:
        results = Parallel(n_jobs=n_jobs, return_as="generator")(
            delayed(job)(k, f) for k, f in tasks)
    if progress:
        from learning.progress import progress_bar
        results = progress_bar(results, total=len(tasks), desc="select_n_modes", unit="fit")
    out = dict(zip(tasks, results))

    F = len(folds)
    ll = np.array([[out[(k, f)][0] for f in range(F)] for k in cands])  # (C, F) totals
    n = np.array([out[(cands[0], f)][1] for f in range(F)], dtype=float)  # (F,)
    per_sample = ll.sum(axis=1) / n.sum()
    i_max = int(np.argmax(per_sample))
    w = n / n.sum()
    diff = ll / n - (ll / n)[i_max]  # (C, F) paired per-sample differences to the best
    dbar = (diff * w).sum(axis=1)
    se = np.sqrt(F / max(F - 1, 1) * ((w * (diff - dbar[:, None])) ** 2).sum(axis=1))
    if rule == "max":
        i_pick = i_max
    else:
        i_pick = next(i for i in range(len(cands)) if dbar[i] >= -se[i])
    bics = [float(out[(k, None)][1]) for k in cands]
    estimators = {k: out[(k, None)][0] for k in cands}
    converged = [bool(estimators[k].converged_ and all(out[(k, f)][2] for f in range(F)))
                 for k in cands]
    return ModeSelection(
        candidates=cands, heldout_loglik=[float(v) for v in per_sample],
        heldout_se=[float(v) for v in se], bic=bics, n_modes=cands[i_pick],
        n_modes_max=cands[i_max], n_modes_bic=cands[int(np.argmin(bics))], rule=rule,
        cv=cv_name, n_folds=F, converged=converged, estimators=estimators)
