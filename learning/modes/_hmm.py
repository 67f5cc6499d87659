"""The Gaussian HMM behind :class:`~learning.modes.TaskModes` and its helpers.

:class:`RegularizedGaussianHMM` overrides private methods of hmmlearn's
``GaussianHMM`` (``_accumulate_sufficient_statistics``, ``_compute_log_likelihood``,
``_do_mstep``, ``_needs_sufficient_statistics_for_covars``) and reads its private
``_covars_``; it was written against hmmlearn 0.3.3, and pyproject caps hmmlearn
below 0.4 for that reason. With the floor off (``reg_covar = 0``), its EM step equals plain hmmlearn's.
"""

from __future__ import annotations

import functools
import logging
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np
from hmmlearn.base import ConvergenceMonitor
from hmmlearn.hmm import GaussianHMM
from scipy import linalg
from threadpoolctl import threadpool_limits

__all__ = [
    "COV_TYPES",
    "AbsDeltaMonitor",
    "RegularizedGaussianHMM",
    "check_sequences",
    "n_hmm_parameters",
    "one_thread",
    "quiet_hmmlearn",
    "split_sequences",
]

COV_TYPES = ("full", "diag", "spherical", "tied")


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
    if not np.issubdtype(lens.dtype, np.integer) and (
            not np.all(np.isfinite(lens)) or not np.all(lens == np.round(lens))):
        raise ValueError("lengths must be integers")
    lens = lens.astype(np.int64)
    if (lens <= 0).any():
        raise ValueError(f"lengths must be positive, got {lens[lens <= 0][0]} "
                         f"at position {int(np.flatnonzero(lens <= 0)[0])}")
    if lens.sum() != N:
        raise ValueError(f"lengths sum to {int(lens.sum())} but X has {N} rows")
    return X, lens


def split_sequences(X: np.ndarray, lengths: np.ndarray) -> list[np.ndarray]:
    """The rows of ``X`` cut into sequences of ``lengths``."""
    return np.split(X, np.cumsum(lengths)[:-1])


@contextmanager
def quiet_hmmlearn() -> Iterator[None]:
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


def one_thread(method):
    """Decorator: run ``method`` with BLAS and OpenMP limited to one thread (threadpoolctl).

    The matrices here are small (D ≲ 20, K ≲ 10); threading them only adds
    synchronisation, and on a loaded 2-core machine a threaded 9×9 triangular solve
    took milliseconds (EM 20–40× slower). Parallelism: ``select_n_modes(n_jobs=…)``.
    """
    @functools.wraps(method)
    def wrapper(*args, **kwargs):
        with threadpool_limits(limits=1):
            return method(*args, **kwargs)
    return wrapper


class RegularizedGaussianHMM(GaussianHMM):
    """hmmlearn ``GaussianHMM`` (0.3.x) with two repairs in the M-step.

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
        for k, (mu, Linv, log_det) in enumerate(self._whiteners()):
            y = (X - mu) @ Linv.T
            out[:, k] = -0.5 * (D * np.log(2 * np.pi) + np.einsum("ij,ij->i", y, y)) - log_det
        return out

    def _whiteners(self) -> list[tuple[np.ndarray, np.ndarray, float]]:
        """Per state (μ_k, L_k⁻¹, log|L_k|) with Σ_k = L_k L_kᵀ, computed once per parameter
        set: hmmlearn evaluates the likelihood one trial at a time, and factorising every
        covariance again for each of 90 trials took 35 % of an EM fit (measured, 108k
        samples in 90 trials, 5 modes). Keyed by the bytes of means and covariances, so a
        change of parameters (M-step, reseeding, user assignment) is always seen."""
        means = np.asarray(self.means_, dtype=float)
        covars = np.asarray(self.covars_, dtype=float)
        key = (means.tobytes(), covars.tobytes())
        cached = getattr(self, "_whitener_cache", None)
        if cached is not None and cached[0] == key:
            return cached[1]
        D = means.shape[1]
        factors = []
        for mu, cv in zip(means, covars):
            try:
                L = linalg.cholesky(cv, lower=True)
            except linalg.LinAlgError:  # same fallback as hmmlearn
                L = linalg.cholesky(cv + 1e-7 * np.eye(D), lower=True)
            Linv = linalg.solve_triangular(L, np.eye(D), lower=True)
            factors.append((mu, Linv, float(np.log(np.diag(L)).sum())))
        self._whitener_cache = (key, factors)
        return factors

    def __getstate__(self):
        state = super().__getstate__()
        state.pop("_whitener_cache", None)  # derived data, rebuilt on first use
        return state

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


class AbsDeltaMonitor(ConvergenceMonitor):
    """Converged when |Δ log-likelihood| < tol. hmmlearn's monitor also stops on any
    decrease; with the covariance floor and the transition prior EM is a regularised
    ascent whose log-likelihood can dip, and stopping there would be premature."""

    @property
    def converged(self) -> bool:
        h = self.history
        return self.iter >= self.n_iter or (len(h) >= 2 and abs(h[-1] - h[-2]) < self.tol)


def n_hmm_parameters(K: int, D: int, covariance_type: str) -> int:
    """Free scalars: π (K−1), A (K(K−1)), means (K·D), covariances (by type)."""
    cov = {"full": K * D * (D + 1) // 2, "diag": K * D, "spherical": K,
           "tied": D * (D + 1) // 2}[covariance_type]
    return (K - 1) + K * (K - 1) + K * D + cov
