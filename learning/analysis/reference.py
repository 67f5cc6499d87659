"""The calibrated claims "modes help" and "the temporal model adds information": random groups,
a time-free reference grouping and per-trial inference.

Quotients q_i = max_{j in group(i)} ‖Δy‖/‖Δx‖ within the HMM modes (a) are compared with those
within a reference (b) of the same windows: random groups of the modes' sizes
(:func:`random_labelings`), or a grouping of the same per-sample features with as many groups
and no temporal information (:func:`reference_segmentation`): ``"gmm"`` (default, a
full-covariance Gaussian mixture: the HMM's emission model without the Markov chain),
``"kmeans-sized"`` (k-means held to the modes' group sizes, :func:`size_matched_kmeans`) or
``"kmeans"``. Test (:func:`trial_test`), over trials, the independent units: per-trial medians
a_t, b_t; effect = median_t ln(b_t/a_t) (> 0: modes lower q) with a seeded percentile-bootstrap
interval; one-sided Wilcoxon signed-rank test (scipy) of ln(b_t/a_t) − δ > 0, δ the smallest
effect of interest (``min_effect``; H0: modes lower q by at most the factor e^δ). With n trials
the smallest p is 2⁻ⁿ; below :func:`min_trials_for` the claim is unreachable (``reachable=False``).
Bad shapes, an unknown reference, alpha outside (0, 1) or δ < 0 raise ``ValueError``.

Why this reference and these δ, and the calibration study behind them: docs/design.md,
"Conventions of the analysis"; docs/results.md, "Modes: the two claims, calibration, discovery".
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass
from typing import Callable, Literal

import numpy as np
from scipy import stats
from sklearn.cluster import KMeans
from sklearn.exceptions import ConvergenceWarning
from sklearn.mixture import GaussianMixture

__all__ = ["REFERENCES", "ModeEvidence", "TrialTest", "min_trials_for", "mode_evidence",
           "random_labelings", "reference_segmentation", "size_matched_kmeans", "trial_medians", "trial_test"]

REFERENCES = ("gmm", "kmeans-sized", "kmeans")
Reference = Literal["gmm", "kmeans-sized", "kmeans"]
_FIT_MAX_SAMPLES = 20_000  # centroids/mixtures are fitted on at most this many rows (seeded subsample)


def _subsample(Z: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    return Z if len(Z) <= _FIT_MAX_SAMPLES else Z[rng.choice(len(Z), _FIT_MAX_SAMPLES, replace=False)]


def _sized_assignment(d2: np.ndarray, sizes: np.ndarray) -> np.ndarray:
    """Greedy transportation: (N, K) squared distances, capacities ``sizes`` (sum N) → labels."""
    N, K = d2.shape
    order = np.argsort(d2, axis=None, kind="stable")
    labels = np.full(N, -1)
    room = sizes.astype(np.int64).copy()
    left = N
    for flat in order:
        i, k = divmod(int(flat), K)
        if labels[i] < 0 and room[k] > 0:
            labels[i] = k
            room[k] -= 1
            left -= 1
            if left == 0:
                break
    return labels


def size_matched_kmeans(Z: np.ndarray, sizes, seed: int = 0, max_iter: int = 30) -> np.ndarray:
    """k-means labels (N,) of ``Z`` (N, D) with group k holding exactly ``sizes[k]`` rows.

    Centres start from k-means++ (scikit-learn ``KMeans``, 4 inits, seeded); then the
    size-constrained assignment and the centroid update alternate until no label changes
    (at most ``max_iter`` rounds). Ties broken by index, so the result is deterministic.
    """
    Z = np.asarray(Z, dtype=np.float64)
    sizes = np.asarray(sizes, dtype=np.int64)
    if Z.ndim != 2 or sizes.ndim != 1 or sizes.sum() != len(Z) or (sizes < 0).any():
        raise ValueError(f"sizes must be non-negative and sum to the {len(Z)} rows of Z, got {sizes.tolist()}")
    K = len(sizes)
    rng = np.random.default_rng(seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        centres = KMeans(n_clusters=K, n_init=4, random_state=seed).fit(_subsample(Z, rng)).cluster_centers_
    labels = None
    for _ in range(max_iter):
        d2 = ((Z[:, None, :] - centres[None, :, :]) ** 2).sum(axis=2)
        new = _sized_assignment(d2, sizes)
        if labels is not None and np.array_equal(new, labels):
            break
        labels = new
        centres = np.stack([Z[labels == k].mean(axis=0) if sizes[k] else centres[k] for k in range(K)])
    return labels


def reference_segmentation(Z: np.ndarray, labels: np.ndarray, method: Reference = "gmm",
                           seed: int = 0) -> np.ndarray:
    """A time-free grouping of the per-sample features ``Z`` (N, D) with as many groups as
    ``labels`` (N,) uses (and, for ``"kmeans-sized"``, the same group sizes); see module doc.
    Returns (N,) labels 0…K−1."""
    Z = np.asarray(Z, dtype=np.float64)
    labels = np.asarray(labels)
    if Z.ndim != 2 or len(Z) != len(labels):
        raise ValueError(f"Z must be (N, D) with N = len(labels) = {len(labels)}, got shape {Z.shape}")
    _, sizes = np.unique(labels, return_counts=True)
    K = len(sizes)
    if K == 1:
        return np.zeros(len(Z), dtype=np.int64)
    if method == "kmeans-sized":
        return size_matched_kmeans(Z, sizes, seed)
    rng = np.random.default_rng(seed)
    sub = _subsample(Z, rng)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        if method == "kmeans":
            return KMeans(n_clusters=K, n_init=4, random_state=seed).fit(sub).predict(Z)
        if method == "gmm":
            return GaussianMixture(K, covariance_type="full", n_init=2, reg_covar=1e-3,
                                   random_state=seed).fit(sub).predict(Z)
    raise ValueError(f"reference must be one of {REFERENCES}, got {method!r}")


def trial_medians(q: np.ndarray, trial: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(trial ids, median q per trial). Infinite quotients sort last (a median can be inf)."""
    q = np.asarray(q, dtype=np.float64)
    trial = np.asarray(trial)
    if q.shape != trial.shape or q.ndim != 1:
        raise ValueError(f"q and trial must be 1-D of equal length, got {q.shape} and {trial.shape}")
    ids, inv = np.unique(trial, return_inverse=True)
    return ids, np.array([np.median(q[inv == k]) for k in range(len(ids))])


