"""Per-mode gates h_j: window → {0, 1} — "is the wearer's intent predictable here?".

Song & Asada train one binary classifier per task mode j on the labels
``Z_t = 1[q_{s_j}(t) ≤ K]`` (the within-mode Lipschitz quotient at or below the
threshold K). :class:`ModeGates` holds those classifiers:

- default ``kernel="rbf"``: ``Pipeline(StandardScaler, SVC(rbf, class_weight="balanced"))``
  inside ``CalibratedClassifierCV(method="sigmoid", cv=n_folds)`` (Platt scaling, one
  pipeline + sigmoid per fold, probabilities averaged over the folds), so that the
  arbitration can use a probability margin, not only a 0/1 decision;
- ``kernel="nystroem"``: the same with ``Nystroem(rbf) → LinearSVC`` in place of the
  exact SVC (the approximation the issue allows where the SVM is too slow);
- a mode with fewer than ``min_class_count`` points of one class gets a *constant*
  gate (its majority value); a mode without any training point gets the constant 0
  (hand over to the wearer — the safe choice). Both are recorded with the reason in
  ``constant_modes_``.

Fit time: the SVM is O(n²–n³) in the points of a mode, so each mode is subsampled
(stratified, seeded) to ``max_samples_per_mode`` rows; ``benchmarks/bench_learned.py``
measures the accuracy cost of that against larger subsamples and the Nyström model.

:meth:`ModeGates.proba_one` is the 10 Hz control-tick path. scikit-learn's per-call
validation costs far more than the arithmetic for one row, so the fitted pipelines are
evaluated in NumPy (written here because sklearn has no per-row fast path):
``z = (x − μ)/σ``; ``f = Σ_i a_i exp(−γ‖z − s_i‖²) + b`` (RBF) or
``f = w·(φ(z)) + b`` with ``φ(z) = exp(−γ‖z − c_k‖²)_k · N`` (Nyström);
``p = 1/(1 + exp(A f + B))`` per fold, averaged over the folds. It is tested equal to
:meth:`predict_proba` to 1e-9.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.calibration import CalibratedClassifierCV
from sklearn.kernel_approximation import Nystroem
from sklearn.metrics import accuracy_score, brier_score_loss, f1_score
from sklearn.model_selection import StratifiedKFold, train_test_split
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC, LinearSVC
from sklearn.utils.validation import check_is_fitted
from threadpoolctl import threadpool_limits

__all__ = ["ConstantGate", "ModeGates", "check_gate_inputs", "gate_metrics"]

KERNELS = ("rbf", "nystroem")


@dataclass(frozen=True)
class ConstantGate:
    """A gate that always answers ``value``; ``reason`` says why the mode got no classifier."""

    value: int
    reason: str
    n_positive: int
    n_negative: int


@dataclass(frozen=True)
class _FoldArrays:
    """One calibrated fold as plain arrays (see the module docstring for the equations)."""

    mean: np.ndarray          # (D,) scaler μ
    inv_scale: np.ndarray     # (D,) 1/σ
    centers: np.ndarray       # (S, D) support vectors (rbf) or Nyström components, scaled space
    centers_sq: np.ndarray    # (S,) ‖c‖²
    gamma: float
    weights: np.ndarray       # (S,) dual coefficients (rbf) or (S,) N·w folded (Nyström)
    intercept: float
    sig_a: float              # Platt: p = 1/(1 + exp(A f + B))
    sig_b: float

    def proba(self, x: np.ndarray) -> float:
        z = (x - self.mean) * self.inv_scale
        d2 = self.centers_sq - 2.0 * (self.centers @ z) + z @ z
        f = float(self.weights @ np.exp(-self.gamma * np.maximum(d2, 0.0))) + self.intercept
        return _sigmoid_neg(self.sig_a * f + self.sig_b)


def _sigmoid_neg(v: float) -> float:
    """1/(1 + exp(v)), written to avoid overflow (equals scipy.special.expit(−v))."""
    if v >= 0:
        e = math.exp(-v)
        return e / (1.0 + e)
    return 1.0 / (1.0 + math.exp(v))


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


def _check_labels(labels: Any, n: int) -> np.ndarray:
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
            subsample); None keeps all.
        min_class_count: a mode with fewer points of either class gets a constant gate.
        n_folds: calibration folds (Platt scaling on held-out folds); ≤ min_class_count.
        n_components: Nyström components (``kernel="nystroem"`` only).
        seed: seeds the subsample, the folds and the Nyström components.

    Fitted attributes: ``n_modes_``, ``n_features_in_``, ``gates_`` (list per mode:
    a ``CalibratedClassifierCV`` or a :class:`ConstantGate`), ``constant_modes_``
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

    def _new_classifier(self, gamma: float, seed: int) -> CalibratedClassifierCV:
        if self.kernel == "rbf":
            steps = [("scale", StandardScaler()),
                     ("svm", SVC(kernel="rbf", C=float(self.C), gamma=gamma, class_weight="balanced"))]
        else:
            steps = [("scale", StandardScaler()),
                     ("features", Nystroem(kernel="rbf", gamma=gamma, n_components=int(self.n_components),
                                           random_state=seed)),
                     ("svm", LinearSVC(C=float(self.C), class_weight="balanced", random_state=seed))]
        folds = StratifiedKFold(n_splits=int(self.n_folds), shuffle=True, random_state=seed)
        return CalibratedClassifierCV(Pipeline(steps), method="sigmoid", cv=folds)

    def fit(self, windows: Any, modes: Any, labels: Any, n_modes: int) -> ModeGates:
        """Fit one calibrated gate per mode on ``windows`` (N, D), ``modes`` (N,) in
        [0, n_modes), ``labels`` (N,) in {0, 1} (1 = predictable, Z_t)."""
        self._check_params()
        if not (isinstance(n_modes, numbers.Integral) and n_modes >= 1):
            raise ValueError(f"n_modes must be an integer ≥ 1, got {n_modes!r}")
        X, m = check_gate_inputs(windows, modes, int(n_modes))
        y = _check_labels(labels, X.shape[0])
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
                reason = (f"{n_pos} predictable / {n_neg} unpredictable points: fewer than "
                          f"min_class_count={self.min_class_count} of one class; constant majority "
                          f"value {value}")
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
                keep, _ = train_test_split(rows, train_size=int(cap), stratify=yj, random_state=seed_j)
                keep = np.sort(keep)
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
        self._fast = [None if isinstance(g, ConstantGate) else self._fold_arrays(g) for g in gates]

    @staticmethod
    def _scale_gamma(X: np.ndarray) -> float:
        """sklearn's ``gamma="scale"`` on the standardised rows: 1 / (D · var(z))."""
        z = StandardScaler().fit_transform(X)
        var = float(z.var())
        return 1.0 / (X.shape[1] * var) if var > 0 else 1.0

    def _fold_arrays(self, clf: CalibratedClassifierCV) -> list[_FoldArrays]:
        """Extract each calibrated fold's parameters for :meth:`proba_one`."""
        folds = []
        for cc in clf.calibrated_classifiers_:
            pipe = cc.estimator
            scaler: StandardScaler = pipe.named_steps["scale"]
            svm = pipe.named_steps["svm"]
            if list(svm.classes_) != [0, 1] or len(cc.calibrators) != 1:
                raise RuntimeError(f"unexpected classes {svm.classes_} in a gate; expected [0, 1]")
            cal = cc.calibrators[0]
            scale = scaler.scale_ if scaler.scale_ is not None else np.ones_like(scaler.mean_)
            if self.kernel == "rbf":
                centers = np.array(svm.support_vectors_, dtype=float)
                weights = np.array(svm.dual_coef_[0], dtype=float)
                intercept = float(svm.intercept_[0])
                gamma = float(svm.gamma)
            else:
                ny: Nystroem = pipe.named_steps["features"]
                centers = np.array(ny.components_, dtype=float)
                # f = w · (k(z) @ N.T) + b = (N.T @ w) · k(z) + b
                weights = np.array(ny.normalization_.T @ svm.coef_[0], dtype=float)
                intercept = float(svm.intercept_[0])
                gamma = float(ny.gamma)
            folds.append(_FoldArrays(
                mean=np.array(scaler.mean_, dtype=float), inv_scale=1.0 / np.asarray(scale, dtype=float),
                centers=centers, centers_sq=np.einsum("ij,ij->i", centers, centers), gamma=gamma,
                weights=weights, intercept=intercept, sig_a=float(cal.a_), sig_b=float(cal.b_)))
        return folds

    # --------------------------------------------------------------- inference

    def predict_proba(self, windows: Any, modes: Any) -> np.ndarray:
        """(N,) probability that each row is predictable (gate of its mode)."""
        check_is_fitted(self, "gates_")
        X, m = check_gate_inputs(windows, modes, self.n_modes_, self.n_features_in_)
        out = np.empty(X.shape[0])
        for j, gate in enumerate(self.gates_):
            rows = np.flatnonzero(m == j)
            if rows.size == 0:
                continue
            if isinstance(gate, ConstantGate):
                out[rows] = float(gate.value)
            else:
                with threadpool_limits(1):
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
        folds = self._fast[j]
        if folds is None:
            return float(self.gates_[j].value)
        p = 0.0
        for f in folds:
            p += f.proba(x)
        return p / len(folds)

    def describe(self) -> dict[str, Any]:
        """JSON-able summary: kernel, per-mode training rows, gamma and constant gates."""
        check_is_fitted(self, "gates_")
        return {"kernel": self.kernel, "n_modes": self.n_modes_, "n_features": self.n_features_in_,
                "n_train": list(self.n_train_), "gamma": list(self.gamma_),
                "constant_modes": {str(k): dict(v) for k, v in self.constant_modes_.items()}}


