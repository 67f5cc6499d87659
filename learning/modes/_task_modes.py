"""Task modes as a Gaussian HMM over standardised, optionally PCA-reduced observations:
the estimator :class:`TaskModes` (see :mod:`learning.modes`)."""

from __future__ import annotations

import warnings
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.cluster import KMeans
from sklearn.decomposition import PCA
from sklearn.exceptions import ConvergenceWarning
from sklearn.metrics import adjusted_rand_score
from sklearn.preprocessing import StandardScaler
from sklearn.utils.validation import check_is_fitted

from ._hmm import (
    AbsDeltaMonitor,
    RegularizedGaussianHMM,
    check_sequences,
    n_hmm_parameters,
    one_thread,
    quiet_hmmlearn,
    split_sequences,
)
from ._online import HMMFilterParams, ModeFilter, forward_filter_log
from ._params import check_params

__all__ = ["DegenerateModesWarning", "TaskModes"]

# A mode whose expected number of samples is below this fraction of N (and below 1
# sample) is "empty": it is re-seeded once, then reported.
_EMPTY_FRACTION = 1e-3
_KMEANS_MAX_SAMPLES = 10_000


class DegenerateModesWarning(UserWarning):
    """Some HMM states ended with (almost) no occupancy; see ``TaskModes.empty_modes_``."""


