"""Per-mode gates h_j: window → {0, 1} — "is the wearer's intent predictable here?".

Song & Asada train one binary classifier per task mode j on ``Z_t = 1[q_{s_j}(t) ≤ K]`` (the
within-mode Lipschitz quotient at or below the threshold K). :class:`ModeGates` holds them:

- ``kernel="rbf"`` (default): ``Pipeline(StandardScaler, CalibratedClassifierCV(SVC(rbf,
  class_weight="balanced"), method="sigmoid", cv=n_folds))`` — Platt scaling per fold, the
  probabilities averaged, so the arbitration can use a probability margin;
- ``kernel="nystroem"``: ``Pipeline(Nystroem(rbf), LinearSVC)`` in place of the exact SVC;
- a mode with fewer than ``min_class_count`` points of one class gets a constant gate (its majority
  value), a mode without training points the constant 0 (hand over to the wearer); both recorded
  with the reason in ``constant_modes_``. Each mode is subsampled (stratified, seeded) to
  ``max_samples_per_mode`` rows, since the SVM costs O(n²–n³) (accuracy cost:
  ``benchmarks/bench_learned.py``).

:meth:`ModeGates.proba_one`, the control-tick path, evaluates the fitted pipeline in NumPy:
z = (x − μ)/σ; per fold k, f_k = Σ_i a_ki·exp(−γ‖z − s_i‖²) + b_k over the support vectors (or the
Nyström components, weights Nᵀw_k); p = mean_k 1/(1 + exp(A_k·f_k + B_k)); equal to
:meth:`ModeGates.predict_proba` to 1e-9. Bad settings, shapes, non-finite training rows, modes out
of range or labels other than 0/1 raise ``ValueError``.
"""

from __future__ import annotations

import numbers
from contextlib import nullcontext
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.calibration import CalibratedClassifierCV
from sklearn.kernel_approximation import Nystroem
from sklearn.model_selection import StratifiedKFold
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC, LinearSVC
from sklearn.utils.validation import check_is_fitted
from threadpoolctl import threadpool_limits

__all__ = ["ConstantGate", "ModeGates", "check_gate_inputs", "check_gate_labels"]

KERNELS = ("rbf", "nystroem")


@dataclass(frozen=True)
class ConstantGate:
    """A gate that always answers ``value``; ``reason`` says why the mode got no classifier."""

    value: int
    reason: str
    n_positive: int
    n_negative: int


@dataclass(frozen=True)
class _FastGate:
    """A fitted calibrated gate as plain arrays (equations in the module docstring).

    All folds share the scaler and γ, so their kernel centres are stacked into one
    matrix (RBF support vectors that several folds share are stored once) and each
    fold's decision value is one row of ``weights``.
    """

    mean: np.ndarray          # (D,) scaler μ
    inv_scale: np.ndarray     # (D,) 1/σ
    centers: np.ndarray       # (U, D) distinct support vectors (rbf) or all folds' Nyström components
    centers_sq: np.ndarray    # (U,) ‖c‖²
    gamma: float
    weights: np.ndarray       # (k, U) per fold: dual coefficients (rbf) or Nᵀw (Nyström), 0 elsewhere
    intercepts: np.ndarray    # (k,)
    sig_a: np.ndarray         # (k,) Platt: p_k = 1/(1 + exp(A_k f_k + B_k))
    sig_b: np.ndarray         # (k,)

    def proba(self, x: np.ndarray) -> float:
        z = (x - self.mean) * self.inv_scale
        d2 = self.centers_sq - 2.0 * (self.centers @ z) + z @ z
        np.maximum(d2, 0.0, out=d2)
        d2 *= -self.gamma
        f = self.weights @ np.exp(d2, out=d2) + self.intercepts
        v = self.sig_a * f + self.sig_b
        # 1/(1 + e^v) = e^{−v}/(1 + e^{−v}); pick the form whose exponent is ≤ 0 (no overflow)
        e = np.exp(-np.abs(v))
        return float(np.mean(np.where(v >= 0, e, 1.0) / (1.0 + e)))


