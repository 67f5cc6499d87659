"""The knife tip's future as a continuous trajectory: the predictor's forecast, or a known plan.

The reactive predictor forecasts the tip at the model ticks, ``p̂(t_j + h·Δ_m)`` for
h = 0 … H (Δ_m = 1/model_hz, :class:`learning.predictor.ReactivePredictor` with
``horizons = H``). :class:`ForecastTrack` turns the latest forecast into a trajectory
the 100 Hz loop samples anywhere in time:

* a cubic spline through the H + 1 points (natural ends, as scipy's ``CubicSpline(bc_type="natural")``,
  set up directly for the uniform knots: it is re-made every control step with the control-rate forecast); past the
  last point the spline's end velocity is extrapolated (constant velocity), before the
  first the first point is held; with H = 0 (no forecast) the point is held: the
  controller before forecasting;
* at each new tick the track cross-fades from the previous forecast to the new one over
  one model period (w = smoothstep((t − t_j)/Δ_m)): p = (1 − w)·p_old + w·p_new, with the
  matching velocity and acceleration, so the reference does not jump 10 times a second.

:class:`KnownTrajectory` has the same interface over a trajectory known in advance (the
wearer's true intent, for the ``oracle_preview`` upper bound; it is not realisable).
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from scipy.interpolate import CubicSpline

from mpcshare.errors import ControllerSetupError

__all__ = ["ForecastTrack", "KnownTrajectory", "TipTrajectory"]


class _Spline:
    """p, ṗ, p̈ of points (n, 3) at times (n,): a cubic spline inside, held before, constant velocity after."""

    def __init__(self, times: np.ndarray, points: np.ndarray) -> None:
        self.t0, self.t1 = float(times[0]), float(times[-1])
        self.first, self.last = points[0].copy(), points[-1].copy()
        self.curved = len(times) >= 2
        if self.curved:
            self.cs = CubicSpline(times, points, axis=0, bc_type="natural")
            self.end_velocity = np.asarray(self.cs(self.t1, 1))
        else:
            self.end_velocity = np.zeros(points.shape[1])

    def _inside(self, ti: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """p, ṗ, p̈ at times strictly between the first and the last knot."""
        return self.cs(ti), self.cs(ti, 1), self.cs(ti, 2)

    def __call__(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        t = np.asarray(t, dtype=float)
        n, d = t.shape[0], self.first.shape[0]
        p, v, a = np.empty((n, d)), np.zeros((n, d)), np.zeros((n, d))
        before, after = t <= self.t0, t >= self.t1
        inside = ~(before | after)
        p[before] = self.first
        if not self.curved:
            p[after] = self.last
            return p, v, a
        p[after] = self.last + (t[after] - self.t1)[:, None] * self.end_velocity
        v[after] = self.end_velocity
        if inside.any():
            p[inside], v[inside], a[inside] = self._inside(t[inside])
        return p, v, a


@lru_cache(maxsize=8)
def _natural_inverse(n: int) -> np.ndarray:
    """Inverse of the (n−2)×(n−2) tridiagonal [1, 4, 1] matrix of a natural spline on n uniform knots."""
    m = n - 2
    A = 4.0 * np.eye(m) + np.eye(m, k=1) + np.eye(m, k=-1)
    return np.linalg.inv(A)


class _UniformSpline(_Spline):
    """:class:`_Spline` on uniform knots t0 + k·h (the forecast's), without scipy's general set-up.

    Natural cubic spline: second derivatives M with M_0 = M_{n−1} = 0 and
    M_{k−1} + 4·M_k + M_{k+1} = 6·(y_{k−1} − 2·y_k + y_{k+1})/h² (the inverse is cached per n);
    on [t_k, t_{k+1}], a = t_{k+1} − t, u = t − t_k:
    S = (M_k·a³ + M_{k+1}·u³)/(6h) + (y_k/h − M_k·h/6)·a + (y_{k+1}/h − M_{k+1}·h/6)·u.
    Equal to scipy's ``CubicSpline(..., bc_type="natural")``.
    """

    def __init__(self, t0: float, h: float, points: np.ndarray) -> None:
        n = points.shape[0]
        self.t0, self.t1, self.h = float(t0), float(t0) + h * (n - 1), float(h)
        self.first, self.last = points[0].copy(), points[-1].copy()
        self.curved = n >= 2
        if not self.curved:
            self.end_velocity = np.zeros(points.shape[1])
            return
        M = np.zeros_like(points)
        if n > 2:
            M[1:-1] = _natural_inverse(n) @ ((points[:-2] - 2.0 * points[1:-1] + points[2:]) * (6.0 / (h * h)))
        self.M, self.y = M, points
        self.end_velocity = (points[-1] - points[-2]) / h + M[-2] * (h / 6.0) + M[-1] * (h / 3.0)

    def _inside(self, ti: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        h, M, y = self.h, self.M, self.y
        k = np.minimum(((ti - self.t0) / h).astype(int), M.shape[0] - 2)
        u = (ti - (self.t0 + k * h))[:, None]
        b = h - u
        c0, c1 = y[k] / h - M[k] * (h / 6.0), y[k + 1] / h - M[k + 1] * (h / 6.0)
        p = (M[k] * b ** 3 + M[k + 1] * u ** 3) / (6.0 * h) + c0 * b + c1 * u
        v = (M[k + 1] * u ** 2 - M[k] * b ** 2) / (2.0 * h) - c0 + c1
        return p, v, (M[k] * b + M[k + 1] * u) / h


class TipTrajectory:
    """Interface: ``ready``, ``sample(times) -> (p, ṗ, p̈)`` each (n, 3) [m, m/s, m/s²], plate frame."""

    ready: bool = False

    def sample(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        raise NotImplementedError

    def at(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(p, ṗ, p̈) each (3,) at one time t [s]."""
        p, v, a = self.sample(np.array([t]))
        return p[0], v[0], a[0]

    def reset(self) -> None:
        """Start a new episode (nothing to forget for a known trajectory)."""


class ForecastTrack(TipTrajectory):
    """The predictor's latest forecast as a trajectory, cross-faded between ticks (module docstring).

    Args:
        step_s: Δ_m, the time between the forecast's points [s] (1/model_hz).
        fade_s: cross-fade time from the previous forecast [s] (default Δ_m; 0: jump).
    """

    def __init__(self, step_s: float, fade_s: float | None = None) -> None:
        if not (math.isfinite(step_s) and step_s > 0):
            raise ControllerSetupError(f"step_s must be finite and > 0, got {step_s!r}")
        fade = step_s if fade_s is None else float(fade_s)
        if not (math.isfinite(fade) and fade >= 0):
            raise ControllerSetupError(f"fade_s must be finite and >= 0, got {fade_s!r}")
        self.step_s, self.fade_s = float(step_s), fade
        self.reset()

    def reset(self) -> None:
        """Forget every forecast (``ready`` is False until the next :meth:`update`)."""
        self._new: _Spline | None = None
        self._old: _Spline | None = None
        self._t_tick = -math.inf

    @property
    def ready(self) -> bool:  # type: ignore[override]
        return self._new is not None

    def update(self, t_tick: float, points: np.ndarray) -> None:
        """A new forecast made at ``t_tick`` [s]: ``points`` (H+1, 3), row h at t_tick + h·Δ_m.

        Non-finite points raise ValueError and leave the track unchanged.
        """
        pts = np.asarray(points, dtype=float)
        if pts.ndim != 2 or pts.shape[0] < 1:
            raise ValueError(f"forecast points must be (H+1, d), got shape {pts.shape}")
        if not np.isfinite(pts).all():
            raise ValueError("forecast points are not finite; track left unchanged")
        self._old = self._new
        self._new = _UniformSpline(float(t_tick), self.step_s, pts)
        self._t_tick = float(t_tick)

    def sample(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(p, ṗ, p̈) at ``times`` [s] (n,), each (n, d); NaN before the first forecast."""
        times = np.atleast_1d(np.asarray(times, dtype=float))
        if self._new is None:
            nan = np.full((times.shape[0], 3), np.nan)
            return nan, nan.copy(), nan.copy()
        p, v, a = self._new(times)
        if self._old is None or self.fade_s <= 0:
            return p, v, a
        s = np.clip((times - self._t_tick) / self.fade_s, 0.0, 1.0)
        if np.all(s >= 1.0):
            return p, v, a
        po, vo, ao = self._old(times)
        w = (s * s * (3.0 - 2.0 * s))[:, None]  # smoothstep: w' = 0 at both ends
        dw = np.where((s > 0) & (s < 1), 6.0 * s * (1.0 - s) / self.fade_s, 0.0)[:, None]
        ddw = np.where((s > 0) & (s < 1), (6.0 - 12.0 * s) / self.fade_s ** 2, 0.0)[:, None]
        dp, dv = p - po, v - vo
        return (po + w * dp, vo + w * dv + dw * dp, ao + w * (a - ao) + 2.0 * dw * dv + ddw * dp)


class KnownTrajectory(TipTrajectory):
    """A tip trajectory known in advance: positions (T, 3) [m] every ``step_s`` [s] from t = 0.

    For upper bounds only (``oracle_preview``: the wearer's true intent with perfect
    preview). Raises ValueError for a wrong shape or non-finite positions.
    """

    def __init__(self, positions: np.ndarray, step_s: float) -> None:
        p = np.asarray(positions, dtype=float)
        if p.ndim != 2 or p.shape[0] < 2 or p.shape[1] != 3:
            raise ValueError(f"positions must be (T >= 2, 3), got shape {p.shape}")
        if not np.isfinite(p).all():
            raise ValueError("positions are not finite")
        if not (math.isfinite(step_s) and step_s > 0):
            raise ValueError(f"step_s must be finite and > 0, got {step_s!r}")
        self._spline = _Spline(float(step_s) * np.arange(p.shape[0]), p)
        self.ready = True

    def sample(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self._spline(np.atleast_1d(np.asarray(times, dtype=float)))