@dataclass
class _Restart:
    model: RegularizedGaussianHMM
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
            standardised units (prevents singular states; see ``RegularizedGaussianHMM``).
        seed: everything random (k-means, restarts) derives from it.
        n_jobs: restarts run in this many processes (joblib; None = 1, -1 = all cores). Each
            restart has its own seed, so the fitted model does not depend on it.
        temporal: True (default): the HMM. False: the time-free Gaussian mixture of the same
            emissions (scikit-learn ``GaussianMixture``, one fit per restart), stored as an HMM
            whose every row of A and π equal the mixture weights w, so that p(s_t | s_{t−1}) =
            w_{s_t}: Viterbi, the filter and :class:`ModeFilter` then give the mixture's
            per-sample posteriors p(s | o_t) ∝ w_s·N(o_t; μ_s, Σ_s). ``sticky`` is unused.

    Fitted attributes:
        model_: the hmmlearn ``GaussianHMM`` (in the preprocessed space).
        scaler_, pca_ (or None): preprocessing. n_features_in_: D. n_components_: model dim.
        converged_: bool — last EM improvement below ``tol`` per sample, before ``n_iter``.
        n_iter_: EM iterations of the kept restart. loglik_: its training log-likelihood.
        restart_logliks_: training log-likelihood of every restart.
        restart_ari_: adjusted Rand index of every restart's Viterbi labels against the kept
            restart's (1 for all: every restart found the same partition).
        empty_modes_: indices of states left with ~no occupancy (normally empty).
        n_parameters_: free HMM parameters (used by ``bic``).
        startprob_, transmat_: π and A. expected_durations_: 1/(1−A_ii) [samples].
    """

    def __init__(self, n_modes: int = 4, covariance_type: str = "full",
                 n_pca: float | None = None, n_restarts: int = 5, sticky: float = 10.0,
                 n_iter: int = 200, tol: float = 1e-4, min_covar: float = 1e-3,
                 seed: int = 0, n_jobs: int | None = None, temporal: bool = True) -> None:
        self.n_modes = n_modes
        self.covariance_type = covariance_type
        self.n_pca = n_pca
        self.n_restarts = n_restarts
        self.sticky = sticky
        self.n_iter = n_iter
        self.tol = tol
        self.min_covar = min_covar
        self.seed = seed
        self.n_jobs = n_jobs
        self.temporal = temporal

    def __setstate__(self, state: dict[str, Any]) -> None:
        state.setdefault("temporal", True)  # models pickled before the option were HMMs
        super().__setstate__(state)

    # ------------------------------------------------------------------ fitting
    def _check_params(self) -> None:
        check_params(self)

    @one_thread
    def fit(self, X: np.ndarray, lengths: Sequence[int] | None = None) -> TaskModes:
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
        if self.n_jobs in (None, 1) or len(seeds) == 1:
            runs = [self._fit_restart(Z, lengths, int(s)) for s in seeds]
        else:  # restarts in parallel processes; each is seeded, so the result is the same
            from sklearn.utils.parallel import Parallel, delayed
            runs = Parallel(n_jobs=self.n_jobs)(delayed(self._fit_restart)(Z, lengths, int(s)) for s in seeds)
        best = min(runs, key=lambda r: (r.empty.size, -r.loglik))
        self.model_ = best.model
        self.loglik_ = best.loglik
        self.loglik_history_ = best.history
        self.n_iter_ = best.n_iter
        self.converged_ = best.converged
        self.restart_logliks_ = [r.loglik for r in runs]
        kept = best.model.predict(Z, lengths)
        self.restart_ari_ = [1.0 if r is best else float(adjusted_rand_score(kept, r.model.predict(Z, lengths)))
                             for r in runs]
        self.empty_modes_ = best.empty
        self.n_parameters_ = n_hmm_parameters(K, self.n_components_, self.covariance_type)
        if not self.temporal:  # A is not a parameter of the mixture
            self.n_parameters_ -= K * (K - 1)
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

    def _new_hmm(self, N: int, seed: int) -> RegularizedGaussianHMM:
        K = int(self.n_modes)
        hmm = RegularizedGaussianHMM(
            n_components=K, covariance_type=self.covariance_type,
            min_covar=self.min_covar, startprob_prior=2.0,
            transmat_prior=2.0 + float(self.sticky) * np.eye(K),
            means_prior=0.0, means_weight=0.0, covars_prior=0.0, covars_weight=1.0,
            n_iter=int(self.n_iter), tol=float(self.tol) * N, random_state=seed,
            params="stmc", init_params="", implementation="log")
        hmm.reg_covar = float(self.min_covar)
        hmm.monitor_ = AbsDeltaMonitor(hmm.tol, hmm.n_iter, False)
        return hmm

    def _init_hmm(self, hmm: RegularizedGaussianHMM, Z: np.ndarray, lengths: np.ndarray,
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
        for seq in split_sequences(labels, lengths):
            start[seq[0]] += 1
            np.add.at(trans, (seq[:-1], seq[1:]), 1)
        hmm.startprob_ = start / start.sum()
        hmm.transmat_ = trans / trans.sum(axis=1, keepdims=True)
        hmm.means_ = km.cluster_centers_
        hmm.covars_ = {"full": covs,
                       "diag": np.diagonal(covs, axis1=1, axis2=2).copy(),
                       "spherical": np.diagonal(covs, axis1=1, axis2=2).mean(axis=1),
                       "tied": covs.mean(axis=0)}[self.covariance_type]

    def _fit_mixture(self, Z: np.ndarray, lengths: np.ndarray, seed: int) -> _Restart:
        """One time-free restart: a Gaussian mixture (``temporal=False``, see class doc) as an HMM."""
        from sklearn.mixture import GaussianMixture

        N = Z.shape[0]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            gm = GaussianMixture(int(self.n_modes), covariance_type=self.covariance_type,
                                 reg_covar=float(self.min_covar), max_iter=int(self.n_iter),
                                 tol=float(self.tol), random_state=seed).fit(Z)
        hmm = self._new_hmm(N, seed)
        w = np.asarray(gm.weights_, dtype=float)
        hmm.startprob_ = w
        hmm.transmat_ = np.tile(w, (len(w), 1))
        hmm.means_ = gm.means_
        hmm.covars_ = gm.covariances_
        loglik, post = hmm.score_samples(Z, lengths)
        empty = np.flatnonzero(post.sum(axis=0) < max(_EMPTY_FRACTION * N, 1.0))
        return _Restart(hmm, float(loglik), [float(loglik)], bool(gm.converged_), empty, seed, int(gm.n_iter_))

    def _fit_restart(self, Z: np.ndarray, lengths: np.ndarray, seed: int) -> _Restart:
        """One EM run. hmmlearn's "scaling" forward–backward is used for the fit (measured
        on 108k samples, 5 modes: 2.6× faster than "log", the same log-likelihood to 1e-13
        and the same labels); when it under- or overflows (a sample no state explains)
        the run is repeated in log space. The model keeps "log" for inference."""
        if not self.temporal:
            return self._fit_mixture(Z, lengths, seed)
        try:
            run = self._fit_restart_with(Z, lengths, seed, "scaling")
            if np.isfinite(run.loglik) and np.isfinite(run.history).all():
                return run
        except (ValueError, RuntimeError, FloatingPointError, OverflowError):
            pass
        return self._fit_restart_with(Z, lengths, seed, "log")

    def _fit_restart_with(self, Z: np.ndarray, lengths: np.ndarray, seed: int,
                          implementation: str) -> _Restart:
        N = Z.shape[0]
        hmm = self._new_hmm(N, seed)
        hmm.implementation = implementation
        self._init_hmm(hmm, Z, lengths, seed)
        history: list[float] = []
        n_iter = 0
        for attempt in range(2):  # fit, then at most one re-seeding of empty states
            with quiet_hmmlearn():
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
        hmm.implementation = "log"
        return _Restart(hmm, float(loglik), [float(v) for v in history], bool(converged),
                        empty, seed, n_iter)

    def _reseed(self, hmm: RegularizedGaussianHMM, Z: np.ndarray, lengths: np.ndarray,
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

    @one_thread
    def predict(self, X: np.ndarray, lengths: Sequence[int] | None = None) -> np.ndarray:
        """(N,) most likely mode sequence of each trial (Viterbi, hmmlearn)."""
        Z, lengths = self._prepare(X, lengths)
        return self.model_.predict(Z, lengths)

    @one_thread
    def predict_proba(self, X: np.ndarray, lengths: Sequence[int] | None = None) -> np.ndarray:
        """(N, K) smoothed posteriors p(s_t | whole trial) (forward–backward, hmmlearn)."""
        Z, lengths = self._prepare(X, lengths)
        return self.model_.predict_proba(Z, lengths)

    @one_thread
    def _forward(self, X: Any, lengths: Any) -> tuple[np.ndarray, np.ndarray]:
        Z, lengths = self._prepare(X, lengths)
        # Emission log densities: RegularizedGaussianHMM's override (hmmlearn's method for
        # diag/spherical; the hmmlearn version is capped in pyproject for that reason).
        logb = self.model_._compute_log_likelihood(Z)
        with np.errstate(divide="ignore"):
            log_pi = np.log(self.model_.startprob_)
            log_A = np.log(self.model_.transmat_)
        post, pred = [], []
        for lb in split_sequences(logb, lengths):
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

    @one_thread
    def score(self, X: np.ndarray, lengths: Sequence[int] | None = None) -> float:
        """Total log-likelihood Σ_trials log p(z_0..z_T) of the preprocessed observations."""
        Z, lengths = self._prepare(X, lengths)
        return float(self.model_.score(Z, lengths))

    def bic(self, X: np.ndarray, lengths: Sequence[int] | None = None) -> float:
        """BIC = −2·score + n_parameters_·log N (lower is better)."""
        return -2.0 * self.score(X, lengths) + self.n_parameters_ * np.log(len(X))

    @one_thread
    def make_filter(self, fixed_lag: int = 0) -> ModeFilter:
        """A fresh online :class:`ModeFilter` for this model (built from :meth:`filter_params`)."""
        return ModeFilter(self.filter_params(), fixed_lag=fixed_lag)

    def filter_params(self) -> HMMFilterParams:
        """The fitted model as a frozen :class:`HMMFilterParams`: everything the online
        filter needs (π, A, means, full covariances, scaler and PCA), as read-only arrays.

        Built from public attributes only (hmmlearn's ``covars_`` gives full (K, D, D)
        matrices for every covariance type); save it with a model bundle and build
        ``ModeFilter(params)`` without the estimator.
        """
        check_is_fitted(self, "model_")
        hmm = self.model_
        pca = self.pca_
        return HMMFilterParams(
            startprob=hmm.startprob_, transmat=hmm.transmat_, means=hmm.means_,
            covars=hmm.covars_, scaler_mean=self.scaler_.mean_, scaler_scale=self.scaler_.scale_,
            pca_mean=None if pca is None else pca.mean_,
            pca_components=None if pca is None else pca.components_)
