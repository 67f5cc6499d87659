"""Authority that moves continuously: minimum-variance fusion of the two parties from their predicted errors.

Two estimates of the intent with independent errors of variances σ_r² (the robot) and σ_w² (the wearer)
fuse with least variance at α = σ_w² / (σ_r² + σ_w²), the command û = α·û_r + (1 − α)·û_v. Per step:

    σ_w² = π·w                                   w_j: the wearer alone's mean squared tip error in mode j
    log σ_r² = π·r + g·log(c̄ + ε) + s²/2         c̄: the wearer's corrective tip speed ‖û_v‖, leaky mean (τ)

(π: the mode posterior; r, g, s² a least-squares fit of log of the robot alone's mean squared error over the
next 0.5 s, s² its residual variance, so that exp(·) is the mean of a log-normal). c̄ is the wearer's
correction only while the robot leads (α ≥ 0.5: the simulated wearer corrects); while the wearer leads it
drives, and c̄ relaxes toward the mode's mean c_π = exp(π·log c) over ``relax_s``. α moves along the
controller's hand-over ramp (at most 1/``handover_s`` per second): the wearer never inherits a step offset.

With ``split`` (the ``fusion_lead`` variant), the wearer leads alone where the fusion would give the robot
less than half (α* < 0.5 − ``band``), and the robot leads at share α* ≥ 0.5 where α* > 0.5 + ``band``
(hysteresis in between): the simulated wearer drives their own plan below 0.5 whatever the robot's share,
so a share below 0.5 adds the robot's error without saving the wearer's effort.

:func:`fit_fusion` fits (r, g, s², w, log c) on recorded runs of the two parties alone (:mod:`.record`);
:func:`fusion_controller` is a controller factory for :func:`mpcshare.evaluation.episode.simulate_episode`
that puts :class:`FusionPolicy` in the arbiter of a ``SharedController`` (a research candidate, not in the
registry).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from research.coming_error.signals import future_mean

EPS = 1e-3  # [m/s] added to the correction speed before its log
TAU_S = 0.3  # the correction's leaky mean [s]
RELAX_S = 1.0  # while the wearer leads, c̄ relaxes toward the mode's mean [s]
HORIZON_S = 0.5


def leaky(x: np.ndarray, dt: float, tau: float) -> np.ndarray:
    """c̄_t = c̄_{t−1} + (dt/τ)(x_t − c̄_{t−1}), c̄_0 = x_0 (causal)."""
    out = np.empty(x.size)
    c = float(x[0])
    k = min(dt / tau, 1.0)
    for i, v in enumerate(x):
        c += k * (float(v) - c)
        out[i] = c
    return out


def fit_fusion(folder: Path, trials: list[int]) -> dict[str, Any]:
    """(r, g, s², w, log c) (module docstring) fitted on the recorded runs of ``trials`` in ``folder``."""
    K = None
    rows, ys, wear = [], [], []
    for tid in trials:
        with np.load(folder / f"reactive_{tid}.npz") as r, np.load(folder / f"voluntary_{tid}.npz") as w:
            dt = float(np.median(np.diff(r["t"])))
            n = round(HORIZON_S / dt)
            K = r["mode_proba"].shape[1]
            cbar = leaky(np.linalg.norm(r["u_v"], axis=1), dt, TAU_S)
            e_r = future_mean(np.sum((r["tip"] - r["intent"]) ** 2, axis=1), n)
            keep = np.isfinite(e_r) & (r["t"] - r["t"][0] >= 2.0)
            rows.append(np.column_stack([r["mode_proba"], np.log(cbar + EPS)])[keep])
            ys.append(np.log(e_r[keep] + 1e-10))
            e_w = future_mean(np.sum((w["tip"] - w["intent"]) ** 2, axis=1), n)
            kw = np.isfinite(e_w) & (w["t"] - w["t"][0] >= 2.0)
            wear.append((w["mode_proba"][kw], e_w[kw]))
    X, y = np.concatenate(rows), np.concatenate(ys)
    coef, *_ = np.linalg.lstsq(X, y, rcond=None)
    s2 = float(np.var(y - X @ coef))
    P = np.concatenate([p for p, _ in wear])
    E = np.concatenate([e for _, e in wear])
    w_j = (P * E[:, None]).sum(axis=0) / np.maximum(P.sum(axis=0), 1e-9)  # posterior-weighted mean per mode
    logc = (X[:, :K] * X[:, K:K + 1]).sum(axis=0) / np.maximum(X[:, :K].sum(axis=0), 1e-9)
    return {"robot_log_var": coef[:K].tolist(), "correction_gain": float(coef[K]), "log_resid_var": s2,
            "wearer_var": w_j.tolist(), "log_correction_prior": logc.tolist(), "trials": list(trials)}


class FusionPolicy:
    """α = σ_w² / (σ_r² + σ_w²) per step (module docstring); the arbiter's safety overrides apply."""

    overrides = True

    def __init__(self, params: dict[str, Any], split: bool = False, band: float = 0.05) -> None:
        self.split, self.band = bool(split), float(band)
        self.r = np.asarray(params["robot_log_var"], dtype=float)
        self.g = float(params["correction_gain"])
        self.s2 = float(params["log_resid_var"])
        self.w = np.asarray(params["wearer_var"], dtype=float)
        self.logc = np.asarray(params["log_correction_prior"], dtype=float)
        if not (self.r.shape == self.w.shape == self.logc.shape) or np.any(self.w <= 0):
            raise ValueError(f"fusion parameters need one robot log-variance, one wearer variance > 0 and one "
                             f"correction prior per mode; got {self.r.shape}, {self.w.tolist()}, {self.logc.shape}")
        self.reset()

    def reset(self) -> None:
        """Forget the correction's mean."""
        self._c: float | None = None
        self._t = -math.inf

    def decide(self, t: float, inputs: Any, arbiter: Any) -> Any:
        from mpcshare.control.strategies.base import Target

        K = self.r.size
        pi = inputs.mode_proba if inputs.mode_proba is not None and len(inputs.mode_proba) == K else np.full(K, 1 / K)
        speed = float(np.linalg.norm(inputs.u_v)) if inputs.u_v is not None else 0.0
        prior = math.exp(float(pi @ self.logc))
        dt = min(max(t - self._t, 0.0), 0.1) if math.isfinite(self._t) else 0.0
        self._t = t
        if self._c is None:
            self._c = prior
        elif arbiter.alpha >= 0.5:
            self._c += min(dt / TAU_S, 1.0) * (speed - self._c)
        else:
            self._c += min(dt / RELAX_S, 1.0) * (prior - self._c)
        var_r = math.exp(float(pi @ self.r) + self.g * math.log(self._c + EPS) + self.s2 / 2)
        var_w = float(pi @ self.w)
        a = var_w / (var_r + var_w)
        if self.split:
            robot_leads = a > 0.5 + self.band or (arbiter.alpha >= 0.5 and a >= 0.5 - self.band)
            a = max(a, 0.5) if robot_leads else 0.0
        return Target(a, f"fusion: robot {1e3 * math.sqrt(var_r):.1f} mm, wearer {1e3 * math.sqrt(var_w):.1f} mm",
                      ramp=True, beta=1.0 - a)


def fusion_controller(params: dict[str, Any], split: bool = False) -> Any:
    """A ``make_controller`` for ``simulate_episode``: a ``SharedController`` whose arbiter runs
    :class:`FusionPolicy` (built as ``mix50``, the policy then replaced; α starts at 0)."""

    def make(bundle: Any, **options: Any) -> Any:
        from mpcshare.control.controller import SharedController

        ctl = SharedController.from_bundle(bundle, **{**options, "strategy": "mix50"})
        ctl.arbiter.policy = FusionPolicy(params, split)
        ctl.arbiter.reset()
        return ctl

    return make
