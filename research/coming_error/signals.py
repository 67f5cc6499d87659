"""Causal signal functions and their scores: trailing and leading window means, time in a state, gamma
dwell hazards (explicit-duration mode model), adaptive conformal quantiles, entropy, AUC.

Every per-step function takes arrays of one trial in time order; "causal" means the value at step t
uses steps ≤ t only.
"""

from __future__ import annotations

import bisect
from collections import deque
from dataclasses import dataclass

import numpy as np
from scipy import stats
from sklearn.metrics import roc_auc_score

__all__ = ["AdaptiveConformal", "GammaDwell", "auc", "dwell_runs", "entropy", "future_mean", "past_mean",
           "time_in_state"]


def past_mean(x: np.ndarray, n: int) -> np.ndarray:
    """Causal trailing mean over the last ``n`` steps, the current one included (fewer at the start):
    m_t = mean(x_{max(0, t−n+1)..t}) along axis 0. NaN entries propagate."""
    x = np.asarray(x, dtype=float)
    if n < 1:
        raise ValueError(f"past_mean needs a window of at least 1 step, got {n}")
    c = np.cumsum(np.concatenate([np.zeros((1,) + x.shape[1:]), x]), axis=0)
    t = np.arange(1, x.shape[0] + 1)
    lo = np.maximum(t - n, 0)
    k = (t - lo).reshape((-1,) + (1,) * (x.ndim - 1))
    return (c[t] - c[lo]) / k


def future_mean(x: np.ndarray, n: int) -> np.ndarray:
    """Mean over the next ``n`` steps, t+1..t+n (the label's window, not causal); NaN where fewer remain."""
    x = np.asarray(x, dtype=float)
    if n < 1:
        raise ValueError(f"future_mean needs a window of at least 1 step, got {n}")
    c = np.cumsum(np.concatenate([np.zeros((1,) + x.shape[1:]), x]), axis=0)
    out = np.full(x.shape, np.nan)
    m = x.shape[0] - n
    if m > 0:
        out[:m] = (c[n + 1:n + 1 + m] - c[1:1 + m]) / n
    return out


def time_in_state(labels: np.ndarray, dt: float) -> np.ndarray:
    """Time [s] spent in the current state, the current step included: d_t = (steps since the state
    began + 1)·dt; restarts at every change of label."""
    labels = np.asarray(labels)
    out = np.empty(labels.size)
    run = 0
    for i in range(labels.size):
        run = run + 1 if i and labels[i] == labels[i - 1] else 1
        out[i] = run * dt
    return out


def dwell_runs(labels: np.ndarray, groups: np.ndarray, dt: float) -> tuple[np.ndarray, np.ndarray]:
    """(state, duration [s]) of every completed run of a state: runs that touch a group's (trial's) first
    or last step are censored and left out."""
    labels, groups = np.asarray(labels), np.asarray(groups)
    if labels.shape != groups.shape:
        raise ValueError(f"labels {labels.shape} and groups {groups.shape} differ in shape")
    states, durs = [], []
    for g in np.unique(groups):
        lab = labels[groups == g]
        cut = np.flatnonzero(np.diff(lab) != 0) + 1
        bounds = np.concatenate([[0], cut, [lab.size]])
        for a, b in zip(bounds[1:-2], bounds[2:-1]):  # the inner runs only
            states.append(lab[a])
            durs.append((b - a) * dt)
    return np.array(states), np.array(durs, dtype=float)


@dataclass
class GammaDwell:
    """Gamma dwell-time laws per state (shape k, scale θ; location 0) of an explicit-duration model.

    ``hazard(d, s)`` = f(d)/S(d) [1/s], the rate of leaving state s after d seconds in it;
    ``change_within(d, h, s)`` = 1 − S(d + h)/S(d), the probability of leaving within the next h seconds.
    A state with fewer than ``min_runs`` completed dwells takes the law fitted to all dwells.
    """

    shape: dict[int, float]
    scale: dict[int, float]
    pooled: tuple[float, float]

    @classmethod
    def fit(cls, states: np.ndarray, durations: np.ndarray, min_runs: int = 5) -> GammaDwell:
        """Maximum-likelihood gamma laws (scipy.stats.gamma.fit, floc=0) per state."""
        durations = np.asarray(durations, dtype=float)
        if durations.size < min_runs or not np.all(durations > 0):
            raise ValueError(f"GammaDwell.fit needs at least {min_runs} positive durations, got "
                             f"{durations.size} (min {durations.min() if durations.size else None})")
        k, _, th = stats.gamma.fit(durations, floc=0)
        shape, scale = {}, {}
        for s in np.unique(states):
            d = durations[states == s]
            if d.size >= min_runs:
                shape[int(s)], _, scale[int(s)] = stats.gamma.fit(d, floc=0)
        return cls(shape, scale, (float(k), float(th)))

    def _law(self, s: int) -> tuple[float, float]:
        return (self.shape[s], self.scale[s]) if s in self.shape else self.pooled

    def hazard(self, d: np.ndarray, states: np.ndarray) -> np.ndarray:
        """f(d)/S(d) per step [1/s] (log-space, finite far into the tail)."""
        d, states = np.asarray(d, dtype=float), np.asarray(states)
        out = np.empty(d.size)
        for s in np.unique(states):
            i = states == s
            k, th = self._law(int(s))
            out[i] = np.exp(stats.gamma.logpdf(d[i], k, scale=th) - stats.gamma.logsf(d[i], k, scale=th))
        return out

    def change_within(self, d: np.ndarray, h: float, states: np.ndarray) -> np.ndarray:
        """1 − S(d + h)/S(d) per step."""
        d, states = np.asarray(d, dtype=float), np.asarray(states)
        out = np.empty(d.size)
        for s in np.unique(states):
            i = states == s
            k, th = self._law(int(s))
            out[i] = -np.expm1(stats.gamma.logsf(d[i] + h, k, scale=th) - stats.gamma.logsf(d[i], k, scale=th))
        return out


