"""Streaming front end of the controller: fork signal at 100 Hz → model inputs at 10 Hz.

Per control step (one raw sample of the fork, ``rate_hz``):

1. :class:`ForkKalman` — a constant-velocity Kalman filter (filterpy) per channel,
   state ``[x_j, ẋ_j]``: x⁺ = x + ẋ·Δt, ẋ⁺ = ẋ + w·Δt (white acceleration w).
   It predicts through missing (NaN) channels and stale samples (a sample bit-for-bit
   equal to the previous one: a frozen sensor) and says for how long it has been
   predicting (``predicting_for_s``); its velocity state is the fork velocity.
2. The sample that goes on into the features is the **raw** sample when present
   (so online and offline features are identical), the KF prediction where it is
   missing or stale.
3. :class:`learning.resample.StreamingDecimator` (anti-aliasing low-pass, keep every
   f-th sample; equal to ``causal_downsample`` offline), then the bundle's obs
   standardiser, then the causal window of ``window_s`` RMS-normalised as
   ``learning.preprocess.causal_windows(..., rms=True)`` builds it:
   ``w_t = [o_t, o_{t−1}, …, o_{t−L+1}] / √L``.
4. The :class:`learning.modes_online.ModeFilter` stepped on every standardised
   model-rate sample; novelty = −log p(o_t | o_<t) (``inf`` when the sample is
   impossible under every mode).

A recorded trial streamed sample by sample gives the offline windows,
posteriors and novelty scores (tests/mpcshare/test_streaming.py, 1e-9).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np
from filterpy.common import Q_discrete_white_noise
from filterpy.kalman import KalmanFilter
from scipy.linalg import block_diag

from learning.preprocess import window_lags
from learning.resample import StreamingDecimator

__all__ = ["ForkKalman", "ModelTick", "StreamingFrontEnd"]


class ForkKalman:
    """Constant-velocity Kalman filter over ``d`` channels (filterpy ``KalmanFilter``).

    State (2d,): ``[x_0, ẋ_0, x_1, ẋ_1, …]``. Process noise: white acceleration of
    standard deviation ``accel_std[j]`` [unit/s²] (filterpy ``Q_discrete_white_noise``);
    measurement noise ``meas_std[j]`` [unit]. A channel that is NaN is left out of the
    update (its row of H is zero for that step, which leaves the gain column zero: an
    exact partial update).
    """

    def __init__(self, n_channels: int, dt: float, accel_std: np.ndarray, meas_std: np.ndarray) -> None:
        d = int(n_channels)
        accel_std = np.broadcast_to(np.asarray(accel_std, dtype=float), (d,))
        meas_std = np.broadcast_to(np.asarray(meas_std, dtype=float), (d,))
        if not (np.all(np.isfinite(accel_std)) and np.all(accel_std > 0)):
            raise ValueError("ForkKalman: accel_std must be finite and > 0 per channel")
        if not (np.all(np.isfinite(meas_std)) and np.all(meas_std > 0)):
            raise ValueError("ForkKalman: meas_std must be finite and > 0 per channel")
        if not (math.isfinite(dt) and dt > 0):
            raise ValueError(f"ForkKalman: dt must be > 0, got {dt!r}")
        self.n_channels, self.dt = d, float(dt)
        self._accel_var = accel_std ** 2
        self._H = np.zeros((d, 2 * d))
        self._H[np.arange(d), 2 * np.arange(d)] = 1.0
        self._R = np.diag(meas_std ** 2)
        self._Q_cache: dict[float, tuple[np.ndarray, np.ndarray]] = {}
        self.kf = KalmanFilter(dim_x=2 * d, dim_z=d)
        self.kf.H = self._H.copy()
        self.kf.R = self._R.copy()
        self._meas_var = meas_std ** 2
        self.reset()

    def reset(self) -> None:
        """Forget the past: the next measurement initialises the state (zero velocity)."""
        self.initialized = False
        self.last_update_t = float("nan")

    def _transition(self, dt: float) -> tuple[np.ndarray, np.ndarray]:
        key = round(dt, 9)
        if key not in self._Q_cache:
            if len(self._Q_cache) > 64:
                self._Q_cache.clear()
            F1 = np.array([[1.0, dt], [0.0, 1.0]])
            F = block_diag(*([F1] * self.n_channels))
            Q = block_diag(*[Q_discrete_white_noise(2, dt=dt, var=v) for v in self._accel_var])
            self._Q_cache[key] = (F, Q)
        return self._Q_cache[key]

    def step(self, t: float, z: np.ndarray | None) -> np.ndarray:
        """Predict to time ``t`` [s], then update with the finite entries of ``z`` (None: none).

        Returns the predicted position (d,) *before* the update (what substitutes a
        missing channel). Before the first measurement it returns NaNs.
        """
        d = self.n_channels
        if not self.initialized:
            if z is None or not np.all(np.isfinite(z)):
                return np.full(d, np.nan)
            x0 = np.zeros(2 * d)
            x0[0::2] = z
            self.kf.x = x0
            self.kf.P = np.diag(np.repeat(self._meas_var, 2) * np.tile([1.0, 100.0 / self.dt ** 2], d))
            self.initialized, self.t = True, float(t)
            self.last_update_t = float(t)
            return np.array(z, dtype=float)
        dt = min(max(float(t) - self.t, 0.0), 1.0)
        if dt > 0:
            F, Q = self._transition(dt)
            self.kf.predict(F=F, Q=Q)
        self.t = float(t)
        prior = self.kf.x[0::2].copy()
        if z is not None:
            ok = np.isfinite(z)
            if ok.all():
                self.kf.update(z)
                self.last_update_t = float(t)
            elif ok.any():
                H = self._H.copy()
                H[~ok] = 0.0
                self.kf.update(np.where(ok, z, 0.0), H=H)
                self.last_update_t = float(t)
        return prior

    @property
    def position(self) -> np.ndarray:
        """(d,) filtered position."""
        return self.kf.x[0::2].copy()

    @property
    def velocity(self) -> np.ndarray:
        """(d,) filtered velocity [unit/s]; NaN before the first measurement."""
        if not self.initialized:
            return np.full(self.n_channels, np.nan)
        return self.kf.x[1::2].copy()

    def predicting_for(self, t: float) -> float:
        """Seconds since the last update with at least one measured channel (inf before any)."""
        return float(t) - self.last_update_t if self.initialized else float("inf")


@dataclass
class ModelTick:
    """What the front end produces on a model-rate (10 Hz) tick.

    sample: (d_o,) standardised obs o_t; window: (L·d_o,) RMS-normalised causal window or
    None while fewer than L samples were seen; mode_proba: (K,) causal posterior;
    novelty: −log p(o_t | o_<t) (inf: impossible under every mode).
    """

    sample: np.ndarray
    window: np.ndarray | None
    mode_proba: np.ndarray
    novelty: float


@dataclass
class FrontEndOutput:
    """One raw-rate step of the front end.

    feature_sample: (d_o,) what went into the decimator (raw where measured, KF where not);
    fork_velocity: (d_o,) KF velocity [unit/s]; predicting_for_s: time since the last
    measurement [s]; missing: (d_o,) bool, channels substituted this step; stale: the whole
    sample repeated the previous one; tick: the model-rate outputs, or None between ticks.
    """

    feature_sample: np.ndarray
    fork_velocity: np.ndarray
    predicting_for_s: float
    missing: np.ndarray
    stale: bool
    tick: ModelTick | None


class StreamingFrontEnd:
    """Kalman filter → anti-aliased decimation → standardise → causal window → mode filter.

    Args:
        obs_standardizer: fitted ``learning.preprocess.Standardizer`` of the obs (``transform``).
        modes: fitted ``learning.modes.TaskModes`` (on standardised model-rate samples).
        rate_hz: raw rate [Hz]; model_hz: model rate [Hz]; window_s: window [s].
        accel_std, meas_std: Kalman noise levels per channel [unit/s²], [unit]; default from
            the standardiser's scale s_j: 5·s_j per s² and 0.02·s_j.
        detect_stale: treat a sample bit-for-bit equal to the previous one as stale.
    """

    def __init__(self, obs_standardizer, modes, *, rate_hz: float = 100.0, model_hz: float = 10.0,
                 window_s: float = 1.0, accel_std: np.ndarray | None = None,
                 meas_std: np.ndarray | None = None, detect_stale: bool = True) -> None:
        scale = np.asarray(obs_standardizer.scale_, dtype=float)
        self.n_channels = d = scale.size
        if int(getattr(modes, "n_features_in_", d)) != d:
            raise ValueError(f"the mode model expects {modes.n_features_in_} features, "
                             f"the obs standardiser has {d} channels")
        self.standardizer = obs_standardizer
        self.modes = modes
        self.rate_hz, self.model_hz, self.window_s = float(rate_hz), float(model_hz), float(window_s)
        self.decimator = StreamingDecimator(self.rate_hz, self.model_hz, d)
        self.lags = window_lags(self.window_s, self.model_hz)
        self._sqrt_l = math.sqrt(self.lags)
        self.kalman = ForkKalman(d, 1.0 / self.rate_hz, 5.0 * scale if accel_std is None else accel_std,
                                 0.02 * scale if meas_std is None else meas_std)
        self.detect_stale = bool(detect_stale)
        self._mean = np.asarray(obs_standardizer.mean_, dtype=float)
        self._scale = scale
        self.mode_filter = modes.make_filter()
        self.reset()

    def reset(self) -> None:
        """Start a new trial."""
        self.kalman.reset()
        self.decimator.reset()
        self.mode_filter.reset()
        self._history: deque[np.ndarray] = deque(maxlen=self.lags)
        self._last_raw: np.ndarray | None = None
        self.last_tick: ModelTick | None = None

    def step(self, t: float, obs: np.ndarray | None) -> FrontEndOutput:
        """Absorb one raw sample (None or NaN entries: missing) at time ``t`` [s].

        Raises ValueError only when nothing has ever been measured (no feature can be
        formed); the controller reports that as a fault.
        """
        d = self.n_channels
        z = None if obs is None else np.asarray(obs, dtype=float)
        stale = bool(self.detect_stale and z is not None and self._last_raw is not None
                     and np.array_equal(z, self._last_raw) and np.all(np.isfinite(z)))
        if z is not None:
            self._last_raw = z.copy()
        prior = self.kalman.step(t, None if stale else z)
        if z is None or stale:
            missing = np.ones(d, dtype=bool)
        else:
            missing = ~np.isfinite(z)
        feat = prior if (z is None or stale) else np.where(missing, prior, z)
        if not np.all(np.isfinite(feat)):
            raise ValueError("no fork measurement yet: the front end cannot form a feature")
        tick = None
        y = self.decimator.push(feat)
        if y is not None:
            std = (y - self._mean) / self._scale
            self._history.appendleft(std)
            window = (np.concatenate(self._history) / self._sqrt_l
                      if len(self._history) == self.lags else None)
            try:
                proba = self.mode_filter.step(std)
                novelty = -self.mode_filter.log_predictive
            except ValueError:  # impossible under every mode: keep the posterior, flag it
                proba = self.mode_filter.filtered
                novelty = float("inf")
            tick = ModelTick(std, window, np.array(proba, dtype=float), float(novelty))
            self.last_tick = tick
        return FrontEndOutput(feat, self.kalman.velocity, self.kalman.predicting_for(t), missing, stale, tick)
