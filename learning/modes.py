"""HMM task modes (the paper's "missing information"), offline and online.

A Gaussian hidden Markov model over preprocessed observations, fitted without labels
with hmmlearn's :class:`~hmmlearn.hmm.GaussianHMM`::

    s_0 ~ π,   s_t | s_{t-1}=i ~ A_i·,   z_t | s_t=j ~ N(μ_j, Σ_j),   z_t = PCA(standardise(o_t))

Public API
----------
- :class:`TaskModes` — scikit-learn style estimator: ``fit``, ``predict`` (Viterbi),
  ``predict_proba`` (smoothed), ``filter_proba`` (causal), ``log_predictive``, ``score``,
  ``bic``, ``make_filter``.
- :class:`ModeFilter` — online causal posterior, one observation per ``step``.
- :func:`select_n_modes` → :class:`ModeSelection` — number of modes by held-out
  log-likelihood over trials (BIC as a second opinion).
- :func:`match_modes`, :func:`mode_agreement`, :func:`mode_ari`, :func:`relabel` —
  agreement with ground-truth labels (Hungarian matching, accuracy, ARI).

Which inputs (measured on ``sim.demonstrator.generate_demonstrations(3, 10)``, 18k samples
at 10 Hz, 4 true modes, defaults otherwise): per-sample observations (D = 9) give 98 %
agreement (Viterbi; 98 % causal) with a ~2 s fit; 1 s causal windows (D = 90) give only
83–86 % even with PCA to 16 — overlapping windows straddle mode changes and break the
HMM's conditional independence. Fit the modes on per-sample (or short-window) inputs.
On such non-Gaussian data the held-out likelihood and BIC keep rising with K (they chose
6 there), so treat :func:`select_n_modes` as evidence, not as the truth, when K is known.
"""

from __future__ import annotations

import functools
import logging
import warnings
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass, field
from typing import Any, Iterator, Literal, Sequence

import numpy as np
from hmmlearn.base import ConvergenceMonitor
from hmmlearn.hmm import GaussianHMM
from scipy import linalg
from sklearn.base import BaseEstimator
from sklearn.cluster import KMeans
from sklearn.decomposition import PCA
from sklearn.exceptions import ConvergenceWarning
from sklearn.preprocessing import StandardScaler
from sklearn.utils.validation import check_is_fitted

from .modes_metrics import match_modes, mode_agreement, mode_ari, relabel
from .modes_online import ModeFilter, forward_filter_log

__all__ = [
    "TaskModes", "ModeFilter", "ModeSelection", "select_n_modes", "DegenerateModesWarning",
    "match_modes", "mode_agreement", "mode_ari", "relabel", "check_sequences",
]

_COV_TYPES = ("full", "diag", "spherical", "tied")
# A mode whose expected number of samples is below this fraction of N (and below 1
# sample) is "empty": it is re-seeded once, then reported.
_EMPTY_FRACTION = 1e-3
_KMEANS_MAX_SAMPLES = 10_000


class DegenerateModesWarning(UserWarning):
    """Some HMM states ended with (almost) no occupancy; see ``TaskModes.empty_modes_``."""


# --------------------------------------------------------------------------- input checks

