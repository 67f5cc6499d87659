"""Predictability statistics built on point-wise Lipschitz quotients.

- Threshold K and the reactive/voluntary split: a sample is *voluntary* when its
  quotient exceeds K (q_i > K: no smooth map from observation to action
  explains it), otherwise *reactive*. The share of voluntary samples is
  reported per trial (one demonstration), as in the paper.
- Segmentation test: quotients computed within the groups of a segmentation
  (e.g. HMM task modes) against quotients within random segmentations with the
  same number and sizes of groups. Random segmentations are random *label
  permutations* (each random group is a uniformly random subset of the given
  size; seeded) by default, or random *contiguous* blocks with the same sizes.
  One-sided Mann–Whitney U test (segmentation quotients stochastically
  smaller), with Cliff's delta as effect size.
- Paired per-trial test of voluntary shares at given K (the paper: K = 5, 10):
  one-sided Wilcoxon signed-rank test over trials.
- Model-order selection with the Lipschitz index of He & Asada (1993).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from scipy import stats

from learning.lipschitz import check_inputs, pair_ratios, pointwise_quotients

__all__ = [
    "OrderSelection",
    "PairedShareTest",
    "RankTest",
    "SegmentationComparison",
    "compare_quotients",
    "compare_segmentation",
    "compare_voluntary_shares",
    "lipschitz_index",
    "narx_regressors",
    "paired_wilcoxon",
    "random_segmentation",
    "select_order",
    "split_reactive_voluntary",
    "threshold_from_percentile",
    "voluntary_mask",
    "voluntary_share",
]


# --------------------------------------------------------------------------- threshold, split

def threshold_from_percentile(q, percentile: float = 95.0) -> float:
    """K = the given percentile of the quotients (linear interpolation; inf sorts last).

    Interpolating between a finite value and ``inf`` gives ``inf`` (numpy would give NaN).
    """
    q = np.sort(np.asarray(q, dtype=np.float64).ravel())
    if q.size == 0:
        raise ValueError("q is empty")
    if np.isnan(q).any():
        raise ValueError(f"q contains NaN at position {int(np.argmax(np.isnan(q)))}")
    if not 0.0 <= percentile <= 100.0:
        raise ValueError(f"percentile must be in [0, 100], got {percentile}")
    pos = percentile / 100.0 * (len(q) - 1)
    lo = int(np.floor(pos))
    hi = min(lo + 1, len(q) - 1)
    frac = pos - lo
    if frac == 0.0 or q[lo] == q[hi]:
        return float(q[lo])
    if np.isinf(q[hi]):
        return float("inf")
    return float(q[lo] + frac * (q[hi] - q[lo]))


def voluntary_mask(q, K: float) -> np.ndarray:
    """Boolean mask of voluntary samples, ``q > K``."""
    return np.asarray(q, dtype=np.float64) > K


def split_reactive_voluntary(q, K: float) -> tuple[np.ndarray, np.ndarray]:
    """(reactive, voluntary) boolean masks: q ≤ K and q > K."""
    v = voluntary_mask(q, K)
    return ~v, v


def voluntary_share(q, trial, K: float) -> dict:
    """Share of voluntary samples (q > K) per trial: ``{trial_id: share in [0, 1]}``, sorted by id."""
    q = np.asarray(q, dtype=np.float64)
    trial = np.asarray(trial)
    if q.shape != trial.shape or q.ndim != 1:
        raise ValueError(f"q and trial must be 1-D of equal length, got {q.shape} and {trial.shape}")
    ids, inv = np.unique(trial, return_inverse=True)
    vol = np.bincount(inv, weights=(q > K).astype(np.float64), minlength=len(ids))
    cnt = np.bincount(inv, minlength=len(ids))
    return {ids[k].item(): float(vol[k] / cnt[k]) for k in range(len(ids))}


# --------------------------------------------------------------------------- segmentation test

def random_segmentation(labels, seed: int | np.random.Generator | None = 0,
                        method: Literal["permutation", "contiguous"] = "permutation"
                        ) -> np.ndarray:
    """Random labels with the same number of groups and the same group sizes.

    ``permutation``: a uniformly random permutation of ``labels`` (every group a
    random subset of its size). ``contiguous``: the sequence is cut into
    len(groups) consecutive blocks whose sizes are the group sizes in random
    order, each block taking one of the labels.
    """
    labels = np.asarray(labels)
    rng = np.random.default_rng(seed)
    if method == "permutation":
        return labels[rng.permutation(len(labels))]
    if method == "contiguous":
        ids, counts = np.unique(labels, return_counts=True)
        order = rng.permutation(len(ids))
        return np.repeat(ids[order], counts[order])
    raise ValueError(f"method must be 'permutation' or 'contiguous', got {method!r}")


@dataclass
class RankTest:
    """One-sided Mann–Whitney U test of sample a against sample b.

    ``statistic`` is U of a; ``effect_size`` is Cliff's delta
    P(a > b) − P(a < b) = 2U/(n_a n_b) − 1 (negative: a tends to be smaller).
    """

    statistic: float
    p_value: float
    effect_size: float
    median_a: float
    median_b: float
    n_a: int
    n_b: int
    alternative: str
    test: str = "mannwhitneyu"


def compare_quotients(q_a, q_b, alternative: Literal["less", "greater", "two-sided"] = "less"
                      ) -> RankTest:
    """Mann–Whitney U test that quotients ``q_a`` are stochastically smaller than ``q_b``."""
    a = np.asarray(q_a, dtype=np.float64).ravel()
    b = np.asarray(q_b, dtype=np.float64).ravel()
    if a.size == 0 or b.size == 0:
        raise ValueError("both samples must be non-empty")
    if np.isnan(a).any() or np.isnan(b).any():
        raise ValueError("quotients contain NaN")
    res = stats.mannwhitneyu(a, b, alternative=alternative, method="asymptotic")
    U = float(res.statistic)
    return RankTest(statistic=U, p_value=float(res.pvalue),
                    effect_size=2.0 * U / (a.size * b.size) - 1.0,
                    median_a=float(np.median(a)), median_b=float(np.median(b)),
                    n_a=int(a.size), n_b=int(b.size), alternative=alternative)


@dataclass
class SegmentationComparison:
    """Quotients within a segmentation vs within random segmentations of equal group sizes."""

    test: RankTest
    q_segmentation: np.ndarray
    q_random: np.ndarray  # (n_random, N)
    method: str
    seed: int | None
    random_labels: np.ndarray = field(repr=False)


def compare_segmentation(X, Y, labels, *, n_random: int = 1, seed: int | None = 0,
                         method: Literal["permutation", "contiguous"] = "permutation",
                         alternative: Literal["less", "greater", "two-sided"] = "less",
                         **quotient_kwargs) -> SegmentationComparison:
    """Is a segmentation (e.g. HMM modes) more predictable than chance?

    q within the groups of ``labels`` vs q within ``n_random`` random
    segmentations (``random_segmentation``; seeded), pooled, compared by a
    one-sided Mann–Whitney U test (``alternative="less"``: the segmentation's
    quotients are smaller). Extra keyword arguments go to ``pointwise_quotients``.
    """
    X, Y, labels = check_inputs(X, Y, labels)
    if labels is None:
        raise ValueError("labels are required")
    if n_random < 1:
        raise ValueError(f"n_random must be ≥ 1, got {n_random}")
    q_seg = pointwise_quotients(X, Y, labels, **quotient_kwargs)
    rng = np.random.default_rng(seed)
    rand_labels = np.stack([random_segmentation(labels, rng, method) for _ in range(n_random)])
    q_rand = np.stack([pointwise_quotients(X, Y, g, **quotient_kwargs) for g in rand_labels])
    test = compare_quotients(q_seg, q_rand.ravel(), alternative)
    return SegmentationComparison(test=test, q_segmentation=q_seg, q_random=q_rand, method=method,
                                  seed=seed, random_labels=rand_labels)


@dataclass
class PairedShareTest:
    """One-sided Wilcoxon signed-rank test of per-trial voluntary shares a vs b at threshold K.

    ``effect_size`` is the matched-pairs rank-biserial correlation
    (R⁺ − R⁻)/(R⁺ + R⁻) of the differences a − b (negative: a smaller).
    """

    K: float
    statistic: float
    p_value: float
    effect_size: float
    trials: np.ndarray
    shares_a: np.ndarray
    shares_b: np.ndarray
    median_a: float
    median_b: float
    alternative: str
    test: str = "wilcoxon"


def paired_wilcoxon(a, b, alternative: Literal["less", "greater", "two-sided"] = "less"
                    ) -> tuple[float, float, float]:
    """Wilcoxon signed-rank test of paired samples a vs b: (statistic, p-value, effect size).

    The effect size is the matched-pairs rank-biserial correlation (R⁺ − R⁻)/(R⁺ + R⁻)
    of the differences a − b (negative: a smaller). All-zero differences give (0, 1, 0).
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.shape != b.shape or a.ndim != 1:
        raise ValueError(f"a and b must be 1-D of equal length, got {a.shape} and {b.shape}")
    d = a - b
    nz = d[d != 0]
    if len(nz) == 0:
        return 0.0, 1.0, 0.0
    res = stats.wilcoxon(a, b, alternative=alternative, zero_method="wilcox")
    ranks = stats.rankdata(np.abs(nz))
    eff = float((ranks[nz > 0].sum() - ranks[nz < 0].sum()) / ranks.sum())
    return float(res.statistic), float(res.pvalue), eff


