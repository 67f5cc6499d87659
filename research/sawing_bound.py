"""The splice bound with the task's own measure: the lowest error of any schedule whose knife still saws.

:mod:`~research.splice_bound` splices constant-authority runs per group of steps. Here the
spliced knife must also saw: with b_{l,k} the stroke-band tip of run l and b*_k the intent's at cutting
step k (:func:`sim.task.metrics.bandpass`), per group g

    X_g(l) = Σ_{k∈g, cutting} b_{l,k}·b*_k,   S_g(l) = Σ_{k∈g, cutting} ‖b_{l,k}‖²,   Y = Σ_{cutting} ‖b*_k‖²,

and the spliced stroke correlation ρ(a) = Σ_g X_g / √(Y·Σ_g S_g) must be at least c (the task's
measure, :func:`sim.task.metrics.sawing_fidelity`, of the spliced band-passed signals: the filter's
response to a switch is left out, as a splice leaves out the switch). Since √S = min_{t>0} (S/t + t)/2,

    ρ(a) ≥ c  ⟺  ∃ t > 0:  Σ_g w_g(l(g); t) ≥ c√Y·t/2,   w_g(l; t) = X_g(l) − c√Y·S_g(l)/(2t),

and for every λ ≥ 0 an assignment a in effort bin b that meets the constraint of some t has

    N·M(a) ≥ Σ_g [E_g − λ·w_g] ≥ DP_{t,λ}[b] + λ·c√Y·t/2,

DP the multiple-choice knapsack of :func:`~research.splice_bound.knapsack` with the cost
E − λ·w (Lagrangian relaxation). So LB[b] = min_t max_λ (DP_{t,λ}[b] + λ·c√Y·t/2)/N bounds from below
the MSE of every assignment in bin b that saws; a bin whose bound exceeds the largest error any
assignment has holds none that saws (it is left out). t runs over a geometric grid of ratio q: the nearest t
meets (S/t + t)/2 ≤ κ√S, κ = (√q + 1/√q)/2, so the grid uses c/κ and the bound stays optimistic.
Each DP's assignments are also scored exactly; those that saw (ρ ≥ c) are schedules found, an upper
bound: the truth lies between. Checked against brute force in ``tests/research``.
No library solves this relaxation with the knapsack, so it is written here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mpcshare.line_ratio import line_ratio, line_rms
from research.splice_bound import assignments, effort_bins, group_sums, knapsack

__all__ = ["SawingFront", "best_line_ratios", "sawing_front", "stroke_terms"]


@dataclass(frozen=True)
class SawingFront:
    """Per effort bin: the bound and the best schedule found that saws.

    effort: (B,) the bin's mean effort [rad] (rounded down; every assignment in the bin has at most
    effort + slack); mse: (B,) the lowest mean squared error [m²]
    any sawing assignment in the bin could have (a bound from below); found_mse, found_effort,
    found_correlation: (B,) the exact figures of the best sawing assignment found there (inf/nan where
    none); found_assignment: (G, B) its run per group (−1 where none).
    """

    effort: np.ndarray
    slack: float
    mse: np.ndarray
    found_mse: np.ndarray
    found_effort: np.ndarray
    found_correlation: np.ndarray
    found_assignment: np.ndarray


def stroke_terms(tip: np.ndarray, intent: np.ndarray, cutting: np.ndarray, dt: float
                 ) -> tuple[np.ndarray, np.ndarray, float]:
    """(b_k·b*_k (N,), ‖b_k‖² (N,), Y = Σ‖b*_k‖²) of one run's (N, d) tip and intent [m] every dt [s], zero
    outside ``cutting`` (N,): the terms of the module docstring, band-passed as the task measures them."""
    from sim.task.eating import STROKE_BAND_HZ
    from sim.task.metrics import bandpass

    tip, intent = np.asarray(tip, dtype=float), np.asarray(intent, dtype=float)
    mask = np.asarray(cutting, dtype=bool)
    if tip.ndim != 2 or tip.shape != intent.shape or mask.shape != (len(tip),):
        raise ValueError(f"tip and intent must be (N, d) of one shape and cutting (N,), got {tip.shape}, "
                         f"{intent.shape} and {mask.shape}")
    b, b_star = bandpass(tip, dt, STROKE_BAND_HZ), bandpass(intent, dt, STROKE_BAND_HZ)
    dot = np.where(mask, np.sum(b * b_star, axis=1), 0.0)
    power = np.where(mask, np.sum(b**2, axis=1), 0.0)
    return dot, power, float(np.sum(b_star[mask] ** 2))


def _lambdas(g_e2: np.ndarray, g_dot: np.ndarray) -> np.ndarray:
    """λ = 0 and a geometric grid around the ratio of the errors' spread to the stroke terms' spread."""
    scale = float(np.sum(np.ptp(g_e2, axis=0))) / max(float(np.sum(np.ptp(g_dot, axis=0))), 1e-30)
    return np.concatenate([[0.0], scale * np.geomspace(1e-3, 1e3, 43)])


def sawing_front(sq_error: np.ndarray, effort: np.ndarray, groups: np.ndarray, band_dot: np.ndarray,
                 band_power: np.ndarray, intent_power: float, min_correlation: float, *,
                 allowed: np.ndarray | None = None, bins: int = 2000, grid_ratio: float = 1.1,
                 lambdas: np.ndarray | None = None) -> SawingFront:
    """The bound and the schedules found of the module docstring.

    sq_error, effort, band_dot, band_power: (L, N) per run and control step, e² [m²], θ [rad], b·b* and
    ‖b‖² [m²] (zero outside cutting); groups: (N,); intent_power: Y [m²]; min_correlation: c in (0, 1];
    allowed: (L, G) as in :func:`~research.splice_bound.splice_front`. ValueError on bad input.
    """
    e2, ef = np.asarray(sq_error, dtype=float), np.asarray(effort, dtype=float)
    dot, pw = np.asarray(band_dot, dtype=float), np.asarray(band_power, dtype=float)
    if e2.ndim != 2 or not (e2.shape == ef.shape == dot.shape == pw.shape) or e2.shape[1] != np.size(groups):
        raise ValueError(f"sq_error, effort, band_dot and band_power must all be (runs, steps) with one group per "
                         f"step, got {e2.shape}, {ef.shape}, {dot.shape}, {pw.shape} and {np.size(groups)} groups")
    if not all(np.all(np.isfinite(x)) for x in (e2, ef, dot, pw)) or np.any(ef < 0) or np.any(pw < 0):
        raise ValueError("the per-step figures must be finite, effort and band_power >= 0")
    if not 0 < min_correlation <= 1 or not intent_power > 0 or not grid_ratio > 1:
        raise ValueError(f"need 0 < min_correlation <= 1 (got {min_correlation}), intent_power > 0 (got "
                         f"{intent_power}) and grid_ratio > 1 (got {grid_ratio})")
    runs, n = e2.shape
    _, sums = group_sums(np.concatenate([e2, ef, dot, pw]), groups)
    g_e2, g_ef, g_dot, g_pw = (sums[i * runs:(i + 1) * runs] for i in range(4))
    ok = np.ones_like(g_e2, dtype=bool) if allowed is None else np.asarray(allowed, dtype=bool)
    if ok.shape != g_e2.shape or not np.all(ok.any(axis=0)):
        raise ValueError(f"allowed must be (runs, groups) = {g_e2.shape} with a run allowed in every group")
    width, shift, size = effort_bins(g_ef, ok, bins)
    c_root_y = min_correlation * np.sqrt(intent_power)
    c_grid = c_root_y * 2.0 / (np.sqrt(grid_ratio) + 1.0 / np.sqrt(grid_ratio))  # c/κ·√Y: a superset
    s_lo = float(np.sum(np.min(np.where(ok, g_pw, np.inf), axis=0)))
    s_hi = float(np.sum(np.max(np.where(ok, g_pw, 0.0), axis=0)))
    t_lo = max(np.sqrt(s_lo), 1e-12 * max(np.sqrt(s_hi), 1e-12))
    count = int(np.ceil(np.log(max(np.sqrt(s_hi), t_lo) / t_lo) / np.log(np.sqrt(grid_ratio)))) + 1
    t_grid = t_lo * np.sqrt(grid_ratio) ** np.arange(count)  # every √S in [√s_lo, √s_hi] within √q of one t
    lam = _lambdas(g_e2, g_dot) if lambdas is None else np.asarray(lambdas, dtype=float)
    bound = np.full(size, np.inf)
    found = np.full(size, np.inf)
    found_effort, found_corr = np.full(size, np.nan), np.full(size, np.nan)
    found_assignment = np.full((g_e2.shape[1], size), -1, dtype=int)
    cols = np.arange(g_e2.shape[1])[:, None]
    for t in t_grid:
        w = g_dot - c_grid * g_pw / (2.0 * t)
        lower_t = np.full(size, -np.inf)
        for lm in lam:
            dp, picks = knapsack(g_e2 - lm * w, shift, ok, size)
            lower_t = np.maximum(lower_t, dp + lm * c_grid * t / 2.0)  # inf where no assignment reaches the bin
            reach = np.flatnonzero(np.isfinite(dp))
            a = assignments(picks, shift, reach)  # (G, B): score each assignment exactly
            m, s, x = g_e2[a, cols].sum(0), g_pw[a, cols].sum(0), g_dot[a, cols].sum(0)
            rho = np.where(s > 0, x / np.sqrt(intent_power * np.maximum(s, 1e-300)), 0.0)
            better = (rho >= min_correlation) & (m < found[reach])
            idx = reach[better]
            found[idx], found_corr[idx] = m[better], rho[better]
            found_effort[idx] = g_ef[a[:, better], cols].sum(0)
            found_assignment[:, idx] = a[:, better]
        bound = np.minimum(bound, lower_t)
    worst = float(np.sum(np.max(np.where(ok, g_e2, -np.inf), axis=0)))
    bound[bound > worst * (1 + 1e-9) + 1e-300] = np.inf  # above every assignment's error: none there saws
    reach = np.flatnonzero(np.isfinite(bound))
    return SawingFront(reach * width / n, g_e2.shape[1] * width / n, np.maximum(bound[reach], 0.0) / n,
                       found[reach] / n, found_effort[reach] / n, found_corr[reach], found_assignment[:, reach])


def best_line_ratios(front: SawingFront, voluntary: tuple[float, float], reactive: tuple[float, float],
                     max_effort: float | None = 0.75) -> tuple[float | None, float | None, int | None]:
    """(the bound's lowest line ratio within ``max_effort`` × the voluntary effort, the best schedule
    found's, the front's index of that schedule); None where none qualifies.

    voluntary, reactive: (effort [rad], RMS [m]) of the two parties."""
    cap = np.inf if max_effort is None else max_effort * voluntary[0]

    def ratio(m: float, e: float) -> float | None:
        return line_ratio(float(np.sqrt(m)), float(e), voluntary, reactive) if np.isfinite(m) and e <= cap else None

    def lowest(m: float, e: float) -> float | None:  # the line's highest RMS over the bin's efforts: optimistic
        lines = [line_rms(float(x), voluntary, reactive) for x in (e, e + front.slack)]
        top = max((x for x in lines if x is not None), default=None)
        return float(np.sqrt(m)) / top if np.isfinite(m) and e <= cap and top else None

    bounds = [r for r in (lowest(m, e) for e, m in zip(front.effort, front.mse)) if r is not None]
    found = [(r, i) for i, (e, m) in enumerate(zip(front.found_effort, front.found_mse))
             if (r := ratio(m, e)) is not None]
    best = min(found) if found else (None, None)
    return (min(bounds) if bounds else None), best[0], best[1]
