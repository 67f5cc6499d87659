"""Labels, causal signals and their scores for one world's recorded runs (:mod:`.record`).

Label at step t, horizon H: the robot errs more than the wearer over the next H seconds,
D_t = mean_{t<s≤t+H} ‖p_r(s) − p*(s)‖² − mean_{t<s≤t+H} ‖p_w(s) − p*(s)‖² > 0, with p_r the knife tip of the
robot alone (``reactive``), p_w that of the wearer alone (``voluntary``) on the same trial and sim seed,
p* the wearer's intent. Signals are computed from the robot-alone run's record at steps ≤ t (:data:`SIGNALS`);
each is scored by AUC for the label and Spearman's ρ against D_t, pooled over the world's trials, after a
2 s warm-up. The combined signal is a logistic regression on the signals and the mode posterior mapped to
normal scores (quantile transform), cross-fitted (leave one trial out), scored on its held-out predictions;
``mode_posterior_only`` is that regression on the mode posterior alone (what a rule per estimated mode
sees), the baseline the signals must beat.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
from scipy import stats

from research.coming_error.signals import (
    AdaptiveConformal,
    GammaDwell,
    auc,
    dwell_runs,
    entropy,
    future_mean,
    past_mean,
    time_in_state,
)

HORIZONS_S = (0.3, 0.5, 1.0)
WARMUP_S = 2.0
CORRECTION_S = 0.3  # window of the wearer's corrections
FORECAST_STEP = 5  # the fast path's horizon index scored by the conformal interval (5 model steps = 0.5 s)
# name → what it is (docs/results.md's table)
SIGNALS = {
    "conformal_radius": "(a) adaptive conformal radius (90 %) of the 0.5 s forecast's residual against the tip",
    "forecast_revision": "(a) spread of the forecasts of the present made 0.1–0.5 s ago",
    "shoulder_deflection": "(b) the wearer's shoulder deflection, mean over 0.3 s",
    "correction_against": "(b) the wearer's corrective tip velocity against the robot's motion, 0.3 s",
    "correction_displacement": "(b) the wearer's corrective tip displacement over 0.5 s",
    "mode_hazard": "(c) gamma hazard of leaving the estimated mode after the time in it",
    "mode_change_within_h": "(c) gamma probability of leaving the estimated mode within H",
    "time_in_mode": "(c) time in the estimated mode",
    "forecaster_disagreement": "(d) fast path against the 10 Hz LSTM forecast, mean over horizons",
    "mode_entropy": "(d) the mode posterior's entropy",
    "novelty": "the mode filter's novelty (−log predictive)",
    "robot_past_error": "reference, not observable: the robot's own tip error over the last 0.3 s",
}
OBSERVABLE = tuple(k for k in SIGNALS if k != "robot_past_error")


def load_world(folder: Path) -> tuple[dict[str, Any], list[tuple[dict[str, np.ndarray], dict[str, np.ndarray]]]]:
    """(meta, [(robot-alone arrays, wearer-alone arrays) per trial]) of a recorded world."""
    meta = json.loads((folder / "meta.json").read_text())
    runs = []
    for tid in meta["trials"]:
        with np.load(folder / f"reactive_{tid}.npz") as r, np.load(folder / f"voluntary_{tid}.npz") as w:
            runs.append(({k: r[k] for k in r.files}, {k: w[k] for k in w.files}))
    return meta, runs


def dwell_model(folder: Path) -> GammaDwell:
    """Gamma dwell laws of the estimated modes on the training trials (``dwells.npz``)."""
    with np.load(folder / "dwells.npz") as z:
        states, durs = dwell_runs(z["mode"], z["trial"], float(z["dt"]))
    return GammaDwell.fit(states, durs)


def trial_signals(r: dict[str, np.ndarray], dwell: GammaDwell, h_s: float) -> dict[str, np.ndarray]:
    """Every signal of :data:`SIGNALS` per step of one robot-alone run (causal), ``mode_change_within_h``
    for horizon ``h_s``."""
    t = r["t"]
    dt = float(np.median(np.diff(t)))
    n_c = max(1, round(CORRECTION_S / dt))
    out: dict[str, np.ndarray] = {}
    fast = r.get("fast")
    N = t.size
    if fast is not None:
        per_tick = round(0.1 / dt)  # the forecast's horizons are 0.1 s apart (10 Hz model)
        lag = FORECAST_STEP * per_tick
        resid = np.full(N, np.nan)
        resid[lag:] = np.linalg.norm(fast[:-lag, FORECAST_STEP] - r["tip"][lag:], axis=1)
        q, _ = AdaptiveConformal(0.1, 0.005, window=round(10.0 / dt), delay=0).radii(resid)
        out["conformal_radius"] = q
        past = [fast[:, 0]]
        for k in range(1, fast.shape[1]):
            p = np.full((N, 3), np.nan)
            p[k * per_tick:] = fast[:-k * per_tick, k]
            past.append(p)
        stack = np.stack(past)  # (H+1, N, 3): forecasts of p(t) made k·0.1 s ago
        with np.errstate(invalid="ignore"):
            out["forecast_revision"] = np.linalg.norm(np.nanstd(stack, axis=0), axis=1)
        out["forecaster_disagreement"] = np.linalg.norm(fast - r["slow"], axis=2).mean(axis=1)
    else:
        for k in ("conformal_radius", "forecast_revision", "forecaster_disagreement"):
            out[k] = np.full(N, np.nan)
    out["shoulder_deflection"] = past_mean(np.linalg.norm(r["shoulder"], axis=1), n_c)
    v_ref = np.gradient(r["reference"], dt, axis=0)
    speed = np.linalg.norm(v_ref, axis=1)
    against = -np.sum(r["u_v"] * v_ref, axis=1) / np.maximum(speed, 1e-3)
    out["correction_against"] = past_mean(np.maximum(against, 0.0), n_c)
    out["correction_displacement"] = np.linalg.norm(past_mean(r["u_v"], round(0.5 / dt)) * 0.5, axis=1)
    mode = np.argmax(r["mode_proba"], axis=1)
    d = time_in_state(mode, dt)
    out["time_in_mode"] = d
    out["mode_hazard"] = dwell.hazard(d, mode)
    out["mode_change_within_h"] = dwell.change_within(d, h_s, mode)
    out["mode_entropy"] = entropy(r["mode_proba"])
    out["novelty"] = r["novelty"]
    out["robot_past_error"] = past_mean(np.linalg.norm(r["tip"] - r["intent"], axis=1), n_c)
    return out


def labels(r: dict[str, np.ndarray], w: dict[str, np.ndarray], h_s: float) -> np.ndarray:
    """D_t [m²] (module docstring) per step; NaN where fewer than H seconds remain."""
    dt = float(np.median(np.diff(r["t"])))
    n = max(1, round(h_s / dt))
    N = min(r["t"].size, w["t"].size)
    e_r = np.sum((r["tip"][:N] - r["intent"][:N]) ** 2, axis=1)
    e_w = np.sum((w["tip"][:N] - w["intent"][:N]) ** 2, axis=1)
    return future_mean(e_r, n) - future_mean(e_w, n)


def score_world(folder: Path) -> dict[str, Any]:
    """The world's table: per horizon, per signal AUC and Spearman ρ (pooled over trials), the share of
    steps where the robot errs more, and the cross-fitted combined signals (module docstring)."""
    from sklearn.linear_model import LogisticRegression
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import QuantileTransformer

    meta, runs = load_world(folder)
    dwell = dwell_model(folder)
    out: dict[str, Any] = {"world": meta["world"], "trials": meta["trials"],
                           "robot_rms_mm": [1e3 * float(r["rms_m"]) for r, _ in runs],
                           "wearer_rms_mm": [1e3 * float(w["rms_m"]) for _, w in runs],
                           "dwell_gamma": {"shape": dwell.shape, "scale_s": dwell.scale},
                           "horizons": {}}
    for h in HORIZONS_S:
        X, D, G = [], [], []
        for i, (r, w) in enumerate(runs):
            sig = trial_signals(r, dwell, h)
            d = labels(r, w, h)
            N = d.size
            keep = np.isfinite(d) & (r["t"][:N] - r["t"][0] >= WARMUP_S)
            X.append(np.column_stack([sig[k][:N][keep] for k in SIGNALS] + [r["mode_proba"][:N][keep]]))
            D.append(d[keep])
            G.append(np.full(int(keep.sum()), i))
        Xa, Da, Ga = np.concatenate(X), np.concatenate(D), np.concatenate(G)
        y = (Da > 0).astype(float)
        row: dict[str, Any] = {"robot_errs_more_share": float(y.mean()), "steps": int(y.size), "auc": {},
                               "spearman": {}}
        for j, k in enumerate(SIGNALS):
            ok = np.isfinite(Xa[:, j])
            row["auc"][k] = auc(y[ok], Xa[ok, j]) if ok.any() else None
            row["spearman"][k] = float(stats.spearmanr(Xa[ok, j], Da[ok]).statistic) if ok.sum() > 2 else None
        n_s = len(SIGNALS)
        modes = list(range(n_s, Xa.shape[1]))  # the mode posterior's columns
        for name, cols in (("mode_posterior_only", modes),
                           ("combined_observable", [list(SIGNALS).index(k) for k in OBSERVABLE] + modes),
                           ("combined_with_reference", list(range(Xa.shape[1])))):
            Z = Xa[:, cols].copy()
            for c in range(Z.shape[1]):  # ±inf to the column's finite extremes (within ±1e9), NaN to its median
                col = Z[:, c]
                fin = col[np.isfinite(col)]
                lo, hi, med = (fin.min(), fin.max(), np.median(fin)) if fin.size else (0.0, 0.0, 0.0)
                Z[:, c] = np.where(np.isnan(col), med, np.clip(col, max(lo, -1e9), min(hi, 1e9)))
            pred = np.full(y.size, np.nan)
            per_trial = []
            for g in np.unique(Ga):
                tr, te = Ga != g, Ga == g
                if np.unique(y[tr]).size < 2:
                    continue
                model = make_pipeline(QuantileTransformer(n_quantiles=200, output_distribution="normal"),
                                      LogisticRegression(C=1.0, max_iter=500))
                model.fit(Z[tr], y[tr])
                pred[te] = model.predict_proba(Z[te])[:, 1]
                per_trial.append(auc(y[te], pred[te]))
            ok = np.isfinite(pred)
            row["auc"][name] = auc(y[ok], pred[ok])
            row["spearman"][name] = float(stats.spearmanr(pred[ok], Da[ok]).statistic)
            row[f"{name}_per_trial_auc"] = [a for a in per_trial]
        out["horizons"][str(h)] = row
    return out