def compare_voluntary_shares(q_a, q_b, trial, K: float | Iterable[float] = (5.0, 10.0),
                             alternative: Literal["less", "greater", "two-sided"] = "less"
                             ) -> list[PairedShareTest]:
    """Paired per-trial test of voluntary shares under two quotient sets, for each K.

    ``q_a``, ``q_b``: quotients of the same samples (e.g. within HMM modes and
    within random segments); ``trial``: the trial id of each sample.
    """
    q_a = np.asarray(q_a, dtype=np.float64)
    q_b = np.asarray(q_b, dtype=np.float64)
    if q_a.shape != q_b.shape:
        raise ValueError(f"q_a and q_b differ in shape: {q_a.shape} vs {q_b.shape}")
    Ks = [float(K)] if np.isscalar(K) else [float(k) for k in K]
    out = []
    for k in Ks:
        sa = voluntary_share(q_a, trial, k)
        sb = voluntary_share(q_b, trial, k)
        ids = np.array(list(sa.keys()))
        a = np.array([sa[t] for t in sa])
        b = np.array([sb[t] for t in sa])
        stat, p, eff = paired_wilcoxon(a, b, alternative)
        out.append(PairedShareTest(K=k, statistic=stat, p_value=p, effect_size=eff, trials=ids,
                                   shares_a=a, shares_b=b, median_a=float(np.median(a)),
                                   median_b=float(np.median(b)), alternative=alternative))
    return out


