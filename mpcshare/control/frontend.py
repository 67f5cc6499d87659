"""Streaming front end of the controller: fork signal at 100 Hz → model inputs at 10 Hz.

Per control step (one raw fork sample, ``rate_hz``):

1. :class:`ForkKalman` — a constant-velocity Kalman filter per channel (equal to filterpy's), state
   ``[x_j, ẋ_j]``: x⁺ = x + ẋ·Δt, ẋ⁺ = ẋ + w·Δt (white acceleration w); it predicts through missing (NaN)
   channels and stale samples (bit-for-bit equal to the previous one: a frozen sensor) and says for how
   long (``predicting_for_s``);
2. the sample that goes on is the **raw** one when present (online and offline features identical), the
   Kalman prediction where it is missing or stale;
3. :class:`learning.preprocessing.resample.StreamingDecimator` (anti-aliasing low-pass, every f-th sample;
   equal to ``causal_downsample``), the bundle's obs standardiser, the causal window of ``window_s``
   RMS-normalised as ``causal_windows(..., rms=True)``: ``w_t = [o_t, o_{t−1}, …, o_{t−L+1}] / √L``;
4. :class:`learning.modes.ModeFilter` stepped on every model-rate sample; novelty = −log p(o_t | o_<t)
   (``inf`` when the sample is impossible under every mode).

The Kalman state (``FrontEndOutput.fork_position``, ``fork_velocity``) is the control-rate forecast's
input (:mod:`mpcshare.control.fastpath`); :func:`kalman_batch` runs the same filter over a recorded trial.
Streamed sample by sample, a trial gives the offline windows, posteriors and novelty to 1e-9.
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

import numpy as np

from learning.preprocessing.preprocess import window_lags
from learning.preprocessing.resample import StreamingDecimator
from mpcshare.errors import ControllerSetupError

__all__ = ["ForkKalman", "ModelTick", "StreamingFrontEnd", "fork_kalman", "kalman_batch", "kalman_inputs"]

#: the front end's Kalman noise levels per unit of the obs standardiser's scale s_j:
#: white acceleration 5·s_j per s², measurement 0.02·s_j
KALMAN_ACCEL_PER_SCALE, KALMAN_MEAS_PER_SCALE = 5.0, 0.02


class ForkKalman:
    """Constant-velocity Kalman filter over ``d`` independent channels.

    Per channel j the state is ``[x_j, ẋ_j]``, F = [[1, Δt], [0, 1]], H = [1, 0];
    process noise: white acceleration of standard deviation ``accel_std[j]`` [unit/s²]
    (Q as filterpy's ``Q_discrete_white_noise(2, Δt, σ²)``); measurement noise ``meas_std[j]``
    [unit]. A NaN channel is left out of that step's update.

    The channels are independent (block-diagonal F, Q, R), so the filter is d 2-state filters,
    vectorised over channels; the update is filterpy's (Joseph form), equal to filterpy's
    ``KalmanFilter`` per channel to 1e-12.
    """

    def __init__(self, n_channels: int, dt: float, accel_std: np.ndarray, meas_std: np.ndarray) -> None:
        d = int(n_channels)
        accel_std = np.broadcast_to(np.asarray(accel_std, dtype=float), (d,))
        meas_std = np.broadcast_to(np.asarray(meas_std, dtype=float), (d,))
        if not (np.all(np.isfinite(accel_std)) and np.all(accel_std > 0)):
            raise ControllerSetupError("ForkKalman: accel_std must be finite and > 0 per channel")
        if not (np.all(np.isfinite(meas_std)) and np.all(meas_std > 0)):
            raise ControllerSetupError("ForkKalman: meas_std must be finite and > 0 per channel")
        if not (math.isfinite(dt) and dt > 0):
            raise ControllerSetupError(f"ForkKalman: dt must be > 0, got {dt!r}")
        self.n_channels, self.dt = d, float(dt)
        self.accel_var = accel_std ** 2
        self.meas_var = meas_std ** 2
        self.reset()

    def reset(self) -> None:
        """Forget the past: the next measurement initialises the state (zero velocity)."""
        self.initialized = False
        self.last_update_t = float("nan")

    def initial_covariance(self) -> tuple[np.ndarray, np.ndarray]:
        """(P_xx, P_ẋẋ) at the first measurement: σ_m² and 100·σ_m²/Δt² (velocity unknown)."""
        return self.meas_var.copy(), self.meas_var * (100.0 / self.dt ** 2)

    def step(self, t: float, z: np.ndarray | None) -> np.ndarray:
        """Predict to time ``t`` [s], then update with the finite entries of ``z`` (None: none).

        Returns the predicted position (d,) *before* the update (what substitutes a
        missing channel). Before the first complete measurement it returns NaNs.
        """
        d = self.n_channels
        if not self.initialized:
            if z is None or not np.all(np.isfinite(z)):
                return np.full(d, np.nan)
            self.x, self.v = np.array(z, dtype=float), np.zeros(d)
            self.p00, self.p11 = self.initial_covariance()
            self.p01 = np.zeros(d)
            self.initialized, self.t = True, float(t)
            self.last_update_t = float(t)
            return self.x.copy()
        dt = min(max(float(t) - self.t, 0.0), 1.0)
        if dt > 0:  # x⁺ = F x;  P⁺ = F P Fᵀ + Q
            # Q / σ² = [[Δt⁴/4, Δt³/2], [Δt³/2, Δt²]] (filterpy's Q_discrete_white_noise(2, Δt, 1))
            dt2 = dt * dt
            self.x = self.x + dt * self.v
            self.p00 = self.p00 + dt * (2.0 * self.p01 + dt * self.p11) + (0.25 * dt2 * dt2) * self.accel_var
            self.p01 = self.p01 + dt * self.p11 + (0.5 * dt2 * dt) * self.accel_var
            self.p11 = self.p11 + dt2 * self.accel_var
        self.t = float(t)
        prior = self.x.copy()
        if z is None:
            return prior
        ok = np.isfinite(z)
        if not ok.any():
            return prior
        if ok.all():
            ok = True  # np.where with a scalar condition: same values, less work
        # K = P Hᵀ / S, S = P_xx + r;  P⁺ = (I − K H) P (I − K H)ᵀ + K r Kᵀ  (filterpy's Joseph form)
        r = self.meas_var
        s = self.p00 + r
        k0, k1 = self.p00 / s, self.p01 / s
        y = np.where(ok, z, prior) - self.x
        a = 1.0 - k0
        n00 = a * self.p00 * a + k0 * r * k0
        n01 = a * (self.p01 - self.p00 * k1) + k0 * r * k1
        n11 = k1 * (self.p00 * k1 - self.p01) - k1 * self.p01 + self.p11 + k1 * r * k1
        self.x = np.where(ok, self.x + k0 * y, self.x)
        self.v = np.where(ok, self.v + k1 * y, self.v)
        self.p00, self.p01, self.p11 = (np.where(ok, n00, self.p00), np.where(ok, n01, self.p01),
                                        np.where(ok, n11, self.p11))
        self.last_update_t = float(t)
        return prior

    @property
    def position(self) -> np.ndarray:
        """(d,) filtered position; NaN before the first measurement."""
        return self.x.copy() if self.initialized else np.full(self.n_channels, np.nan)

    @property
    def velocity(self) -> np.ndarray:
        """(d,) filtered velocity [unit/s]; NaN before the first measurement."""
        return self.v.copy() if self.initialized else np.full(self.n_channels, np.nan)

    def predicting_for(self, t: float) -> float:
        """Seconds since the last update with at least one measured channel (inf before any)."""
        return float(t) - self.last_update_t if self.initialized else float("inf")


def fork_kalman(scale: np.ndarray, rate_hz: float) -> ForkKalman:
    """The front end's Kalman filter for channels of standardiser scale ``scale`` (d,) at ``rate_hz``."""
    scale = np.asarray(scale, dtype=float)
    return ForkKalman(scale.size, 1.0 / float(rate_hz), KALMAN_ACCEL_PER_SCALE * scale,
                      KALMAN_MEAS_PER_SCALE * scale)


def kalman_batch(kf: ForkKalman, Z: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:meth:`ForkKalman.step` over a whole record Z (T, d) sampled every ``kf.dt``: (positions, velocities).

    For offline use on recorded trials: every sample measured (a NaN row, e.g. padding after
    a trial's end, turns the rest of that channel into NaN). The same arithmetic as ``step``
    (its covariance recursion gives the gains; once they reach a fixed point they are reused),
    so the result equals stepping the filter.
    """
    Z = np.asarray(Z, dtype=float)
    T, dt, r, q = Z.shape[0], kf.dt, kf.meas_var, kf.accel_var
    X, V = np.empty_like(Z), np.empty_like(Z)
    x, v = Z[0].copy(), np.zeros(Z.shape[1])
    p00, p11 = kf.initial_covariance()
    p01 = np.zeros_like(p00)
    X[0], V[0] = x, v
    k0 = k1 = None
    fixed = False
    dt2 = dt * dt
    for i in range(1, T):
        if not fixed:
            p00 = p00 + dt * (2.0 * p01 + dt * p11) + (0.25 * dt2 * dt2) * q
            p01 = p01 + dt * p11 + (0.5 * dt2 * dt) * q
            p11 = p11 + dt2 * q
            s = p00 + r
            n0, n1 = p00 / s, p01 / s
            fixed = k0 is not None and bool(np.array_equal(n0, k0) and np.array_equal(n1, k1))
            k0, k1 = n0, n1
            a = 1.0 - k0
            p00, p01, p11 = (a * p00 * a + k0 * r * k0, a * (p01 - p00 * k1) + k0 * r * k1,
                             k1 * (p00 * k1 - p01) - k1 * p01 + p11 + k1 * r * k1)
        x = x + dt * v
        y = Z[i] - x
        x = x + k0 * y
        v = v + k1 * y
        X[i], V[i] = x, v
    return X, V


def kalman_inputs(x: np.ndarray, v: np.ndarray, mean: np.ndarray, scale: np.ndarray,
                  tau_v: float) -> tuple[np.ndarray, np.ndarray]:
    """The fast forecast's inputs from the Kalman state: ((x − μ)/s, ẋ·τ_v/s), τ_v [s] =
    ``learning.predictor.fast.VELOCITY_SCALE_S`` (position and velocity on one unit scale)."""
    return (x - mean) / scale, v * (tau_v / scale)


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
    fork_velocity: (d_o,) KF velocity [unit/s]; fork_position: (d_o,) KF position; predicting_for_s: time since the last
    measurement [s]; missing: (d_o,) bool, channels substituted this step; stale: the whole
    sample repeated the previous one; tick: the model-rate outputs, or None between ticks.
    """

    feature_sample: np.ndarray
    fork_velocity: np.ndarray
    predicting_for_s: float
    missing: np.ndarray
    stale: bool
    tick: ModelTick | None
    fork_position: np.ndarray | None = None


class StreamingFrontEnd:
    """Kalman filter → anti-aliased decimation → standardise → causal window → mode filter.

    Args:
        obs_standardizer: fitted ``learning.preprocessing.preprocess.Standardizer`` of the obs (``transform``).
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
            raise ControllerSetupError(f"the mode model expects {modes.n_features_in_} features, "
                                       f"the obs standardiser has {d} channels")
        self.standardizer = obs_standardizer
        self.modes = modes
        self.rate_hz, self.model_hz, self.window_s = float(rate_hz), float(model_hz), float(window_s)
        self.decimator = StreamingDecimator(self.rate_hz, self.model_hz, d)
        self.lags = window_lags(self.window_s, self.model_hz)
        self._sqrt_l = math.sqrt(self.lags)
        self.kalman = fork_kalman(scale, self.rate_hz) if accel_std is None and meas_std is None else \
            ForkKalman(d, 1.0 / self.rate_hz, KALMAN_ACCEL_PER_SCALE * scale if accel_std is None else accel_std,
                       KALMAN_MEAS_PER_SCALE * scale if meas_std is None else meas_std)
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
                     and math.isfinite(z.sum()) and bool((z == self._last_raw).all()))
        if z is not None:
            self._last_raw = z.copy()
        prior = self.kalman.step(t, None if stale else z)
        if z is None or stale:
            missing = np.ones(d, dtype=bool)
        else:
            missing = ~np.isfinite(z)
        feat = prior if (z is None or stale) else np.where(missing, prior, z)
        if not math.isfinite(feat.sum()):
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
        return FrontEndOutput(feat, self.kalman.velocity, self.kalman.predicting_for(t), missing, stale, tick,
                              self.kalman.position)
