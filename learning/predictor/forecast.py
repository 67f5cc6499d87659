"""Forecast accuracy per horizon, against the two forecasts that need no learning.

For a forecast F[t, h] of the action u_{t+h} (h = 0 … H model steps, made at step t):

    RMSE_h = sqrt( mean_{t ∈ M_h, c} (F[t, h, c] − u_{t+h, c})² ),   M_h = {t : mask_t, t + h < T}

and the same for the baselines built from the forecast's own current estimate
û_t = F[t, 0] (so they show what forecasting adds, with the same estimate of *now*):

* ``hold``: F[t, h] = û_t, the output held until the next model tick (the
  controller before forecasting);
* ``constant_velocity``: F[t, h] = û_t + h·(û_t − û_{t−1}) (û_{−1} = û_0).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["FORECAST_BASELINES", "forecast_rmse"]

FORECAST_BASELINES = ("hold", "constant_velocity")


def _baselines(F: np.ndarray) -> dict[str, np.ndarray]:
    now = F[:, 0, :]
    prev = np.vstack([now[:1], now[:-1]])
    h = np.arange(F.shape[1])[None, :, None]
    return {"hold": np.repeat(now[:, None, :], F.shape[1], axis=1),
            "constant_velocity": now[:, None, :] + h * (now - prev)[:, None, :]}


def forecast_rmse(forecasts: Sequence[np.ndarray], targets: Sequence[np.ndarray], masks: Sequence[np.ndarray],
                  step_s: float, columns: Sequence[int] | None = None) -> dict[str, Any]:
    """RMSE per horizon of the forecast and of its baselines (module docstring), pooled over trials.

    Args:
        forecasts: per trial (T_i, H+1, d) forecasts.
        targets: per trial (T_i, d) true actions (same units).
        masks: per trial (T_i,) bool, the steps t that count.
        step_s: the model step [s] (horizon h is h·step_s ahead).
        columns: the action columns to score (None: all).

    Returns ``{"horizons_s": [...], "forecast": [...], "hold": [...], "constant_velocity": [...],
    "n_steps": [...]}`` (None where no step counts).
    """
    if not (len(forecasts) == len(targets) == len(masks)) or not len(forecasts):
        raise ValueError(f"need one forecast, target and mask per trial, got {len(forecasts)}, {len(targets)}, "
                         f"{len(masks)}")
    n_h = int(np.asarray(forecasts[0]).shape[1])
    sq = {k: np.zeros(n_h) for k in ("forecast", *FORECAST_BASELINES)}
    count, steps = np.zeros(n_h), np.zeros(n_h, dtype=int)
    for i, (F, y, m) in enumerate(zip(forecasts, targets, masks)):
        F, y, m = np.asarray(F, dtype=float), np.asarray(y, dtype=float), np.asarray(m, dtype=bool)
        if F.ndim != 3 or F.shape[1] != n_h or F.shape[0] != y.shape[0] or F.shape[2] != y.shape[1] \
                or m.shape != (y.shape[0],):
            raise ValueError(f"trial {i}: forecast {F.shape}, target {y.shape}, mask {m.shape} do not match "
                             f"(T, {n_h}, d), (T, d), (T,)")
        cols = list(range(y.shape[1])) if columns is None else list(columns)
        preds = {"forecast": F, **_baselines(F)}
        T = y.shape[0]
        for h in range(n_h):
            rows = np.flatnonzero(m[:max(T - h, 0)])
            if not rows.size:
                continue
            true = y[rows + h][:, cols]
            for name, P in preds.items():
                sq[name][h] += float(np.sum((P[rows, h][:, cols] - true) ** 2))
            count[h] += rows.size * len(cols)
            steps[h] += rows.size

    def finish(x: np.ndarray) -> list[float | None]:
        return [float(np.sqrt(v / c)) if c else None for v, c in zip(x, count)]

    return {"horizons_s": [round(h * step_s, 6) for h in range(n_h)], **{k: finish(v) for k, v in sq.items()},
            "n_steps": steps.tolist()}