# --------------------------------------------------------------------------- order selection

def _top_pairwise_quotients(X: np.ndarray, y: np.ndarray, p: int, row_block: int = 128
                            ) -> np.ndarray:
    """The p largest pairwise quotients |Δy|/‖Δx‖ over all unordered pairs, exactly (float64).

    Blocked direct differences, O(N²·d) time, O(row_block·N) memory; identical
    pairs skipped, identical x with different y → inf.
    """
    N = len(X)
    top = np.empty(0)
    for s in range(0, N - 1, row_block):
        e = min(s + row_block, N - 1)
        ii, jj = [], []
        for i in range(s, e):
            ii.append(np.full(N - i - 1, i))
            jj.append(np.arange(i + 1, N))
        i_arr, j_arr = np.concatenate(ii), np.concatenate(jj)
        r = pair_ratios(X, y, i_arr, j_arr)
        r = r[~np.isnan(r)]
        if len(top) == p:
            r = r[r > top.min()]
        top = np.concatenate([top, r])
        if len(top) > p:
            top = np.partition(top, len(top) - p)[-p:]
    return np.sort(top)[::-1]


def lipschitz_index(X, y, p: int | None = None, p_fraction: float = 0.02) -> float:
    """He & Asada's Lipschitz index of a regression y = f(x), x ∈ ℝⁿ.

        q⁽ⁿ⁾ = ( ∏_{k=1}^{p} √n · q(k) )^{1/p},

    q(k) the k-th largest pairwise quotient |y_i − y_j| / ‖x_i − x_j‖, p ≈
    ``p_fraction``·N (0.01–0.02 N); computed in logs. Units of y per unit of x.
    """
    X, Y, _ = check_inputs(X, y)
    N, n = X.shape
    if N < 2:
        raise ValueError("need at least 2 samples")
    if p is None:
        p = max(1, int(np.rint(p_fraction * N)))
    top = _top_pairwise_quotients(X, Y, int(p))
    if len(top) == 0:
        return 0.0
    if np.isinf(top).any():
        return float("inf")
    with np.errstate(divide="ignore"):
        logs = np.log(top)
    return float(np.exp(0.5 * np.log(n) + logs.mean()))


