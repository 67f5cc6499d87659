"""Causal features of one control step, computed online from the arbiter's inputs (no future, no truth).

Per step t (control period dt, leaky means c̄_t = c̄_{t−1} + min(dt/τ, 1)·(x_t − c̄_{t−1}), τ = ``tau_s``):

* π_t (K): the filtered mode posterior (uniform when unknown);
* log d_t: d_t the time [s] since the posterior's most probable mode last changed;
* π_t·log d_t (K): the time in mode per mode (what a semi-Markov hazard is a function of);
* H(π_t) [nats]: the posterior's entropy; ν_t: the novelty, clipped to [−50, 50];
* log(c̄(‖û_v‖) + ε), log(c̄(‖û_r‖) + ε): the wearer's and the robot's tip speeds [m/s] (ε = 1 mm/s);
* c̄(max(0, −û_v·û_r/‖û_r‖)): the wearer's velocity against the robot's [m/s].
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

EPS = 1e-3  # [m/s]
TAU_S = 0.3


def feature_names(n_modes: int) -> list[str]:
    """The names of :meth:`OnlineFeatures.vector`'s entries, in order."""
    return ([f"p_mode_{k}" for k in range(n_modes)] + ["log_time_in_mode"]
            + [f"p_mode_{k}_x_log_time" for k in range(n_modes)]
            + ["entropy", "novelty", "log_wearer_speed", "log_robot_speed", "wearer_against_robot"])


class OnlineFeatures:
    """The module docstring's features, updated once per control step by :meth:`update`."""

    def __init__(self, n_modes: int, tau_s: float = TAU_S) -> None:
        if n_modes < 1 or not tau_s > 0:
            raise ValueError(f"OnlineFeatures needs n_modes >= 1 and tau_s > 0, got {n_modes} and {tau_s}")
        self.n_modes, self.tau_s = int(n_modes), float(tau_s)
        self.reset()

    def reset(self) -> None:
        """Forget the past (the next update starts every mean and the time in mode afresh)."""
        self._t = -math.inf
        self._mode = -1
        self._since = 0.0
        self._means = np.zeros(3)
        self._started = False
        self._last = np.zeros(len(feature_names(self.n_modes)))

    def update(self, t: float, inputs: Any) -> np.ndarray:
        """Take step ``t`` [s] (``inputs``: a ``StepInputs``) and return the feature vector."""
        K = self.n_modes
        p = inputs.mode_proba
        known = p is not None and len(p) == K and bool(np.all(np.isfinite(p)))
        pi = np.asarray(p, dtype=float) if known else np.full(K, 1 / K)
        dt = min(max(t - self._t, 0.0), 0.1) if math.isfinite(self._t) else 0.0
        self._t = float(t)
        mode = int(np.argmax(pi))
        if mode != self._mode:
            self._mode, self._since = mode, float(t)
        u_v = np.zeros(3) if inputs.u_v is None else np.nan_to_num(np.asarray(inputs.u_v, dtype=float))
        u_r = np.zeros(3) if inputs.u_r is None else np.nan_to_num(np.asarray(inputs.u_r, dtype=float))
        sr = float(np.linalg.norm(u_r))
        x = np.array([float(np.linalg.norm(u_v)), sr, max(0.0, -float(u_v @ u_r) / max(sr, 1e-3))])
        if not self._started:
            self._means, self._started = x, True
        else:
            self._means = self._means + min(dt / self.tau_s, 1.0) * (x - self._means)
        log_d = math.log(max(float(t) - self._since, 0.0) + 0.01)
        with np.errstate(divide="ignore", invalid="ignore"):
            ent = float(-np.sum(np.where(pi > 0, pi * np.log(pi), 0.0)))
        nov = float(np.clip(np.nan_to_num(inputs.novelty, nan=50.0), -50.0, 50.0))
        self._last = np.concatenate([pi, [log_d], pi * log_d,
                                     [ent, nov, math.log(self._means[0] + EPS), math.log(self._means[1] + EPS),
                                      self._means[2]]])
        return self._last
