"""Ridge regression on the causal window: the baseline for the LSTM reactive predictor."""

from __future__ import annotations

import numbers
from collections.abc import Sequence

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.linear_model import Ridge
from sklearn.utils.validation import check_is_fitted

from learning.predictor.sequences import check_sequence_set

__all__ = ["RidgeWindowBaseline"]


class RidgeWindowBaseline(BaseEstimator):
    """Ridge regression on the causal window ``[x_t, x_{t−1}, …, x_{t−L+1}]`` (the first row
    repeated before a trial's start), with the predictor's ``fit``/``predict`` shapes — the
    baseline that says how much the LSTM adds. Fitted on the masked steps only."""

    def __init__(self, lags: int = 10, alpha: float = 1.0) -> None:
        self.lags = lags
        self.alpha = alpha

    def _features(self, x: np.ndarray) -> np.ndarray:
        L = int(self.lags)
        padded = np.vstack([np.repeat(x[:1], L - 1, axis=0), x])
        return np.hstack([padded[L - 1 - l: L - 1 - l + x.shape[0]] for l in range(L)])

    def fit(self, sequences: Sequence[np.ndarray], targets: Sequence[np.ndarray],
            masks: Sequence[np.ndarray] | None = None) -> RidgeWindowBaseline:
        """Fit on all trials' masked steps."""
        if not (isinstance(self.lags, numbers.Integral) and self.lags >= 1):
            raise ValueError(f"lags must be an integer ≥ 1, got {self.lags!r}")
        if not (isinstance(self.alpha, numbers.Real) and self.alpha >= 0):
            raise ValueError(f"alpha must be a number ≥ 0, got {self.alpha!r}")
        xs, ys, ms = check_sequence_set(sequences, targets, masks)
        ms = ms if ms is not None else [np.ones(x.shape[0], bool) for x in xs]
        F = np.vstack([self._features(x)[m] for x, m in zip(xs, ms)])
        if F.shape[0] == 0:
            raise ValueError("no training step has mask True: nothing to fit")
        self.model_ = Ridge(alpha=float(self.alpha)).fit(F, np.vstack([y[m] for y, m in zip(ys, ms)]))
        self.input_dim_, self.output_dim_ = int(xs[0].shape[1]), int(ys[0].shape[1])
        return self

    def predict(self, sequence: np.ndarray) -> np.ndarray:
        """(T, d_u) predictions for one trial (T, d_in)."""
        check_is_fitted(self, "model_")
        (x,), _, _ = check_sequence_set([sequence], what="sequence", d_in=self.input_dim_)
        return np.asarray(self.model_.predict(self._features(x))).reshape(x.shape[0], self.output_dim_)