def narx_regressors(u, y, n_y: int, n_u: int, start: int | None = None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """NARX regressors φ(k) = [y(k−1)…y(k−n_y), u(k−1)…u(k−n_u)] and targets y(k).

    Rows k = start … T−1 (``start`` defaults to max(n_y, n_u), at least 1).
    """
    u = np.asarray(u, dtype=np.float64).ravel()
    y = np.asarray(y, dtype=np.float64).ravel()
    if u.shape != y.shape:
        raise ValueError(f"u and y must have equal length, got {u.shape} and {y.shape}")
    if n_y < 0 or n_u < 0 or n_y + n_u == 0:
        raise ValueError("need n_y ≥ 0, n_u ≥ 0 and n_y + n_u ≥ 1")
    k0 = max(n_y, n_u, 1) if start is None else int(start)
    if k0 < max(n_y, n_u):
        raise ValueError("start must be ≥ max(n_y, n_u)")
    T = len(y)
    cols = [y[k0 - l:T - l] for l in range(1, n_y + 1)] + [u[k0 - l:T - l] for l in range(1, n_u + 1)]
    return np.stack(cols, axis=1), y[k0:]


@dataclass
class OrderSelection:
    """Result of ``select_order``: chosen lags and the index of every (n_y, n_u)."""

    n_y: int
    n_u: int
    index: np.ndarray  # (max_lag + 1, max_lag + 1), index[n_y, n_u]; NaN at (0, 0)
    tol: float


def select_order(u, y, max_lag: int = 4, *, p_fraction: float = 0.02, tol: float = 0.1,
                 standardize: bool = True) -> OrderSelection:
    """Choose NARX orders (n_y, n_u) with the Lipschitz index and the knee rule.

    The index q(n_y, n_u) is computed for all 0 ≤ n_y, n_u ≤ max_lag on the same
    target samples. Knee rule: the smallest total order n_y + n_u (ties: the
    smaller index) such that adding one more lag of y or of u lowers the index
    by less than the factor 1 + ``tol`` — the index falls steeply while a
    relevant regressor is missing and stays flat once the order suffices.
    """
    u = np.asarray(u, dtype=np.float64).ravel()
    y = np.asarray(y, dtype=np.float64).ravel()
    if standardize:
        u = (u - u.mean()) / (u.std() or 1.0)
        y = (y - y.mean()) / (y.std() or 1.0)
    M = max_lag + 1  # one more lag than max_lag so every candidate has successors to compare
    Q = np.full((M + 1, M + 1), np.nan)
    for ny in range(M + 1):
        for nu in range(M + 1):
            if ny + nu == 0:
                continue
            Phi, t = narx_regressors(u, y, ny, nu, start=M)
            Q[ny, nu] = lipschitz_index(Phi, t, p_fraction=p_fraction)
    best = None
    for ny in range(max_lag + 1):
        for nu in range(max_lag + 1):
            if ny + nu == 0:
                continue
            q0 = Q[ny, nu]
            flat = Q[ny + 1, nu] * (1.0 + tol) >= q0 and Q[ny, nu + 1] * (1.0 + tol) >= q0
            if flat:
                key = (ny + nu, q0)
                if best is None or key < best[0]:
                    best = (key, ny, nu)
    if best is None:  # never flat: the largest order considered
        ny, nu = np.unravel_index(np.nanargmin(Q[:max_lag + 1, :max_lag + 1]), (M, M))
        best = (None, int(ny), int(nu))
    return OrderSelection(n_y=best[1], n_u=best[2], index=Q[:max_lag + 1, :max_lag + 1], tol=tol)