def _scores(y: np.ndarray, p: np.ndarray, threshold: float) -> dict[str, Any]:
    n = int(y.size)
    if n == 0:
        return {"n": 0, "n_positive": 0, "accuracy": None, "f1": None, "brier": None}
    pred = (p >= threshold).astype(int)
    return {"n": n, "n_positive": int(y.sum()),
            "accuracy": float(accuracy_score(y, pred)),
            "f1": float(f1_score(y, pred, zero_division=0.0)),
            "brier": float(brier_score_loss(y, np.clip(p, 0.0, 1.0), pos_label=1))}


def gate_metrics(gates: ModeGates, windows: Any, modes: Any, labels: Any,
                 threshold: float = 0.5) -> dict[str, Any]:
    """Accuracy, F1 (of class 1 = predictable) and Brier score of the gates on (held-out) rows,
    per mode and overall, with counts. JSON-able; a mode without rows has None scores.

    Returns ``{"overall": {...}, "per_mode": {"0": {..., "constant": bool}, ...}}``.
    """
    check_is_fitted(gates, "gates_")
    X, m = check_gate_inputs(windows, modes, gates.n_modes_, gates.n_features_in_)
    y = _check_labels(labels, X.shape[0])
    p = gates.predict_proba(X, m) if X.shape[0] else np.zeros(0)
    per_mode = {}
    for j in range(gates.n_modes_):
        sel = m == j
        per_mode[str(j)] = {**_scores(y[sel], p[sel], threshold), "constant": j in gates.constant_modes_}
    return {"overall": _scores(y, p, threshold), "per_mode": per_mode, "threshold": float(threshold)}
