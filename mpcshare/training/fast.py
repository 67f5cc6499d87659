"""The control-rate forecast (:mod:`learning.predictor.fast`): its offline inputs, fit and skill scores.

The controller's fast path sees, at every raw-rate step, the Kalman state of the fork
(:class:`mpcshare.control.frontend.ForkKalman` with the front end's noise levels), the mode
posterior and the LSTM forecast of the last model tick. :func:`fast_rows` rebuilds exactly
these from recorded trials: the same Kalman filter run over the raw fork (all trials of a side
at once, one channel block per trial: the channels are independent), the causal mode posteriors
and the LSTM's forecasts at the ticks (the same samples the online front end ticks on:
``causal_downsample`` keeps raw indices 0, f, 2f, …): they equal the controller's own inputs, step by
step.

Skill (:func:`skill_table`): per horizon h and per HMM mode (the mode the controller acts on:
the last tick's most probable one), on the knife tip in metres::

    skill_b[h] = 1 − RMSE_forecast[h] / RMSE_b[h],   b ∈ {hold, constant_velocity}

with the baselines built from the forecast's own estimate of now F_i[0] (as
:mod:`learning.predictor.forecast`): hold F_i[0]; constant velocity F_i[0] + h·(F_i[0] − F_{i−f}[0]).
Above 0: the forecast beats the baseline at that horizon. The MPC's preview uses the forecast
only up to the horizons where its skill against the hold, on the validation trials, is above 0.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, Iterator

import numpy as np

from learning.predictor.fast import VELOCITY_SCALE_S, FastForecaster, fast_design, interpolate_slow
from learning.preprocessing.resample import decimation_factor
from mpcshare.control.frontend import fork_kalman, kalman_batch, kalman_inputs
from mpcshare.training.data import SplitData, TrainingData

if TYPE_CHECKING:  # annotations only
    from learning.data import Demonstrations
    from learning.predictor import ReactivePredictor

__all__ = ["FastRows", "TIP", "fast_rows", "fit_fast", "preview_skill", "skill_table", "trial_designs"]

TIP = ("knife_x", "knife_y", "knife_z")


@dataclass
class FastRows:
    """The fast path's inputs and targets of one side, rows = raw steps that count (all trials).

    phi: (n, p) features; slow: (n, H+1, 3) interpolated LSTM forecast; truth: (n, H+1, 3)
    standardised tip at t + h·Δ_m; mode: (n,) most probable mode of the last tick; trial: (n,)
    trial id; prev: (n,) row of the same trial f steps earlier (−1: none).
    """

    phi: np.ndarray
    slow: np.ndarray
    truth: np.ndarray
    mode: np.ndarray
    trial: np.ndarray
    prev: np.ndarray


def _kalman_states(raw: Demonstrations, scale: np.ndarray, mean: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per trial the standardised Kalman position and velocity (T_i, d_o), as the front end's
    (all trials in one batch of independent channels, padded with NaN past a trial's end)."""
    trials = raw.trials
    d, n, T = raw.obs_dim, len(trials), max(len(tr) for tr in trials)
    Z = np.full((T, n * d), np.nan)
    for k, tr in enumerate(trials):
        Z[:len(tr), k * d:(k + 1) * d] = tr.obs
    X, V = kalman_batch(fork_kalman(np.tile(scale, n), raw.rate_hz), Z)
    return [kalman_inputs(X[:len(tr), k * d:(k + 1) * d], V[:len(tr), k * d:(k + 1) * d], mean, scale,
                          VELOCITY_SCALE_S)
            for k, tr in enumerate(trials)]