def check_sequences(X: Any, lengths: Any = None, n_features: int | None = None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Validate ``X`` (N, D) finite float and ``lengths`` (positive ints summing to N).

    ``lengths=None`` means one sequence. Raises ValueError naming the problem.
    """
    X = np.asarray(X, dtype=np.float64)
    if X.ndim != 2:
        raise ValueError(f"X must be 2-D (n_samples, n_features), got shape {X.shape}")
    N, D = X.shape
    if N == 0 or D == 0:
        raise ValueError(f"X is empty (shape {X.shape})")
    bad = ~np.isfinite(X)
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise ValueError(f"X contains NaN or inf (first at row {r}, column {c})")
    if n_features is not None and D != n_features:
        raise ValueError(f"X has {D} features, but the model was fitted with {n_features}")
    if lengths is None:
        return X, np.array([N], dtype=np.int64)
    lens = np.asarray(lengths)
    if lens.ndim != 1 or lens.size == 0:
        raise ValueError(f"lengths must be a non-empty 1-D sequence, got shape {lens.shape}")
    if not np.issubdtype(lens.dtype, np.integer):
        if not np.all(np.isfinite(lens)) or not np.all(lens == np.round(lens)):
            raise ValueError("lengths must be integers")
    lens = lens.astype(np.int64)
    if (lens <= 0).any():
        raise ValueError(f"lengths must be positive, got {lens[lens <= 0][0]} "
                         f"at position {int(np.flatnonzero(lens <= 0)[0])}")
    if lens.sum() != N:
        raise ValueError(f"lengths sum to {int(lens.sum())} but X has {N} rows")
    return X, lens


def _split(X: np.ndarray, lengths: np.ndarray) -> list[np.ndarray]:
    return np.split(X, np.cumsum(lengths)[:-1])


@contextmanager
def _quiet_hmmlearn() -> Iterator[None]:
    """Mute hmmlearn's 'Model is not converging' log lines (tiny decreases are expected:
    the transition prior and the covariance floor make EM a MAP/regularised ascent)."""
    log = logging.getLogger("hmmlearn.base")

    def drop(record: logging.LogRecord) -> bool:
        return "not converging" not in record.getMessage()

    log.addFilter(drop)
    try:
        yield
    finally:
        log.removeFilter(drop)


@contextmanager
def _single_threaded() -> Iterator[None]:
    """Limit BLAS and OpenMP to one thread while fitting/decoding.

    The matrices here are small (D ≲ 20, K ≲ 10); threading them only adds
    synchronisation, and on a loaded 2-core machine a threaded 9×9 triangular solve
    took milliseconds (EM 20–40× slower). Uses sklearn's thread-pool controller; if that
    private helper is missing, nothing is limited. Parallelism: ``select_n_modes(n_jobs=…)``.
    """
    try:
        from sklearn.utils.parallel import _get_threadpool_controller
        ctx = _get_threadpool_controller().limit(limits=1)
    except Exception:  # pragma: no cover - depends on the sklearn version
        ctx = nullcontext()
    with ctx:
        yield


def _one_thread(method):
    """Decorator: run ``method`` inside :func:`_single_threaded`."""
    @functools.wraps(method)
    def wrapper(*args, **kwargs):
        with _single_threaded():
            return method(*args, **kwargs)
    return wrapper


# --------------------------------------------------------------------------- the HMM

class _RegularizedGaussianHMM(GaussianHMM):
    """hmmlearn ``GaussianHMM`` with two repairs in the M-step.

    1. ``reg_covar`` is added to the diagonal of every covariance after each M-step (as
       sklearn's ``GaussianMixture(reg_covar=…)`` does); hmmlearn 0.3.3 applies
       ``min_covar`` only at initialisation, so a state collapsing onto a few (or
       duplicated) points could become singular and fail in ``decode``.
    2. A state with zero occupancy keeps its previous mean and covariance (hmmlearn would
       compute 0/0 = NaN).

    Full/tied scatter statistics are accumulated with one BLAS product per state instead
    of hmmlearn's three-operand ``einsum`` (same numbers, several times faster).
    """

    reg_covar: float = 1e-3

    def _needs_sufficient_statistics_for_covars(self) -> bool:
        return "c" in self.params and self.covariance_type not in ("full", "tied")

    def _accumulate_sufficient_statistics(self, stats, X, lattice, posteriors, fwdlattice,
                                          bwdlattice):
        super()._accumulate_sufficient_statistics(stats, X, lattice, posteriors, fwdlattice,
                                                  bwdlattice)
        if "c" in self.params and self.covariance_type in ("full", "tied"):
            # Σ_t γ_t(k) x_t x_tᵀ, equal to einsum('ij,ik,il->jkl', posteriors, X, X)
            acc = stats["obs*obs.T"]
            for k in range(self.n_components):
                acc[k] += (X * posteriors[:, k:k + 1]).T @ X

    def _compute_log_likelihood(self, X):
        """log N(x_t; μ_k, Σ_k), as hmmlearn's, but via precomputed L_k⁻¹ and one matrix
        product per state (hmmlearn's per-call triangular solve was up to 40× slower with
        multi-threaded BLAS on a busy 2-core machine)."""
        if self.covariance_type not in ("full", "tied"):
            return super()._compute_log_likelihood(X)
        N, D = X.shape
        out = np.empty((N, self.n_components))
        for k, (mu, cv) in enumerate(zip(self.means_, self.covars_)):
            try:
                L = linalg.cholesky(cv, lower=True)
            except linalg.LinAlgError:  # same fallback as hmmlearn
                L = linalg.cholesky(cv + 1e-7 * np.eye(D), lower=True)
            Linv = linalg.solve_triangular(L, np.eye(D), lower=True)
            y = (X - mu) @ Linv.T
            out[:, k] = -0.5 * (D * np.log(2 * np.pi) + np.einsum("ij,ij->i", y, y)) \
                - np.log(np.diag(L)).sum()
        return out

    def _do_mstep(self, stats):
        means_old = np.array(self.means_, copy=True)
        covars_old = np.array(self._covars_, copy=True)
        with np.errstate(divide="ignore", invalid="ignore"):
            super()._do_mstep(stats)
        reg = self.reg_covar
        cov = np.array(self._covars_, dtype=float)
        if self.covariance_type == "full":
            cov = 0.5 * (cov + np.swapaxes(cov, 1, 2)) + reg * np.eye(cov.shape[-1])
        elif self.covariance_type == "tied":
            cov = 0.5 * (cov + cov.T) + reg * np.eye(cov.shape[-1])
        elif self.covariance_type == "diag":
            cov = cov + reg
        else:  # spherical: hmmlearn's M-step tiles to (K, D), which breaks its covars_
            cov = (cov.mean(axis=1) if cov.ndim == 2 else cov) + reg
        dead = ~(stats["post"] > 0) | ~np.isfinite(self.means_).all(axis=1)
        if dead.any():
            self.means_[dead] = means_old[dead]
            if self.covariance_type != "tied":
                cov[dead] = covars_old[dead]
        self._covars_ = cov


class _AbsDeltaMonitor(ConvergenceMonitor):
    """Converged when |Δ log-likelihood| < tol. hmmlearn's monitor also stops on any
    decrease; with the covariance floor and the transition prior EM is a regularised
    ascent whose log-likelihood can dip, and stopping there would be premature."""

    @property
    def converged(self) -> bool:
        h = self.history
        return self.iter >= self.n_iter or (len(h) >= 2 and abs(h[-1] - h[-2]) < self.tol)


def _n_hmm_parameters(K: int, D: int, covariance_type: str) -> int:
    """Free scalars: π (K−1), A (K(K−1)), means (K·D), covariances (by type)."""
    cov = {"full": K * D * (D + 1) // 2, "diag": K * D, "spherical": K,
           "tied": D * (D + 1) // 2}[covariance_type]
    return (K - 1) + K * (K - 1) + K * D + cov


@dataclass
class _Restart:
    model: _RegularizedGaussianHMM
    loglik: float
    history: list[float]
    converged: bool
    empty: np.ndarray
    seed: int
    n_iter: int


class TaskModes(BaseEstimator):
    """Task modes as a Gaussian HMM (hmmlearn) over standardised, optionally PCA-reduced inputs.

    ``X`` (N, D) is the concatenation of trials, ``lengths`` their lengths (hmmlearn
    convention); rows may be per-sample observations (D≈9) or causal windows (D≈90).
    Preprocessing — ``StandardScaler``, then ``PCA`` if ``n_pca`` — is fitted on the
    training data only and applied by every method and by :class:`ModeFilter`.

    EM runs from ``n_restarts`` k-means initialisations (seeds derived from ``seed``); the
    fit with the highest log-likelihood among those without empty states is kept.

    Args:
        n_modes: number of hidden states K.
        covariance_type: "full", "diag", "spherical" or "tied" (hmmlearn's).
        n_pca: None (no PCA), an int (number of components) or a float in (0, 1) (fraction
            of variance kept). For windowed inputs (D≈90) use about 10–20: a full
            covariance in 90-D has ~4k parameters per mode and EM gets slow and overfits.
        n_restarts: EM runs from different k-means initialisations.
        sticky: self-transition prior strength in pseudo-counts. The Dirichlet prior on row
            i of A is α_ij = 2 + sticky·δ_ij: one pseudo-transition everywhere (no
            transition gets probability 0, so held-out trials never score −inf) plus
            ``sticky`` extra self-transitions favouring long-lived modes. The start
            probabilities get one pseudo-count per state. Pseudo-counts are absolute: 10 is
            negligible next to 20k samples, a real push for a few hundred.
        n_iter: maximum EM iterations per restart (hmmlearn's default, 10, stops early).
        tol: convergence threshold on the improvement of the log-likelihood PER SAMPLE
            (hmmlearn's ``tol`` is on the total; here ``tol·N`` is passed), so the criterion
            does not tighten as data grow.
        min_covar: covariance floor added to the diagonal after every M-step, in
            standardised units (prevents singular states; see ``_RegularizedGaussianHMM``).
        seed: everything random (k-means, restarts) derives from it.

    Fitted attributes:
        model_: the hmmlearn ``GaussianHMM`` (in the preprocessed space).
        scaler_, pca_ (or None): preprocessing. n_features_in_: D. n_components_: model dim.
        converged_: bool — last EM improvement below ``tol`` per sample, before ``n_iter``.
        n_iter_: EM iterations of the kept restart. loglik_: its training log-likelihood.
        restart_logliks_: training log-likelihood of every restart.
        empty_modes_: indices of states left with ~no occupancy (normally empty).
        n_parameters_: free HMM parameters (used by ``bic``).
        startprob_, transmat_: π and A. expected_durations_: 1/(1−A_ii) [samples].
    """

    def __init__(self, n_modes: int = 4, covariance_type: str = "full",
                 n_pca: int | float | None = None, n_restarts: int = 5, sticky: float = 10.0,
                 n_iter: int = 200, tol: float = 1e-4, min_covar: float = 1e-3,
                 seed: int = 0) -> None:
        self.n_modes = n_modes
        self.covariance_type = covariance_type
        self.n_pca = n_pca
        self.n_restarts = n_restarts
        self.sticky = sticky
        self.n_iter = n_iter
        self.tol = tol
        self.min_covar = min_covar
        self.seed = seed

    # ------------------------------------------------------------------ fitting
    def _check_params(self) -> None:
        if int(self.n_modes) != self.n_modes or self.n_modes < 1:
            raise ValueError(f"n_modes must be a positive integer, got {self.n_modes!r}")
        if self.covariance_type not in _COV_TYPES:
            raise ValueError(f"covariance_type must be one of {_COV_TYPES}, "
                             f"got {self.covariance_type!r}")
        if int(self.n_restarts) != self.n_restarts or self.n_restarts < 1:
            raise ValueError(f"n_restarts must be a positive integer, got {self.n_restarts!r}")
        if int(self.n_iter) != self.n_iter or self.n_iter < 1:
            raise ValueError(f"n_iter must be a positive integer, got {self.n_iter!r}")
        if not self.sticky >= 0:
            raise ValueError(f"sticky must be >= 0, got {self.sticky!r}")
        if not self.tol >= 0:
            raise ValueError(f"tol must be >= 0, got {self.tol!r}")
        if not self.min_covar > 0:
            raise ValueError(f"min_covar must be > 0, got {self.min_covar!r}")
        if self.n_pca is not None:
            ok = (isinstance(self.n_pca, (int, np.integer)) and self.n_pca >= 1) or \
                 (isinstance(self.n_pca, float) and 0 < self.n_pca < 1)
            if not ok:
                raise ValueError("n_pca must be None, a positive int or a float in (0, 1), "
                                 f"got {self.n_pca!r}")

    @_one_thread
    def fit(self, X: np.ndarray, lengths: Sequence[int] | None = None) -> "TaskModes":
        """Fit scaler, PCA and the HMM on trials ``X`` (N, D) with ``lengths``."""
        self._check_params()
        X, lengths = check_sequences(X, lengths)
        N, D = X.shape
        K = int(self.n_modes)
        if N < K:
            raise ValueError(f"{N} samples cannot be split into {K} modes")
        self.n_features_in_ = D
        self.scaler_ = StandardScaler().fit(X)
        Z = self.scaler_.transform(X)
        self.pca_ = None
        if self.n_pca is not None:
            n = self.n_pca if isinstance(self.n_pca, float) else min(int(self.n_pca), D, N)
            self.pca_ = PCA(n_components=n, svd_solver="full").fit(Z)
            Z = self.pca_.transform(Z)
        self.n_components_ = Z.shape[1]

        seeds = np.random.SeedSequence(int(self.seed)).generate_state(int(self.n_restarts))
        runs = [self._fit_restart(Z, lengths, int(s)) for s in seeds]
        best = min(runs, key=lambda r: (r.empty.size, -r.loglik))
        self.model_ = best.model
        self.loglik_ = best.loglik
        self.loglik_history_ = best.history
        self.n_iter_ = best.n_iter
        self.converged_ = best.converged
        self.restart_logliks_ = [r.loglik for r in runs]
        self.empty_modes_ = best.empty
        self.n_parameters_ = _n_hmm_parameters(K, self.n_components_, self.covariance_type)
        self.startprob_ = np.array(best.model.startprob_)
        self.transmat_ = np.array(best.model.transmat_)
        with np.errstate(divide="ignore"):
            self.expected_durations_ = 1.0 / (1.0 - np.diag(self.transmat_))
        if best.empty.size:
            warnings.warn(f"TaskModes: state(s) {best.empty.tolist()} of {K} have almost no "
                          "occupancy even after re-seeding; the data may support fewer modes. "
                          "Decoding still works (those states are never chosen).",
                          DegenerateModesWarning, stacklevel=2)
        return self

    def _new_hmm(self, N: int, seed: int) -> _RegularizedGaussianHMM:
        K = int(self.n_modes)
        hmm = _RegularizedGaussianHMM(
            n_components=K, covariance_type=self.covariance_type,
            min_covar=self.min_covar, startprob_prior=2.0,
            transmat_prior=2.0 + float(self.sticky) * np.eye(K),
            means_prior=0.0, means_weight=0.0, covars_prior=0.0, covars_weight=1.0,
            n_iter=int(self.n_iter), tol=float(self.tol) * N, random_state=seed,
            params="stmc", init_params="", implementation="log")
        hmm.reg_covar = float(self.min_covar)
        hmm.monitor_ = _AbsDeltaMonitor(hmm.tol, hmm.n_iter, False)
        return hmm

    def _init_hmm(self, hmm: _RegularizedGaussianHMM, Z: np.ndarray, lengths: np.ndarray,
                  seed: int) -> None:
        """k-means (on ≤10k samples) → means, per-cluster covariances, and π, A from the
        k-means label sequence plus the prior pseudo-counts."""
        N, D = Z.shape
        K = int(self.n_modes)
        rng = np.random.default_rng(seed)
        sub = Z if N <= _KMEANS_MAX_SAMPLES else Z[rng.choice(N, _KMEANS_MAX_SAMPLES, replace=False)]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)  # fewer distinct points than K
            km = KMeans(n_clusters=K, n_init=1, random_state=seed).fit(sub)
        labels = km.predict(Z)
        reg = self.min_covar * np.eye(D)
        glob = np.cov(Z.T).reshape(D, D) + reg
        covs = np.empty((K, D, D))
        for k in range(K):
            Zk = Z[labels == k]
            covs[k] = np.cov(Zk.T).reshape(D, D) + reg if len(Zk) > D else glob
        start = np.ones(K)
        trans = np.ones((K, K)) + float(self.sticky) * np.eye(K)
        for seq in _split(labels, lengths):
            start[seq[0]] += 1
            np.add.at(trans, (seq[:-1], seq[1:]), 1)
        hmm.startprob_ = start / start.sum()
        hmm.transmat_ = trans / trans.sum(axis=1, keepdims=True)
        hmm.means_ = km.cluster_centers_
        hmm.covars_ = {"full": covs,
                       "diag": np.diagonal(covs, axis1=1, axis2=2).copy(),
                       "spherical": np.diagonal(covs, axis1=1, axis2=2).mean(axis=1),
                       "tied": covs.mean(axis=0)}[self.covariance_type]

    def _fit_restart(self, Z: np.ndarray, lengths: np.ndarray, seed: int) -> _Restart:
        N = Z.shape[0]
        hmm = self._new_hmm(N, seed)
        self._init_hmm(hmm, Z, lengths, seed)
        history: list[float] = []
        n_iter = 0
        for attempt in range(2):  # fit, then at most one re-seeding of empty states
            with _quiet_hmmlearn():
                hmm.fit(Z, lengths)
            history.extend(hmm.monitor_.history)
            n_iter += hmm.monitor_.iter
            loglik, post = hmm.score_samples(Z, lengths)
            occupancy = post.sum(axis=0)
            empty = np.flatnonzero(occupancy < max(_EMPTY_FRACTION * N, 1.0))
            if not empty.size or attempt == 1:
                break
            self._reseed(hmm, Z, lengths, empty, seed)
        h = hmm.monitor_.history
        converged = len(h) >= 2 and abs(h[-1] - h[-2]) < hmm.tol
        return _Restart(hmm, float(loglik), [float(v) for v in history], bool(converged),
                        empty, seed, n_iter)

    def _reseed(self, hmm: _RegularizedGaussianHMM, Z: np.ndarray, lengths: np.ndarray,
                empty: np.ndarray, seed: int) -> None:
        """Move each empty state onto a poorly explained sample (one of the 1 % with the
        lowest emission likelihood), with the global covariance."""
        rng = np.random.default_rng([seed, 1])
        D = Z.shape[1]
        worst = np.argsort(hmm._compute_log_likelihood(Z).max(axis=1))
        pool = worst[:max(len(empty), Z.shape[0] // 100)]
        picks = rng.choice(pool, size=len(empty), replace=len(pool) < len(empty))
        means = np.array(hmm.means_)
        means[empty] = Z[picks]
        hmm.means_ = means
        glob = np.cov(Z.T).reshape(D, D) + self.min_covar * np.eye(D)
        cov = np.array(hmm._covars_, copy=True)
        if self.covariance_type == "full":
            cov[empty] = glob
        elif self.covariance_type == "diag":
            cov[empty] = np.diag(glob)
        elif self.covariance_type == "spherical":
            cov[empty] = np.diag(glob).mean()
        hmm._covars_ = cov
        hmm.init_params = ""

    # ------------------------------------------------------------------ inference
    def _prepare(self, X: Any, lengths: Any) -> tuple[np.ndarray, np.ndarray]:
        check_is_fitted(self, "model_")
        X, lengths = check_sequences(X, lengths, self.n_features_in_)
        return self.transform(X), lengths

    def transform(self, X: np.ndarray) -> np.ndarray:
        """Preprocessed observations z (N, n_components_): standardised, then PCA."""
        check_is_fitted(self, "model_")
        X, _ = check_sequences(X, None, self.n_features_in_)
        Z = self.scaler_.transform(X)
        return self.pca_.transform(Z) if self.pca_ is not None else Z

    @_one_thread
    def predict(self, X: np.ndarray, lengths: Sequence[int] | None = None) -> np.ndarray:
        """(N,) most likely mode sequence of each trial (Viterbi, hmmlearn)."""
        Z, lengths = self._prepare(X, lengths)
        return self.model_.predict(Z, lengths)

    @_one_thread
    def predict_proba(self, X: np.ndarray, lengths: Sequence[int] | None = None) -> np.ndarray:
        """(N, K) smoothed posteriors p(s_t | whole trial) (forward–backward, hmmlearn)."""
        Z, lengths = self._prepare(X, lengths)
        return self.model_.predict_proba(Z, lengths)

    @_one_thread
    def _forward(self, X: Any, lengths: Any) -> tuple[np.ndarray, np.ndarray]:
        Z, lengths = self._prepare(X, lengths)
        logb = self.model_._compute_log_likelihood(Z)  # hmmlearn's emission log densities
        with np.errstate(divide="ignore"):
            log_pi = np.log(self.model_.startprob_)
            log_A = np.log(self.model_.transmat_)
        post, pred = [], []
        for lb in _split(logb, lengths):
            lp, lq = forward_filter_log(log_pi, log_A, lb)
            post.append(np.exp(lp))
            pred.append(lq)
        return np.concatenate(post), np.concatenate(pred)

    def filter_proba(self, X: np.ndarray, lengths: Sequence[int] | None = None) -> np.ndarray:
        """(N, K) causal posteriors p(s_t | o_0..o_t) within each trial (offline forward
        pass in log space; what :class:`ModeFilter` computes online)."""
        return self._forward(X, lengths)[0]

    def log_predictive(self, X: np.ndarray, lengths: Sequence[int] | None = None) -> np.ndarray:
        """(N,) log p(o_t | o_0..o_{t−1}) within each trial: the causal novelty score."""
        return self._forward(X, lengths)[1]

    @_one_thread
    def score(self, X: np.ndarray, lengths: Sequence[int] | None = None) -> float:
        """Total log-likelihood Σ_trials log p(z_0..z_T) of the preprocessed observations."""
        Z, lengths = self._prepare(X, lengths)
        return float(self.model_.score(Z, lengths))

    def bic(self, X: np.ndarray, lengths: Sequence[int] | None = None) -> float:
        """BIC = −2·score + n_parameters_·log N (lower is better)."""
        return -2.0 * self.score(X, lengths) + self.n_parameters_ * np.log(len(X))

    @_one_thread
    def make_filter(self, fixed_lag: int = 0) -> ModeFilter:
        """A fresh online :class:`ModeFilter` for this model."""
        return ModeFilter(self, fixed_lag=fixed_lag)


# --------------------------------------------------------------------------- model selection

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
    segs = _split(np.arange(len(X)), lengths)
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
        from tqdm.auto import tqdm
        results = tqdm(results, total=len(tasks), desc="select_n_modes", unit="fit")
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
