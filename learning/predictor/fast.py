"""The two-rate forecast: a linear correction at the control rate on top of the slow LSTM forecast.

The LSTM (:mod:`learning.predictor.lstm`) runs at the model rate (10 Hz) behind the fork's 4 Hz
anti-aliasing and 10 Hz hold (~150 ms of delay). The fast model runs at every raw-rate (control)
step i on inputs with a few ms of delay: ``P_i``, ``V_i`` the fork's Kalman position and velocity
(standardised: ``(x − μ)/s`` and ``ẋ·τ_v/s``, τ_v = :data:`VELOCITY_SCALE_S` [s]); ``p_j`` the mode
posterior of the last model tick j; ``S_i[h]`` that tick's slow forecast at ``t_i + h·Δ_m``
(h = 0 … H, Δ_m the model step [s]), interpolated linearly (:func:`interpolate_slow`). Features
(:func:`fast_design`) and the forecast, a ridge regression of the slow forecast's residual::

    b_i = [1, P_i, P_i − P_{i−l_1}, …, P_i − P_{i−l_n}, V_i]          (lags l in raw steps)
    φ_i = [vec(p_j ⊗ b_i), vec(S_i)]                                   (a per-mode affine map)
    F_i[h] = S_i[h] + W_h φ_i + c_h,   min Σ_i ‖Y_{i+h·f} − S_i[h] − W_h φ_i − c_h‖² + λ‖W‖²

(``Y`` the standardised tip actions at the raw rate, f raw steps per model step). Lags before a
trial's start repeat its first sample. :class:`FastInputStream` builds φ one step at a time for
the controller, equal to the offline rows (tests/learning/predictor/test_fast.py). Bad settings
(λ < 0, lags < 1), mis-shaped or non-finite inputs and too few steps to fit raise ``ValueError``.
"""

from __future__ import annotations

import math
import numbers
from collections import deque
from typing import Any

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.linear_model import Ridge
from sklearn.utils.validation import check_is_fitted

__all__ = ["DEFAULT_LAGS", "VELOCITY_SCALE_S", "FastForecaster", "FastInputStream", "fast_design",
           "interpolate_slow"]

#: lags of the fork position differences [raw steps] (50, 100, 200 ms at 100 Hz)
DEFAULT_LAGS: tuple[int, ...] = (5, 10, 20)
#: the Kalman velocity enters as the displacement over this time [s] (unit scale)
VELOCITY_SCALE_S = 0.1


def interpolate_slow(points: np.ndarray, frac: np.ndarray) -> np.ndarray:
    """Slow forecast points (n, H+1, d) of ticks, read ``frac`` (n,) model steps later, per horizon.

    Row i, horizon h: linear interpolation of ``points[i]`` at index a = frac_i + h, the last
    point held past the end (a ≥ H). Returns (n, H+1, d).
    """
    points = np.asarray(points, dtype=float)
    n, n_h, _ = points.shape
    a = np.minimum(np.asarray(frac, dtype=float)[:, None] + np.arange(n_h)[None, :], n_h - 1)
    lo = np.floor(a).astype(int)
    hi = np.minimum(lo + 1, n_h - 1)
    w = (a - lo)[:, :, None]
    rows = np.arange(n)[:, None]
    return (1.0 - w) * points[rows, lo] + w * points[rows, hi]


def _base(P: np.ndarray, V: np.ndarray, lagged: list[np.ndarray]) -> np.ndarray:
    """b = [1, P, P − P_l …, V] per row (module docstring)."""
    ones = np.ones((P.shape[0], 1))
    return np.hstack([ones, P, *[P - L for L in lagged], V])


