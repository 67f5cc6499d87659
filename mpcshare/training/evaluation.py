"""Held-out evaluation of a trained gate + reactive predictor at a threshold K.

Held-out points get their modes from the training trials' HMM (Viterbi per held-out trial) and their quotients
within modes from pairs of held-out points only, Z_t = 1[q_t ≤ K] with the training K (no held-out trial in
any fit; fewer partners, so a somewhat higher reactive share than in training: docs/training.md).
Reported on the held-out windowed steps (a full causal window):

- ``rmse_reactive`` / ``rmse_all`` / ``rmse_gated``: the predictor's RMSE on R = {Z = 1}, on every step, on the
  steps the gate hands to the robot (ĥ = 1), sqrt(mean_{t, c} (û_{t,c} − u_{t,c})²) in standardised action
  units; per channel group in physical units (``*_by_group``, :func:`learning.predictor.rmse_by_group`);
- the gates' accuracy, F1 and Brier score per mode (:func:`learning.gates.metrics.gate_metrics`);
- ``voluntary_share`` = mean_t (1 − ĥ_t), ĥ_t = 1[gate probability ≥ 0.5];
- ``voluntary_effort`` E = (1/N) · Σ_t (1 − ĥ_t) · ‖θ_t‖ [rad] over the N steps, θ the shoulder angles from the
  neutral posture (causally downsampled): the closed loop's effort (:mod:`sim.metrics`) with the wearer at rest
  wherever the gate hands to the robot. Without a voluntary channel θ_t is the proxy ‖u_t − u_{t−1}‖/Δt of the
  standardised action (Δt = 1/model_hz; standardised units/s); ``effort_source`` says which;
  ``effort_if_all_voluntary`` is E with ĥ ≡ 0.
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Any, Mapping

import numpy as np

from mpcshare.training.data import SplitData, TrainingData, reactive_labels

if TYPE_CHECKING:  # annotations only
    from learning.gates import ModeGates
    from learning.predictor import ReactivePredictor

__all__ = ["command_magnitude", "voluntary_effort", "rmse", "evaluate", "fit_ridge", "forecast_errors",
           "heldout_gate", "predict_side",
           "RMSE_UNITS"]

RMSE_UNITS = "standardised action units (per-sensor unit RMS), RMS over channels and steps"


def command_magnitude(side: SplitData, model_hz: float) -> tuple[np.ndarray, str, str]:
    """(n_windows,) the wearer's command magnitude at the windowed steps; source; units.

    ‖θ_t‖ [rad] of the voluntary channel θ if every trial has one; else the proxy
    ‖u_t − u_{t−1}‖·model_hz of the standardised action u (the first step of a trial
    counts as still).
    """
    has_vol = side.std.has_voluntary and side.std.trials[0].voluntary.shape[1] > 0
    if has_vol:
        mags = [np.linalg.norm(tr.voluntary, axis=1) for tr in side.std.trials]
    else:
        mags = [np.concatenate([[0.0], np.linalg.norm(np.diff(tr.act, axis=0), axis=1) * float(model_hz)])
                for tr in side.std.trials]
    magnitude = np.concatenate(mags)[side.windows.source_index]
    if has_vol:
        return magnitude, "voluntary", "rad (shoulder angles from neutral)"
    return magnitude, "action_proxy", "standardised action units/s (knife speed, no voluntary channel)"


def voluntary_effort(gate: np.ndarray, magnitude: np.ndarray) -> float:
    """E = mean_t (1 − ĥ_t)·m_t, m_t the command magnitude (module docstring)."""
    gate = np.asarray(gate, dtype=float)
    return float(np.mean((1.0 - gate) * np.asarray(magnitude, dtype=float))) if gate.size else float("nan")


def rmse(pred: np.ndarray, true: np.ndarray, mask: np.ndarray | None = None) -> float | None:
    """sqrt(mean over steps and channels of the squared error), on ``mask`` rows; None if empty."""
    e = np.asarray(pred) - np.asarray(true)
    if mask is not None:
        e = e[np.asarray(mask, dtype=bool)]
    return None if e.size == 0 else float(np.sqrt(np.mean(e ** 2)))


def fit_ridge(data: TrainingData) -> Any:
    """The ridge baseline: ridge regression on the causal window (L samples) of the LSTM's
    input concat(o_t, p_t) → standardised act, fitted on every windowed training step."""
    from learning.predictor import RidgeWindowBaseline

    side = data.train
    mask = side.masks(np.ones(len(side.q), dtype=bool))
    return RidgeWindowBaseline(lags=side.windows.lags).fit(side.sequences(), side.targets(), mask)


def predict_side(model: Any, side: SplitData) -> np.ndarray:
    """(n_windows, d_u) standardised predictions at the windowed steps of ``side``: the
    model (LSTM or ridge) runs over each trial's sequence concat(o_t, p_t)."""
    return side.stacked_predictions(model)


