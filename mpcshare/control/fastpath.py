"""The control-rate forecast in the loop (:mod:`learning.predictor.fast`, trained by ``mpcshare train``).

Every control step, on the front end's Kalman state of the fork (no anti-aliasing filter, no
10 Hz hold in front of it), the mode posterior and the LSTM forecast of the last model tick
(interpolated to the step's time), :class:`FastPath` gives the knife tip's forecast over the
horizon, ``F[h]`` at ``t + h·Δ_m`` (plate frame, m). Its inputs equal what
:func:`mpcshare.training.fast.fast_rows` builds offline, step by step.

:meth:`FastPath.preview_until` says how far the forecast may be used for the MPC's preview: up to
the last horizon, counted from the first, whose skill against the hold (validation trials, the
current mode) is above 0; past it the preview holds.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

import numpy as np

from learning.preprocessing.resample import decimation_factor
from mpcshare.control.frontend import kalman_inputs

if TYPE_CHECKING:  # annotations only
    from mpcshare.bundle import ModelBundle
    from mpcshare.control.bundle_inputs import BundleLayout

__all__ = ["FastPath"]


class FastPath:
    """The bundle's fast forecaster, its streaming inputs and its preview limit (module docstring).

    Raises ValueError at construction when the forecaster does not fit the bundle (horizons,
    channels, feature count).
    """

    def __init__(self, bundle: ModelBundle, layout: BundleLayout) -> None:
        # here, not at the top: importing learning.predictor pulls in torch, which the controller's
        # module must not need (a bundle with a fast forecaster has loaded it already)
        from learning.predictor.fast import VELOCITY_SCALE_S, FastInputStream, interpolate_slow

        self._interpolate, self._tau_v = interpolate_slow, VELOCITY_SCALE_S
        fast = bundle.fast
        H1 = int(getattr(bundle.predictor, "horizons", 0)) + 1
        lags = tuple(int(v) for v in fast.lags)
        n_feat = layout.n_modes * (1 + layout.d_o * (2 + len(lags))) + H1 * 3
        if fast.n_horizons_ != H1 or fast.output_dim_ != 3 or fast.n_features_in_ != n_feat:
            raise ValueError(f"the bundle's fast forecaster ({fast.n_horizons_} horizons x {fast.output_dim_} "
                             f"outputs, {fast.n_features_in_} features) does not fit its predictor ({H1} horizons) "
                             f"and channels (3 tip outputs, {n_feat} features); retrain the bundle")
        tip_names = tuple(bundle.act_names[i] for i in layout.tip_index)
        if fast.channels_ and tuple(fast.channels_) != tip_names:
            raise ValueError(f"the bundle's fast forecaster forecasts {list(fast.channels_)}, the controller "
                             f"tracks {list(tip_names)}")
        self.model = fast
        self.factor = decimation_factor(bundle.rate_hz, bundle.model_hz)
        self.step_s = 1.0 / float(bundle.model_hz)
        self._obs_mean = np.asarray(bundle.preprocessor.obs.mean_, dtype=float)
        self._obs_scale = np.asarray(bundle.preprocessor.obs.scale_, dtype=float)
        self._tip = layout.tip_index
        self._mean, self._scale = layout.act_mean[self._tip], layout.act_scale[self._tip]
        self.skill = getattr(fast, "preview_skill_", None)
        self.inputs = FastInputStream(lags)
        self.reset()

    def reset(self) -> None:
        """Start a new episode."""
        self.inputs.reset()
        self._slow: np.ndarray | None = None
        self._since_tick = 0

    def on_tick(self, forecast_std: np.ndarray | None) -> None:
        """A model tick: the LSTM's forecast (H+1, d_u) standardised, or None (it failed: the last is kept)."""
        self._since_tick = 0
        if forecast_std is not None:
            self._slow = np.asarray(forecast_std, dtype=float)[:, self._tip]

    def step(self, fork_position: np.ndarray, fork_velocity: np.ndarray, mode_proba: np.ndarray,
             ticked: bool) -> np.ndarray | None:
        """The tip forecast (H+1, 3) [m] at this step (None before the first tick's forecast).

        ``ticked``: this step was a model tick (:meth:`on_tick` called before).
        """
        if not ticked:
            self._since_tick += 1
        P, V = kalman_inputs(fork_position, fork_velocity, self._obs_mean, self._obs_scale, self._tau_v)
        if self._slow is None:
            self.inputs.step(P, V, mode_proba, np.zeros((self.model.n_horizons_, 3)))  # keep the lag history
            return None
        slow = self._interpolate(self._slow[None], np.array([self._since_tick / self.factor]))[0]
        phi = self.inputs.step(P, V, mode_proba, slow)
        return self.model.predict_one(phi, slow) * self._scale + self._mean

    def preview_until(self, t: float, mode_proba: np.ndarray) -> float:
        """The latest time [s] the preview may read the forecast at (``inf`` without a skill table)."""
        if self.skill is None:
            return math.inf
        s = self.skill[int(np.argmax(mode_proba)) % self.skill.shape[0]]
        h_ok = 0
        while h_ok + 1 < s.size and s[h_ok + 1] > 0:
            h_ok += 1
        return float(t) + h_ok * self.step_s