def fast_design(P: np.ndarray, V: np.ndarray, proba: np.ndarray, slow: np.ndarray,
                lags: tuple[int, ...] = DEFAULT_LAGS, rows: np.ndarray | None = None) -> np.ndarray:
    """Feature rows φ (n, n_features) of one trial (module docstring).

    Args:
        P, V: (T, d_o) standardised Kalman position and velocity per raw step.
        proba: (T, K) mode posterior of the last tick at each step.
        slow: (T, H+1, d_y) interpolated slow forecast at each step.
        lags: position lags [raw steps]; before the trial's start the first row is repeated.
        rows: the steps to build (None: all T).
    """
    idx = np.arange(P.shape[0]) if rows is None else np.asarray(rows)
    lagged = [P[np.maximum(idx - int(lag), 0)] for lag in lags]
    b = _base(P[idx], V[idx], lagged)
    n = idx.size
    kron = (proba[idx][:, :, None] * b[:, None, :]).reshape(n, -1)
    return np.hstack([kron, slow[idx].reshape(n, -1)])


class FastInputStream:
    """:func:`fast_design` one step at a time (the controller's side): ``step(P, V, proba, slow) -> φ``."""

    def __init__(self, lags: tuple[int, ...] = DEFAULT_LAGS) -> None:
        self.lags = tuple(int(lag) for lag in lags)
        self._maxlag = max(self.lags, default=0)
        self.reset()

    def reset(self) -> None:
        """Forget the history (the next step is a trial's first)."""
        self._hist: deque[np.ndarray] = deque(maxlen=self._maxlag + 1)

    def step(self, P: np.ndarray, V: np.ndarray, proba: np.ndarray, slow: np.ndarray) -> np.ndarray:
        """φ (n_features,) of this step: P, V (d_o,), proba (K,), slow (H+1, d_y)."""
        P = np.asarray(P, dtype=float)
        if not self._hist:
            for _ in range(self._maxlag):
                self._hist.append(P)
        self._hist.append(P)
        n = len(self._hist)
        lagged = [self._hist[n - 1 - lag][None, :] for lag in self.lags]
        b = _base(P[None, :], np.asarray(V, dtype=float)[None, :], lagged)[0]
        return np.concatenate([np.outer(proba, b).ravel(), np.asarray(slow, dtype=float).ravel()])