def check_gate_inputs(windows: Any, modes: Any, n_modes: int | None,
                      n_features: int | None = None, what: str = "windows") -> tuple[np.ndarray, np.ndarray]:
    """Validate ``windows`` (N, D) finite floats and ``modes`` (N,) ints in [0, n_modes)."""
    X = np.asarray(windows, dtype=float)
    if X.ndim != 2:
        raise ValueError(f"{what} must be 2-D (N, D), got shape {X.shape}")
    if n_features is not None and X.shape[1] != n_features:
        raise ValueError(f"{what} have {X.shape[1]} features, the gates were fitted on {n_features}")
    bad = np.flatnonzero(~np.isfinite(X).all(axis=1))
    if bad.size:
        raise ValueError(f"{what} row {bad[0]} is not finite ({bad.size} such rows)")
    m_raw = np.asarray(modes)
    if m_raw.shape != (X.shape[0],):
        raise ValueError(f"modes must have shape ({X.shape[0]},) to match {what}, got {m_raw.shape}")
    integral = np.issubdtype(m_raw.dtype, np.integer) or (
        np.issubdtype(m_raw.dtype, np.floating) and bool(np.all(m_raw == np.round(m_raw))))
    if m_raw.size and not integral:
        raise ValueError(f"modes must be integers, got dtype {m_raw.dtype}")
    m = m_raw.astype(int)
    if n_modes is not None and m.size:
        out = np.flatnonzero((m < 0) | (m >= n_modes))
        if out.size:
            raise ValueError(f"modes[{out[0]}] = {m[out[0]]} is outside 0..{n_modes - 1} "
                             f"({out.size} such rows)")
    return X, m


def _stratified_subsample(rows: np.ndarray, y: np.ndarray, cap: int, min_count: int,
                          rng: np.random.Generator) -> np.ndarray:
    """``cap`` of ``rows`` drawn without replacement, each class in proportion to its share
    (rounded) but never fewer than ``min(n_class, min_count)`` rows; sorted."""
    n_pos = int(y.sum())
    k_pos = round(cap * n_pos / rows.size)
    k_pos = min(max(k_pos, min(n_pos, min_count)), n_pos, cap - min(rows.size - n_pos, min_count))
    k_neg = cap - k_pos
    pos, neg = rows[y == 1], rows[y == 0]
    return np.sort(np.concatenate([rng.choice(pos, k_pos, replace=False),
                                   rng.choice(neg, k_neg, replace=False)]))


def check_gate_labels(labels: Any, n: int) -> np.ndarray:
    """Validate ``labels`` (n,) of 0/1 (or bool); return them as ints."""
    y_raw = np.asarray(labels)
    if y_raw.shape != (n,):
        raise ValueError(f"labels must have shape ({n},), got {y_raw.shape}")
    if y_raw.dtype == bool:
        return y_raw.astype(int)
    bad = np.flatnonzero(~np.isin(y_raw, (0, 1)))
    if bad.size:
        raise ValueError(f"labels must be 0 or 1, labels[{bad[0]}] = {y_raw[bad[0]]!r} "
                         f"({bad.size} such rows)")
    return y_raw.astype(int)