def min_trials_for(alpha: float) -> int:
    """Fewest trials for which a one-sided Wilcoxon signed-rank test can give p < alpha (2⁻ⁿ < alpha)."""
    return int(math.floor(math.log2(1.0 / alpha))) + 1


@dataclass(frozen=True)
class TrialTest:
    """Per-trial paired test of quotients within modes (a) against a reference (b).

    ``p_value``: one-sided Wilcoxon signed-rank over trials of ln(b_t/a_t) − ``min_effect``
    (H0: modes lower q by at most the factor e^min_effect); ``reachable``: the
    number of trials allows p < ``alpha`` at all; ``claimed``: reachable, p < alpha and
    the effect positive. ``effect``: median over trials of ln(b_t/a_t) (> 0: modes lower
    q), ``ci_low``/``ci_high`` its ``ci_level`` percentile-bootstrap interval over trials.
    """

    p_value: float
    statistic: float
    n_trials: int
    median_a: np.ndarray
    median_b: np.ndarray
    effect: float
    ci_low: float
    ci_high: float
    ci_level: float
    alpha: float
    min_effect: float
    reachable: bool
    claimed: bool


def _log_ratios(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """ln(b/a) per trial; 0/0 and inf/inf count as no difference, x/0 and inf/x as ±large."""
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.log(b) - np.log(a)
    r[(a == b)] = 0.0
    return np.clip(np.nan_to_num(r, nan=0.0, posinf=50.0, neginf=-50.0), -50.0, 50.0)


def trial_test(q_a, q_b, trial, alpha: float = 1e-3, min_effect: float = 0.0, n_boot: int = 2000,
               ci_level: float = 0.95, seed: int = 0) -> TrialTest:
    """One-sided per-trial Wilcoxon test that quotients ``q_a`` are smaller than ``q_b``
    (same samples, ``trial`` their trial ids), with the bootstrap effect size (module doc).

    ``q_b`` may be (n_draws, N) (e.g. several random segmentations): a trial's reference
    median is then the mean of its per-draw medians."""
    q_a = np.asarray(q_a, dtype=np.float64)
    q_b = np.asarray(q_b, dtype=np.float64)
    if q_b.shape[-1:] != q_a.shape or q_a.ndim != 1 or q_b.ndim > 2:
        raise ValueError(f"q_a must be (N,) and q_b (N,) or (n_draws, N), got {q_a.shape} and {q_b.shape}")
    if not 0 < alpha < 1:
        raise ValueError(f"alpha must be in (0, 1), got {alpha}")
    _, a = trial_medians(q_a, trial)
    b = np.mean([trial_medians(qb, trial)[1] for qb in np.atleast_2d(q_b)], axis=0)
    if not min_effect >= 0:
        raise ValueError(f"min_effect must be >= 0, got {min_effect}")
    n = len(a)
    r = _log_ratios(a, b)
    shifted = r - min_effect
    if np.all(shifted == 0):
        p, stat = 1.0, 0.0
    else:
        with np.errstate(divide="ignore", invalid="ignore"):
            res = stats.wilcoxon(shifted, alternative="greater", zero_method="wilcox")
        p, stat = float(res.pvalue), float(res.statistic)
    rng = np.random.default_rng(seed)
    boot = np.median(r[rng.integers(0, n, (n_boot, n))], axis=1)
    lo, hi = np.quantile(boot, [(1 - ci_level) / 2, (1 + ci_level) / 2])
    effect = float(np.median(r))
    reachable = n >= min_trials_for(alpha)
    return TrialTest(p_value=p, statistic=stat, n_trials=n, median_a=a, median_b=b, effect=effect,
                     ci_low=float(lo), ci_high=float(hi), ci_level=ci_level, alpha=alpha,
                     min_effect=float(min_effect), reachable=reachable,
                     claimed=bool(reachable and p < alpha and effect > min_effect))


@dataclass
class ModeEvidence:
    """Quotients within HMM modes, the time-free reference and random groups, and the two tests.

    ``q_modes``, ``q_reference`` (N,), ``q_random`` (n_random, N) over the window rows;
    ``reference_labels`` (N_samples,) per sample; ``vs_reference`` and ``vs_random`` the
    per-trial tests against the time-free reference and against random groups of equal
    sizes. The claim "the temporal model adds information" needs both (intersection–union
    test, level alpha; ``p_value`` is the larger p): on confounded data a coherent
    time-free grouping can lose to random groups (random thinning removes close conflicting
    neighbours, a spatial cluster keeps them), so beating the reference alone is not
    evidence when random labels would beat it too. ``modes_help``: the claim "modes help",
    modes against random groups alone with its own smallest effect of interest
    (``help_effect`` of :func:`mode_evidence`; the paper's test).
    """

    q_modes: np.ndarray
    q_reference: np.ndarray
    q_random: np.ndarray
    reference_labels: np.ndarray
    vs_reference: TrialTest
    vs_random: TrialTest
    modes_help: TrialTest

    @property
    def p_value(self) -> float:
        """p-value of the claim: the larger of the two one-sided p-values."""
        return max(self.vs_reference.p_value, self.vs_random.p_value)

    @property
    def claimed(self) -> bool:
        """Modes lower q beyond both the time-free reference and random groups."""
        return self.vs_reference.claimed and self.vs_random.claimed


def random_labelings(labels: np.ndarray, n_random: int, method: str = "permutation", seed: int = 0
                     ) -> np.ndarray:
    """(n_random, N) random segmentations of ``labels`` (equal group sizes; see
    :func:`learning.analysis.predictability.random_segmentation`), drawn in turn from one generator
    seeded with ``seed`` (the draws :func:`mode_evidence` uses)."""
    from learning.analysis.predictability import random_segmentation

    if n_random < 1:
        raise ValueError(f"n_random must be >= 1, got {n_random}")
    rng = np.random.default_rng(seed)
    return np.stack([random_segmentation(labels, rng, method) for _ in range(n_random)])


def _known(q, name: str, n: int) -> np.ndarray:
    """Quotients passed in by the caller, checked against the number of window rows."""
    q = np.asarray(q, dtype=np.float64)
    if q.shape != (n,):
        raise ValueError(f"{name} must be ({n},) (one quotient per window row), got shape {q.shape}")
    return q


def mode_evidence(X: np.ndarray, Y: np.ndarray, trial: np.ndarray, source_index: np.ndarray,
                  features: np.ndarray, labels: np.ndarray, *, reference: Reference = "gmm",
                  n_random: int = 20, random_method: str = "permutation", alpha: float = 1e-3,
                  min_effect: float = 0.0, help_effect: float | None = None, seed: int = 0,
                  quotient: Callable[..., np.ndarray] | None = None,
                  q_modes: np.ndarray | None = None, q_random: np.ndarray | None = None,
                  reference_labels: np.ndarray | None = None,
                  q_reference: np.ndarray | None = None) -> ModeEvidence:
    """Do the modes ``labels`` (per sample, on ``features`` (N_samples, D), the HMM's input
    space) lower the quotients of the windows ``X`` → ``Y`` (rows taken from samples
    ``source_index``, trials ``trial``) beyond a time-free grouping? See module doc.

    Quotients: within modes and within the reference by
    :func:`learning.lipschitz.pointwise_quotients`, within the ``n_random`` random groupings
    (:func:`random_labelings` with ``seed``) all in one pass by
    :func:`learning.lipschitz.pointwise_quotients_multi` (the same numbers, several times
    faster). ``quotient``, when given, is used for every grouping one by one instead;
    ``q_modes`` (N,) and ``q_random`` (n_random, N) may be passed when already computed
    (``q_random`` for the groupings ``random_labelings(labels[source_index], n_random,
    random_method, seed)``), and ``reference_labels`` (N_samples,), the result of
    ``reference_segmentation(features, labels, reference, seed)``, with ``q_reference``
    (N,) the quotients within it when already computed. ``help_effect``: the smallest effect
    of interest of the claim "modes help" (modes against random groups alone; None: ``min_effect``).
    """
    from learning.lipschitz import pointwise_quotients, pointwise_quotients_multi

    if n_random < 1:
        raise ValueError(f"n_random must be >= 1, got {n_random}")
    labels = np.asarray(labels)
    single = quotient or pointwise_quotients
    if reference_labels is None:
        ref = reference_segmentation(features, labels, reference, seed)
    else:
        ref = np.asarray(reference_labels)
        if ref.shape != labels.shape:
            raise ValueError(f"reference_labels must have the shape of labels {labels.shape}, got {ref.shape}")
    g = labels[source_index]
    qm = single(X, Y, g) if q_modes is None else _known(q_modes, "q_modes", len(g))
    if q_reference is not None and reference_labels is None:
        raise ValueError("q_reference needs the reference_labels it was computed within")
    qr = single(X, Y, ref[source_index]) if q_reference is None else _known(q_reference, "q_reference", len(g))
    if q_random is not None:
        qrand = np.asarray(q_random, dtype=np.float64)
        if qrand.shape != (n_random, len(g)):
            raise ValueError(f"q_random must be (n_random, N) = ({n_random}, {len(g)}), got shape {qrand.shape}")
    else:
        rand = random_labelings(g, n_random, random_method, seed)
        qrand = (np.stack([quotient(X, Y, r) for r in rand]) if quotient is not None
                 else pointwise_quotients_multi(X, Y, rand))
    return ModeEvidence(
        q_modes=qm, q_reference=qr, q_random=qrand, reference_labels=ref,
        vs_reference=trial_test(qm, qr, trial, alpha=alpha, min_effect=min_effect, seed=seed),
        vs_random=trial_test(qm, qrand, trial, alpha=alpha, min_effect=min_effect, seed=seed),
        modes_help=trial_test(qm, qrand, trial, alpha=alpha,
                              min_effect=min_effect if help_effect is None else help_effect, seed=seed))