class FastForecaster(BaseEstimator):
    """Ridge correction of the slow forecast at the control rate (module docstring).

    Args:
        alpha: ridge penalty λ (on features of unit scale).
        lags: position lags [raw steps] of the features.

    Fitted attributes: ``coef_`` (n_out, n_features), ``intercept_`` (n_out,), ``n_horizons_``
    (H+1), ``output_dim_`` (d_y), ``n_features_in_``. Set by the training that fits it:
    ``channels_`` (the d_y action names forecast) and ``preview_skill_`` (n_modes, H+1), the
    skill against the hold per mode and horizon on validation trials (the MPC's preview uses
    the forecast only where it is above 0).
    """

    def __init__(self, alpha: float = 1.0, lags: tuple[int, ...] = DEFAULT_LAGS) -> None:
        self.alpha = alpha
        self.lags = lags

    def fit(self, phi: np.ndarray, slow: np.ndarray, target: np.ndarray) -> FastForecaster:
        """Fit on rows φ (n, n_features), slow forecasts (n, H+1, d_y) and true futures (n, H+1, d_y)."""
        if not (isinstance(self.alpha, numbers.Real) and math.isfinite(self.alpha) and self.alpha >= 0):
            raise ValueError(f"alpha must be a finite number >= 0, got {self.alpha!r}")
        if any(not (isinstance(lag, numbers.Integral) and lag >= 1) for lag in self.lags):
            raise ValueError(f"lags must be integers >= 1 (raw steps), got {self.lags!r}")
        phi, slow, target = (np.asarray(a, dtype=float) for a in (phi, slow, target))
        if phi.ndim != 2 or slow.ndim != 3 or target.shape != slow.shape or phi.shape[0] != slow.shape[0]:
            raise ValueError(f"phi (n, p), slow and target (n, H+1, d) expected, got {phi.shape}, {slow.shape}, "
                             f"{target.shape}")
        if phi.shape[0] <= phi.shape[1]:
            raise ValueError(f"{phi.shape[0]} rows for {phi.shape[1]} features: too few steps to fit")
        if not (np.isfinite(phi).all() and np.isfinite(slow).all() and np.isfinite(target).all()):
            raise ValueError("fast forecaster: non-finite features or targets")
        n = phi.shape[0]
        model = Ridge(alpha=float(self.alpha)).fit(phi, (target - slow).reshape(n, -1))
        self.coef_ = np.ascontiguousarray(model.coef_, dtype=float)
        self.intercept_ = np.asarray(model.intercept_, dtype=float)
        self.n_horizons_, self.output_dim_ = int(slow.shape[1]), int(slow.shape[2])
        self.n_features_in_ = int(phi.shape[1])
        return self

    def predict(self, phi: np.ndarray, slow: np.ndarray) -> np.ndarray:
        """(n, H+1, d_y) forecasts of rows φ (n, n_features) with slow forecasts (n, H+1, d_y)."""
        check_is_fitted(self, "coef_")
        phi, slow = np.asarray(phi, dtype=float), np.asarray(slow, dtype=float)
        if phi.ndim != 2 or phi.shape[1] != self.n_features_in_:
            raise ValueError(f"phi must be (n, {self.n_features_in_}), got {phi.shape}")
        return slow + (phi @ self.coef_.T + self.intercept_).reshape(slow.shape)

    def predict_one(self, phi: np.ndarray, slow: np.ndarray) -> np.ndarray:
        """(H+1, d_y) forecast of one step (the controller's call)."""
        return slow + (self.coef_ @ phi + self.intercept_).reshape(self.n_horizons_, self.output_dim_)

    def to_json(self) -> dict[str, Any]:
        """JSON-able parameters and fitted arrays (floats as exact JSON numbers)."""
        check_is_fitted(self, "coef_")
        skill = getattr(self, "preview_skill_", None)
        return {"alpha": float(self.alpha), "lags": [int(v) for v in self.lags],
                "coef": self.coef_.tolist(), "intercept": self.intercept_.tolist(),
                "n_horizons": self.n_horizons_, "output_dim": self.output_dim_,
                "channels": list(getattr(self, "channels_", ())),
                "preview_skill": None if skill is None else np.asarray(skill, dtype=float).tolist()}

    @classmethod
    def from_json(cls, d: dict[str, Any]) -> FastForecaster:
        """Inverse of :meth:`to_json`; raises ValueError for inconsistent shapes."""
        m = cls(alpha=float(d["alpha"]), lags=tuple(int(v) for v in d["lags"]))
        coef, b = np.asarray(d["coef"], dtype=float), np.asarray(d["intercept"], dtype=float)
        n_h, d_y = int(d["n_horizons"]), int(d["output_dim"])
        if coef.ndim != 2 or coef.shape[0] != n_h * d_y or b.shape != (n_h * d_y,):
            raise ValueError(f"fast forecaster: coef {coef.shape} / intercept {b.shape} do not fit "
                             f"{n_h} horizons x {d_y} outputs")
        if not (np.isfinite(coef).all() and np.isfinite(b).all()):
            raise ValueError("fast forecaster: non-finite coefficients")
        m.coef_, m.intercept_, m.n_horizons_, m.output_dim_ = coef, b, n_h, d_y
        m.n_features_in_ = int(coef.shape[1])
        m.channels_ = tuple(str(c) for c in d.get("channels", ()))
        if len(m.channels_) not in (0, d_y):
            raise ValueError(f"fast forecaster: {len(m.channels_)} channel names for {d_y} outputs")
        if d.get("preview_skill") is not None:
            skill = np.asarray(d["preview_skill"], dtype=float)
            if skill.ndim != 2 or skill.shape[1] != n_h:
                raise ValueError(f"fast forecaster: preview_skill {skill.shape} is not (n_modes, {n_h})")
            m.preview_skill_ = skill
        return m