class ModeGates(BaseEstimator):
    """One calibrated binary classifier per task mode (module docstring).

    Args:
        kernel: ``"rbf"`` (exact SVM, the paper's) or ``"nystroem"`` (approximation).
        C: SVM regularisation.
        gamma: RBF width on the standardised windows; ``"scale"`` = 1/(D · var(z)) of
            the mode's standardised training rows (sklearn's rule, resolved at fit).
        max_samples_per_mode: rows kept per mode for fitting (stratified, seeded
            subsample that keeps at least ``min_class_count`` rows of each class); None
            keeps all.
        min_class_count: a mode with fewer points of either class gets a constant gate.
        n_folds: calibration folds (Platt scaling on held-out folds); ≤ min_class_count.
        n_components: Nyström components (``kernel="nystroem"`` only).
        seed: seeds the subsample, the folds and the Nyström components.

    Fitted attributes: ``n_modes_``, ``n_features_in_``, ``gates_`` (list per mode:
    a fitted ``Pipeline(scale, gate=CalibratedClassifierCV)`` or a :class:`ConstantGate`), ``constant_modes_``
    (dict mode → {"value", "reason", "n_positive", "n_negative"}), ``n_train_`` (rows
    used per mode), ``train_rows_`` (per mode, the indices of those rows into the fitted
    arrays), ``gamma_`` (per mode, None for constant modes).
    """

    def __init__(self, kernel: Literal["rbf", "nystroem"] = "rbf", C: float = 1.0,
                 gamma: float | str = "scale", max_samples_per_mode: int | None = 2000,
                 min_class_count: int = 20, n_folds: int = 3, n_components: int = 300,
                 seed: int = 0) -> None:
        self.kernel = kernel
        self.C = C
        self.gamma = gamma
        self.max_samples_per_mode = max_samples_per_mode
        self.min_class_count = min_class_count
        self.n_folds = n_folds
        self.n_components = n_components
        self.seed = seed

    # ------------------------------------------------------------------ fitting

    def _check_params(self) -> None:
        if self.kernel not in KERNELS:
            raise ValueError(f"kernel must be one of {KERNELS}, got {self.kernel!r}")
        if not (isinstance(self.C, numbers.Real) and self.C > 0):
            raise ValueError(f"C must be a number > 0, got {self.C!r}")
        if not (self.gamma == "scale" or (isinstance(self.gamma, numbers.Real) and self.gamma > 0)):
            raise ValueError(f"gamma must be 'scale' or a number > 0, got {self.gamma!r}")
        if not (isinstance(self.n_folds, numbers.Integral) and self.n_folds >= 2):
            raise ValueError(f"n_folds must be an integer ≥ 2, got {self.n_folds!r}")
        if not (isinstance(self.min_class_count, numbers.Integral) and self.min_class_count >= self.n_folds):
            raise ValueError(f"min_class_count must be an integer ≥ n_folds ({self.n_folds}), "
                             f"got {self.min_class_count!r}")
        m = self.max_samples_per_mode
        if m is not None and not (isinstance(m, numbers.Integral) and m >= 2 * self.min_class_count):
            raise ValueError(f"max_samples_per_mode must be None or an integer ≥ 2·min_class_count "
                             f"({2 * self.min_class_count}), got {m!r}")
        if not (isinstance(self.n_components, numbers.Integral) and self.n_components >= 1):
            raise ValueError(f"n_components must be an integer ≥ 1, got {self.n_components!r}")

    def _new_classifier(self, gamma: float, seed: int) -> Pipeline:
        svm: Any
        if self.kernel == "rbf":
            svm = SVC(kernel="rbf", C=float(self.C), gamma=gamma, class_weight="balanced")
        else:
            svm = Pipeline([("features", Nystroem(kernel="rbf", gamma=gamma, n_components=int(self.n_components),
                                                  random_state=seed)),
                            ("svm", LinearSVC(C=float(self.C), class_weight="balanced", random_state=seed))])
        folds = StratifiedKFold(n_splits=int(self.n_folds), shuffle=True, random_state=seed)
        return Pipeline([("scale", StandardScaler()),
                         ("gate", CalibratedClassifierCV(svm, method="sigmoid", cv=folds))])

    def fit(self, windows: Any, modes: Any, labels: Any, n_modes: int) -> ModeGates:
        """Fit one calibrated gate per mode on ``windows`` (N, D), ``modes`` (N,) in
        [0, n_modes), ``labels`` (N,) in {0, 1} (1 = predictable, Z_t)."""
        self._check_params()
        if not (isinstance(n_modes, numbers.Integral) and n_modes >= 1):
            raise ValueError(f"n_modes must be an integer ≥ 1, got {n_modes!r}")
        X, m = check_gate_inputs(windows, modes, int(n_modes))
        y = check_gate_labels(labels, X.shape[0])
        if X.shape[0] == 0:
            raise ValueError("no training rows: windows is empty")
        with threadpool_limits(1):  # small matrices: BLAS threads only add contention
            self._fit_modes(X, m, y, int(n_modes))
        return self

    def _fit_modes(self, X: np.ndarray, m: np.ndarray, y: np.ndarray, n_modes: int) -> None:
        rng = np.random.default_rng(self.seed)
        gates: list[Any] = []
        constant: dict[int, dict[str, Any]] = {}
        n_train: list[int] = []
        kept: list[np.ndarray] = []
        gammas: list[float | None] = []
        for j in range(n_modes):
            seed_j = int(rng.integers(2**31 - 1))
            rows = np.flatnonzero(m == j)
            yj = y[rows]
            n_pos, n_neg = int(yj.sum()), int(rows.size - yj.sum())
            reason = None
            if rows.size == 0:
                value, reason = 0, "no training points in this mode: hand over to the wearer"
            elif min(n_pos, n_neg) < self.min_class_count:
                value = int(n_pos > n_neg)
                reason = (f"{n_pos} predictable and {n_neg} unpredictable points: too few of one kind to "
                          f"learn from (at least {self.min_class_count} of each needed), so it keeps the "
                          f"majority's answer")
            if reason is not None:
                gate = ConstantGate(value, reason, n_pos, n_neg)
                constant[j] = {"value": value, "reason": reason, "n_positive": n_pos, "n_negative": n_neg}
                gates.append(gate)
                n_train.append(int(rows.size))
                kept.append(rows)
                gammas.append(None)
                continue
            keep = rows
            cap = self.max_samples_per_mode
            if cap is not None and rows.size > cap:
                keep = _stratified_subsample(rows, yj, int(cap), int(self.min_class_count),
                                             np.random.default_rng(seed_j))
            Xj, yk = X[keep], y[keep]
            gamma = float(self.gamma) if self.gamma != "scale" else self._scale_gamma(Xj)
            gates.append(self._new_classifier(gamma, seed_j).fit(Xj, yk))
            n_train.append(int(keep.size))
            kept.append(keep)
            gammas.append(gamma)
        self.gates_ = gates
        self.constant_modes_ = constant
        self.n_train_ = n_train
        self.train_rows_ = kept
        self.gamma_ = gammas
        self.n_modes_ = n_modes
        self.n_features_in_ = int(X.shape[1])
        self._fast = [None if isinstance(g, ConstantGate) else self._fast_gate(g) for g in gates]

    @staticmethod
    def _scale_gamma(X: np.ndarray) -> float:
        """sklearn's ``gamma="scale"`` on the standardised rows: 1 / (D · var(z))."""
        z = StandardScaler().fit_transform(X)
        var = float(z.var())
        return 1.0 / (X.shape[1] * var) if var > 0 else 1.0

    def _fast_gate(self, pipe: Pipeline) -> _FastGate:
        """Extract the fitted pipeline's parameters for :meth:`proba_one`."""
        scaler: StandardScaler = pipe.named_steps["scale"]
        cal: CalibratedClassifierCV = pipe.named_steps["gate"]
        if list(cal.classes_) != [0, 1]:
            raise RuntimeError(f"unexpected classes {cal.classes_} in a gate; expected [0, 1]")
        blocks, coefs, intercepts, sig_a, sig_b = [], [], [], [], []
        gamma = None
        for cc in cal.calibrated_classifiers_:
            est = cc.estimator
            if self.kernel == "rbf":
                blocks.append(np.asarray(est.support_vectors_, dtype=float))
                coefs.append(np.asarray(est.dual_coef_[0], dtype=float))
                intercepts.append(float(est.intercept_[0]))
                gamma = float(est.gamma)
            else:
                ny: Nystroem = est.named_steps["features"]
                svm: LinearSVC = est.named_steps["svm"]
                blocks.append(np.asarray(ny.components_, dtype=float))
                # f = w · (k(z) @ Nᵀ) + b = (N w)ᵀ-weighted kernel values + b, N = normalization_
                coefs.append(np.asarray(ny.normalization_.T @ svm.coef_[0], dtype=float))
                intercepts.append(float(svm.intercept_[0]))
                gamma = float(ny.gamma)
            sig_a.append(float(cc.calibrators[0].a_))
            sig_b.append(float(cc.calibrators[0].b_))
        stacked = np.vstack(blocks)
        if self.kernel == "rbf":  # a training row is a support vector of several folds: keep it once
            centers, where = np.unique(stacked, axis=0, return_inverse=True)
            where = where.ravel()
        else:
            centers, where = stacked, np.arange(stacked.shape[0])
        W = np.zeros((len(blocks), centers.shape[0]))
        start = 0
        for k, (blk, c) in enumerate(zip(blocks, coefs)):
            np.add.at(W[k], where[start:start + blk.shape[0]], c)
            start += blk.shape[0]
        scale = scaler.scale_ if scaler.scale_ is not None else np.ones_like(scaler.mean_)
        return _FastGate(mean=np.array(scaler.mean_, dtype=float), inv_scale=1.0 / np.asarray(scale, dtype=float),
                         centers=np.ascontiguousarray(centers),
                         centers_sq=np.einsum("ij,ij->i", centers, centers), gamma=float(gamma),
                         weights=W, intercepts=np.array(intercepts), sig_a=np.array(sig_a),
                         sig_b=np.array(sig_b))

    # --------------------------------------------------------------- inference

    def predict_proba(self, windows: Any, modes: Any) -> np.ndarray:
        """(N,) probability that each row is predictable (gate of its mode)."""
        check_is_fitted(self, "gates_")
        X, m = check_gate_inputs(windows, modes, self.n_modes_, self.n_features_in_)
        out = np.empty(X.shape[0])
        # BLAS threads only matter (and only hurt) for large Nyström batches; entering the
        # limit costs milliseconds, so small batches skip it
        ctx = threadpool_limits(1) if X.shape[0] >= 1000 else nullcontext()
        with ctx:
            for j, gate in enumerate(self.gates_):
                rows = np.flatnonzero(m == j)
                if rows.size == 0:
                    continue
                if isinstance(gate, ConstantGate):
                    out[rows] = float(gate.value)
                else:
                    out[rows] = gate.predict_proba(X[rows])[:, 1]
        return out

    def predict(self, windows: Any, modes: Any, threshold: float = 0.5) -> np.ndarray:
        """(N,) int gate decisions: 1 where ``predict_proba ≥ threshold``."""
        if not (isinstance(threshold, numbers.Real) and 0.0 <= threshold <= 1.0):
            raise ValueError(f"threshold must be in [0, 1], got {threshold!r}")
        return (self.predict_proba(windows, modes) >= threshold).astype(int)

    def proba_one(self, window: np.ndarray, mode: int) -> float:
        """Probability that one window (D,) in ``mode`` is predictable — the control-tick
        path (NumPy evaluation of the fitted pipeline, module docstring).

        Raises ValueError for a wrong shape or an unknown mode; a non-finite window
        gives NaN (the arbitration treats it as "not predictable").
        """
        check_is_fitted(self, "gates_")
        x = np.asarray(window, dtype=float)
        if x.shape != (self.n_features_in_,):
            raise ValueError(f"window must have shape ({self.n_features_in_},), got {x.shape}")
        j = int(mode)
        if j != mode or not 0 <= j < self.n_modes_:
            raise ValueError(f"mode must be an integer in 0..{self.n_modes_ - 1}, got {mode!r}")
        fast = getattr(self, "_fast", None)
        if fast is None:  # e.g. an object restored by an older pickle
            fast = self._fast = [None if isinstance(g, ConstantGate) else self._fast_gate(g)
                                 for g in self.gates_]
        gate = fast[j]
        if gate is None:
            return float(self.gates_[j].value)
        return gate.proba(x)

    def describe(self) -> dict[str, Any]:
        """JSON-able summary: kernel, per-mode training rows, gamma and constant gates."""
        check_is_fitted(self, "gates_")
        return {"kernel": self.kernel, "n_modes": self.n_modes_, "n_features": self.n_features_in_,
                "n_train": list(self.n_train_), "gamma": list(self.gamma_),
                "constant_modes": {str(k): dict(v) for k, v in self.constant_modes_.items()}}