def _errors(data: TrainingData, pred: np.ndarray, R: np.ndarray,
            gated: np.ndarray | None) -> dict[str, Any]:
    from learning.predictor import rmse_by_group

    side = data.heldout
    true = side.windows.Y
    act = data.preprocessor.act
    phys_pred, phys_true = act.inverse_transform(pred), act.inverse_transform(true)
    names = list(data.act_names)
    out: dict[str, Any] = {
        "rmse_reactive": rmse(pred, true, R), "rmse_all": rmse(pred, true),
        "rmse_reactive_by_group": rmse_by_group(phys_true[R], phys_pred[R], names) if R.any() else None,
        "rmse_all_by_group": rmse_by_group(phys_true, phys_pred, names),
    }
    if gated is not None:
        out["rmse_gated"] = rmse(pred, true, gated)
    return out


def forecast_errors(data: TrainingData, predictor: ReactivePredictor, R: np.ndarray) -> dict[str, Any] | None:
    """RMSE per horizon of the predictor's forecast on the held-out reactive steps, against
    holding and extrapolating its current estimate (:func:`learning.predictor.forecast.forecast_rmse`);
    in metres on the knife tip channels (``knife_x/y/z``) when the data has them, else in
    standardised action units. None for a predictor without a forecast."""
    from learning.predictor.forecast import forecast_rmse

    if not int(getattr(predictor, "horizons", 0)):
        return None
    side, act = data.heldout, data.preprocessor.act
    masks = side.masks(R)
    names = list(data.act_names)
    tip = [names.index(n) for n in ("knife_x", "knife_y", "knife_z")] if all(
        n in names for n in ("knife_x", "knife_y", "knife_z")) else None
    forecasts, targets = [], []
    for seq, tr in zip(side.sequences(), side.std.trials):
        F = predictor.forecast(seq)
        T, n_h, d = F.shape
        forecasts.append(act.inverse_transform(F.reshape(T * n_h, d)).reshape(T, n_h, d) if tip else F)
        targets.append(act.inverse_transform(tr.act) if tip else tr.act)
    out = forecast_rmse(forecasts, targets, masks, 1.0 / data.config.model_hz, columns=tip)
    out["units"] = "m (knife tip, RMS over x, y, z)" if tip else RMSE_UNITS
    return out


def _share_by_label(side: SplitData, wearer: np.ndarray) -> dict[str, float] | None:
    """Mean of ``wearer`` (n_windows,) per true mode label of the data (None without labels)."""
    if any(tr.mode is None for tr in side.std.trials):
        return None
    labels = np.concatenate([tr.mode for tr in side.std.trials])[side.windows.source_index]
    return {str(int(j)): float(np.mean(wearer[labels == j])) for j in np.unique(labels) if j >= 0}


def heldout_gate(data: TrainingData, gates: ModeGates, K: float) -> tuple[np.ndarray, np.ndarray, dict[str, Any]]:
    """The gates on the held-out windows at threshold ``K``: (Z, the quotient labels; ĥ = 1[gate probability ≥ 0.5];
    :func:`learning.gates.metrics.gate_metrics` against Z)."""
    from learning.gates.metrics import gate_metrics

    side = data.heldout
    Z = reactive_labels(side.q, K)
    h = (gates.predict_proba(side.windows.X, side.window_modes) >= 0.5).astype(int)
    return Z, h, gate_metrics(gates, side.windows.X, side.window_modes, Z)


def evaluate(data: TrainingData, gates: ModeGates, predictor: ReactivePredictor, K: float,
             baselines: Mapping[str, Any] | None = None,
             baseline_predictions: Mapping[str, np.ndarray] | None = None) -> dict[str, Any]:
    """Held-out metrics of ``gates`` + ``predictor`` at threshold ``K`` (module docstring).

    ``baselines``: name → fitted model (LSTM or window model), evaluated on the same R;
    ``baseline_predictions``: name → precomputed held-out predictions (n_windows, d_u).
    Returns a JSON-able dict.
    """
    side = data.heldout
    Z, h, gate = heldout_gate(data, gates, K)
    R = Z.astype(bool)
    magnitude, source, units = command_magnitude(side, data.config.model_hz)
    preds = {name: predict_side(m, side) for name, m in (baselines or {}).items()}
    preds.update(baseline_predictions or {})
    return {
        "K": None if math.isinf(K) else float(K),
        "n_heldout_steps": int(len(Z)),
        "heldout_reactive_share": float(R.mean()),
        "predictor": _errors(data, predict_side(predictor, side), R, h.astype(bool)),
        "forecast": forecast_errors(data, predictor, R),
        "baselines": {name: _errors(data, p, R, None) for name, p in preds.items()},
        "gate": gate,
        "voluntary_share": float(np.mean(1 - h)),
        "voluntary_share_by_label": _share_by_label(side, 1 - h),
        "voluntary_effort": voluntary_effort(h, magnitude),
        "effort_if_all_voluntary": float(np.mean(magnitude)),
        "effort_source": source,
        "effort_units": units,
        "rmse_units": RMSE_UNITS,
        "rmse_by_group_units": "physical units of each channel group (e.g. m, rad, N)",
    }