class AdaptiveConformal:
    """Adaptive conformal inference (Gibbs & Candès, 2021) on a stream of nonconformity scores.

    Before score s_t arrives, the interval's radius is q_t, the (1 − a_t) empirical quantile of the last
    ``window`` scores; then err_t = [s_t > q_t] and a_{t+1} = a_t + γ·(a − err_t). a_t ≤ 0 gives the
    largest past score, a_t ≥ 1 gives 0. Over a long stream the miscoverage rate tends to ``a`` whatever
    the scores do. ``delay`` d: score s_t is known only at step t + d (an h-step forecast's residual).
    """

    def __init__(self, miscoverage: float = 0.1, gamma: float = 0.005, window: int = 1000, delay: int = 0) -> None:
        if not 0 < miscoverage < 1 or gamma <= 0 or window < 1 or delay < 0:
            raise ValueError(f"AdaptiveConformal needs 0 < miscoverage < 1, gamma > 0, window ≥ 1, delay ≥ 0; got "
                             f"{miscoverage}, {gamma}, {window}, {delay}")
        self.target, self.gamma, self.window, self.delay = miscoverage, gamma, window, delay

    def radii(self, scores: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(q_t, err_t) per step of one stream: q_t from the scores known before step t (those of steps
        < t − delay); NaN (and err NaN) until one is known. A NaN score is skipped (no update)."""
        s = np.asarray(scores, dtype=float)
        q = np.full(s.size, np.nan)
        err = np.full(s.size, np.nan)
        a = self.target
        known: deque[float] = deque()
        ranked: list[float] = []  # the window's scores, sorted
        for t in range(s.size):
            j = t - self.delay - 1  # score j (and whether q_j covered it) becomes known before step t
            if j >= 0 and np.isfinite(s[j]):
                known.append(float(s[j]))
                bisect.insort(ranked, float(s[j]))
                if len(known) > self.window:
                    del ranked[bisect.bisect_left(ranked, known.popleft())]
                if np.isfinite(err[j]):
                    a += self.gamma * (self.target - err[j])
            if ranked:
                q[t] = ranked[-1] if a <= 0 else 0.0 if a >= 1 else _quantile(ranked, 1 - a)
                if np.isfinite(s[t]):
                    err[t] = float(s[t] > q[t])
        return q, err


def _quantile(ranked: list[float], p: float) -> float:
    """The p-quantile of sorted values, linear interpolation (numpy's default)."""
    x = (len(ranked) - 1) * p
    i = int(x)
    return ranked[i] if i + 1 >= len(ranked) else ranked[i] + (x - i) * (ranked[i + 1] - ranked[i])


def entropy(P: np.ndarray) -> np.ndarray:
    """Shannon entropy [nats] of each row of a probability matrix (N, K); 0·log 0 = 0."""
    P = np.asarray(P, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        return -np.sum(np.where(P > 0, P * np.log(P), 0.0), axis=-1)


def auc(y: np.ndarray, score: np.ndarray) -> float | None:
    """Area under the ROC curve of ``score`` for the binary ``y`` (Mann–Whitney, ties count half):
    P(score of a positive > score of a negative). None when one class is absent. NaN pairs are dropped."""
    y, score = np.asarray(y, dtype=float), np.asarray(score, dtype=float)
    ok = np.isfinite(y) & np.isfinite(score)
    y, score = y[ok] > 0.5, score[ok]
    if y.all() or not y.any():
        return None
    return float(roc_auc_score(y, score))