def trial_designs(raw: Demonstrations, sequences: list[np.ndarray], posteriors: list[np.ndarray],
                  predictor: ReactivePredictor, pre, tip: list[int], model_hz: float, lags: tuple[int, ...],
                  rows: Callable[[int], np.ndarray] | None = None
                  ) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """Per raw trial (φ (n, p), interpolated slow forecast (n, H+1, 3), tick posterior (n, K)) at the
    steps ``rows(T)`` (None: every raw step): what the controller's fast path sees online.
    ``sequences``/``posteriors``: the trials' model-rate LSTM inputs concat(o, p) and causal mode
    posteriors."""
    f = decimation_factor(raw.rate_hz, model_hz)
    states = _kalman_states(raw, np.asarray(pre.obs.scale_, dtype=float), np.asarray(pre.obs.mean_, dtype=float))
    for tr, seq, p, (P, V) in zip(raw.trials, sequences, posteriors, states):
        F = predictor.forecast(seq)[:, :, tip]  # (T10, H+1, 3) standardised
        i = np.arange(len(tr)) if rows is None else rows(len(tr))
        tick, frac = i // f, (i % f) / f
        slow = interpolate_slow(F[tick], frac)
        full = np.zeros((len(tr), *slow.shape[1:]))
        full[i] = slow  # fast_design reads the steps i only
        yield fast_design(P, V, p[np.arange(len(tr)) // f], full, lags, i), slow, p[tick]


def fast_rows(raw: Demonstrations, side: SplitData, predictor: ReactivePredictor, pre, tip: list[int],
              model_hz: float, lags: tuple[int, ...]) -> FastRows:
    """The fast path's rows of one side (module docstring): every ``stride``-th raw step (half a
    model step: consecutive steps are nearly the same row) from the first full window on, whose
    horizon lies inside its trial."""
    f = decimation_factor(raw.rate_hz, model_hz)
    stride = f // 2 if f % 2 == 0 else 1
    n_h = int(predictor.horizons) + 1
    warm = side.windows.lags * f

    def steps(T: int) -> np.ndarray:
        return np.arange(warm, T - (n_h - 1) * f, stride)

    act_mean, act_scale = np.asarray(pre.act.mean_), np.asarray(pre.act.scale_)
    post = np.split(side.posterior, np.cumsum(side.lengths)[:-1])
    parts: dict[str, list[np.ndarray]] = {k: [] for k in ("phi", "slow", "truth", "mode", "trial", "prev")}
    offset = 0
    designs = trial_designs(raw, side.sequences(), post, predictor, pre, tip, model_hz, lags, steps)
    for tr, (phi, slow, p) in zip(raw.trials, designs):
        Y = (tr.act[:, tip] - act_mean[tip]) / act_scale[tip]
        rows = steps(len(tr))
        parts["phi"].append(phi)
        parts["slow"].append(slow)
        parts["truth"].append(Y[rows[:, None] + f * np.arange(n_h)[None, :]])
        parts["mode"].append(np.argmax(p, axis=1))
        parts["trial"].append(np.full(rows.size, tr.trial_id))
        prev = np.searchsorted(rows, rows - f)
        ok = (rows - f >= rows[0]) & (prev < rows.size)
        parts["prev"].append(np.where(ok, prev + offset, -1))
        offset += rows.size
    return FastRows(**{k: np.concatenate(v) for k, v in parts.items()})


def _rmse(err: np.ndarray) -> list[float | None]:
    """Per horizon RMS over rows and channels of (n, H+1, d) errors."""
    if err.shape[0] == 0:
        return [None] * err.shape[1]
    return [float(v) for v in np.sqrt(np.mean(err ** 2, axis=(0, 2)))]


def _skill(a: list[float | None], b: list[float | None]) -> list[float | None]:
    return [None if x is None or y is None or y <= 0 else 1.0 - x / y for x, y in zip(a, b)]


def _scores(F: np.ndarray, S: np.ndarray, truth: np.ndarray, now_prev: np.ndarray) -> dict[str, Any]:
    h = np.arange(F.shape[1])[None, :, None]
    now = F[:, :1, :]
    base = {"hold": np.broadcast_to(now, F.shape), "constant_velocity": now + h * (now - now_prev[:, None, :])}
    rmse = {"forecast": _rmse(F - truth), "slow_lstm": _rmse(S - truth),
            **{k: _rmse(v - truth) for k, v in base.items()}}
    return {"n_steps": int(F.shape[0]), "rmse": rmse,
            "skill": {"vs_hold": _skill(rmse["forecast"], rmse["hold"]),
                      "vs_constant_velocity": _skill(rmse["forecast"], rmse["constant_velocity"]),
                      "slow_lstm_vs_hold": _skill(rmse["slow_lstm"], rmse["hold"])}}


def skill_table(F: np.ndarray, rows: FastRows, scale: np.ndarray, n_modes: int, step_s: float) -> dict[str, Any]:
    """RMSE [m] and skill per horizon, pooled and per mode (module docstring); F (n, H+1, 3) standardised."""
    keep = rows.prev >= 0
    Fm, Sm, Ym = (a * scale for a in (F, rows.slow, rows.truth))
    now_prev = Fm[np.where(keep, rows.prev, 0), 0, :]
    Fm, Sm, Ym, now_prev, mode = Fm[keep], Sm[keep], Ym[keep], now_prev[keep], rows.mode[keep]
    out = {"horizons_s": [round(h * step_s, 6) for h in range(F.shape[1])], "units": "m (knife tip, RMS over x, y, z)",
           **_scores(Fm, Sm, Ym, now_prev), "by_mode": {}}
    for j in range(n_modes):
        sel = mode == j
        out["by_mode"][str(j)] = _scores(Fm[sel], Sm[sel], Ym[sel], now_prev[sel])
    return out


def preview_skill(table: dict[str, Any], n_modes: int) -> np.ndarray:
    """(n_modes, H+1) skill against the hold per mode (the pooled figure where a mode has no step; 0 at h = 0)."""
    pooled = np.array([s if s is not None else -1.0 for s in table["skill"]["vs_hold"]])
    out = np.tile(pooled, (n_modes, 1))
    for j in range(n_modes):
        s = table["by_mode"][str(j)]["skill"]["vs_hold"]
        if table["by_mode"][str(j)]["n_steps"]:
            out[j] = [v if v is not None else -1.0 for v in s]
    out[:, 0] = 0.0
    return out


def fit_fast(data: TrainingData, predictor: ReactivePredictor) -> tuple[FastForecaster | None, dict[str, Any]]:
    """The fast forecaster fitted on the fit trials, its preview skill from the validation trials and
    its skill table on the held-out trials; (None, reason) when the data has no knife tip channels
    or the predictor no forecast, or too few fit steps for its features."""
    c = data.config
    names = list(data.act_names)
    if not all(n in names for n in TIP):
        return None, {"skipped": f"no knife tip channels {list(TIP)} among the actions"}
    if data.train_raw is None or data.heldout_raw is None:
        return None, {"skipped": "the raw-rate trials were not kept"}
    tip = [names.index(n) for n in TIP]
    lags = tuple(int(v) for v in c.fast_lags)
    pre = data.preprocessor
    train = fast_rows(data.train_raw, data.train, predictor, pre, tip, c.model_hz, lags)
    fit = np.isin(train.trial, data.fit_trials)
    n_fit, n_features = int(fit.sum()), int(train.phi.shape[1])
    if n_fit <= n_features:
        return None, {"skipped": f"{n_fit} fit steps for {n_features} features: too few to fit (more or longer "
                                 f"trials)"}
    model = FastForecaster(alpha=c.fast_alpha, lags=lags).fit(train.phi[fit], train.slow[fit], train.truth[fit])
    scale = np.asarray(pre.act.scale_)[tip]
    step_s = 1.0 / c.model_hz

    def table(rows: FastRows) -> dict[str, Any]:
        return skill_table(model.predict(rows.phi, rows.slow), rows, scale, data.modes.n_modes, step_s)

    val = _subset(train, ~fit)
    model.channels_ = TIP
    model.preview_skill_ = preview_skill(table(val), data.modes.n_modes)
    held = fast_rows(data.heldout_raw, data.heldout, predictor, pre, tip, c.model_hz, lags)
    return model, {**table(held), "preview_skill_validation": model.preview_skill_.tolist(),
                   "rate_hz": float(data.rate_hz)}


def _subset(rows: FastRows, sel: np.ndarray) -> FastRows:
    """Rows ``sel`` (bool) with ``prev`` re-indexed (−1 where the earlier row is left out)."""
    idx = np.flatnonzero(sel)
    new = np.full(sel.size, -1)
    new[idx] = np.arange(idx.size)
    prev = np.where(rows.prev[idx] >= 0, new[np.maximum(rows.prev[idx], 0)], -1)
    return FastRows(rows.phi[idx], rows.slow[idx], rows.truth[idx], rows.mode[idx], rows.trial[idx], prev)
