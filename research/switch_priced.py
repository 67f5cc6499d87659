"""Schedules that pay for their switches: the splice search with a price per switch (issue 28).

The splice bounds (:mod:`~research.splice_bound`, :mod:`~research.sawing_bound`)
leave out what a switch of authority costs, and replayed in the closed loop their schedules lose 0.06–0.26
of the line to their switches. Here a switch from level a to level b at the start of a group (not the first
of a trial) adds a price: P_e[a, b] to the summed squared error [m²·steps] and P_θ[a, b] to the summed
effort [rad·steps]. With l(g) the level of group g in time order,

    N·M(a) = Σ_g E_g(l(g)) + Σ_{g: l(g) ≠ l(g−1)} P_e[l(g−1), l(g)],   N·Θ(a) likewise with θ and P_θ,

and the knife must still saw: ρ(a) = Σ_g X_g / √(Y·Σ_g S_g) ≥ c (the terms of
:mod:`~research.sawing_bound`; a switch's effect on the stroke is left out). :func:`priced_search`
finds schedules by the same Lagrangian relaxation as the sawing bound, each DP now a chain over the groups
with the level of the previous group in its state (:func:`chain_knapsack`, exact for its integer effort
bins, checked against brute force), scores every schedule found exactly and returns the lowest line ratio
within the effort cap. It is a search, not a bound: the prices are estimates, measured from replays of
earlier schedules in the closed loop by :func:`estimate_prices`, so the schedule found is only as good as
its replay says. No library solves this chain knapsack with the assignment recovered, so it is written here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mpcshare.line_ratio import line_ratio
from research.splice_bound import group_sums

__all__ = ["SWITCH_CLASSES", "PricedSchedule", "SwitchPrices", "chain_knapsack", "estimate_prices",
           "next_targets", "priced_search", "switch_class"]

SWITCH_CLASSES = ("to the wearer", "from the wearer", "between robot levels")


def switch_class(before: int, after: int, wearer: int = 0) -> int | None:
    """The index in :data:`SWITCH_CLASSES` of a switch from level ``before`` to ``after`` (None: no switch);
    ``wearer`` is the level at which the wearer leads alone."""
    if before == after:
        return None
    return 0 if after == wearer else 1 if before == wearer else 2


@dataclass(frozen=True)
class SwitchPrices:
    """What a switch adds, per class of :data:`SWITCH_CLASSES`: to the summed squared error [m²·steps] and
    the summed effort [rad·steps] of the steps around it; ``counts``: the switches the estimate rests on."""

    error: np.ndarray
    effort: np.ndarray
    counts: np.ndarray

    @classmethod
    def zero(cls) -> SwitchPrices:
        """Switches for free: the splice."""
        return cls(np.zeros(3), np.zeros(3), np.zeros(3, dtype=int))

    def matrices(self, levels: int, wearer: int = 0) -> tuple[np.ndarray, np.ndarray]:
        """(P_e, P_θ): (levels, levels) the prices of a switch from row level to column level."""
        p_e, p_t = np.zeros((levels, levels)), np.zeros((levels, levels))
        for a in range(levels):
            for b in range(levels):
                c = switch_class(a, b, wearer)
                if c is not None:
                    p_e[a, b], p_t[a, b] = self.error[c], self.effort[c]
        return p_e, p_t


def estimate_prices(samples: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]],
                    wearer: int = 0) -> SwitchPrices:
    """Switch prices from replays of level schedules.

    samples: per replay (level (G,) per group in time order, first (G,) whether the group begins a trial,
    excess_e2 (G,) the replay's summed squared error over each group minus the constant-level run's at
    that level [m²·steps], excess_effort (G,) likewise [rad·steps]). A switch at the
    start of group g is charged the excess of g and, where g+1 holds no switch, of g+1 (the pick-up lasts
    about a second); each class's price is the mean over its switches, and a class never seen takes the
    mean over all switches (0 where there were none). An effort price below 0 is taken as 0."""
    per_class: list[list[tuple[float, float]]] = [[], [], []]
    for level, first, x_e2, x_ef in samples:
        level, first = np.asarray(level, dtype=int), np.asarray(first, dtype=bool)
        x_e2, x_ef = np.asarray(x_e2, dtype=float), np.asarray(x_ef, dtype=float)
        if not (level.shape == first.shape == x_e2.shape == x_ef.shape) or level.ndim != 1:
            raise ValueError(f"level, first and the excesses must be equal-length 1-D arrays, got {level.shape}, "
                             f"{first.shape}, {x_e2.shape} and {x_ef.shape}")
        switch = np.zeros(level.size, dtype=bool)
        switch[1:] = (level[1:] != level[:-1]) & ~first[1:]
        for g in np.flatnonzero(switch):
            c = switch_class(int(level[g - 1]), int(level[g]), wearer)
            span = [g] + ([g + 1] if g + 1 < level.size and not switch[g + 1] and not first[g + 1] else [])
            per_class[c].append((float(x_e2[span].sum()), float(x_ef[span].sum())))
    every = [s for cls in per_class for s in cls]
    fallback = np.mean(every, axis=0) if every else np.zeros(2)
    mean = np.array([np.mean(cls, axis=0) if cls else fallback for cls in per_class])
    return SwitchPrices(mean[:, 0], np.maximum(mean[:, 1], 0.0), np.array([len(cls) for cls in per_class]))


def chain_knapsack(cost: np.ndarray, shift: np.ndarray, ok: np.ndarray, price: np.ndarray, price_shift: np.ndarray,
                   first: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """The knapsack along a chain: (per level and bin the lowest Σ_g cost[l(g), g] + Σ_switches price over
    assignments ending at that level with Σ_g shift + Σ_switches price_shift = b (L, size), per group, level
    and bin the previous group's level (G, L, size)).

    cost, shift, ok: (L, G) per level and group; price, price_shift: (L, L) per switch from row to column
    level (cost, and bins of effort ≥ 0); first: (G,) groups that begin a trial (no price there)."""
    levels, n_groups = cost.shape
    dp = np.full((levels, size), np.inf)
    prev = np.zeros((n_groups, levels, size), dtype=np.int8)
    for lv in np.flatnonzero(ok[:, 0]):
        if shift[lv, 0] < size:
            dp[lv, shift[lv, 0]] = cost[lv, 0]
    for g in range(1, n_groups):
        new = np.full((levels, size), np.inf)
        for lv in np.flatnonzero(ok[:, g]):
            into, arg = np.full(size, np.inf), np.zeros(size, dtype=np.int8)
            for lp in range(levels):
                free = first[g] or lp == lv
                s = int(shift[lv, g] + (0 if free else price_shift[lp, lv]))
                if s >= size:
                    continue
                cand = np.full(size, np.inf)
                cand[s:] = dp[lp, :size - s] + (0.0 if free else price[lp, lv])
                better = cand < into
                into[better], arg[better] = cand[better], lp
            new[lv], prev[g, lv] = into + cost[lv, g], arg
        dp = new
    return dp, prev


def _walk_back(dp: np.ndarray, prev: np.ndarray, shift: np.ndarray, price_shift: np.ndarray, first: np.ndarray,
               bins: np.ndarray) -> np.ndarray:
    """(G, B) the level per group of the chain knapsack's best assignment reaching each of ``bins``."""
    b = np.asarray(bins, dtype=int).copy()
    lv = np.argmin(dp[:, b], axis=0)
    out = np.zeros((prev.shape[0], b.size), dtype=int)
    for g in range(prev.shape[0] - 1, -1, -1):
        out[g] = lv
        if g == 0:
            break
        lp = prev[g, lv, b].astype(int)
        b = b - shift[lv, g] - np.where((lp != lv) & (not first[g]), price_shift[lp, lv], 0)
        lv = lp
    return out


@dataclass(frozen=True)
class PricedSchedule:
    """The best schedule found: its level per group (G,) in sorted label order, and its figures with the
    switch prices: ``mse`` [m²], ``effort`` [rad], ``line_ratio``, ``correlation`` (ρ), ``switches``."""

    assignment: np.ndarray
    mse: float
    effort: float
    line_ratio: float
    correlation: float
    switches: int


def priced_search(sq_error: np.ndarray, effort: np.ndarray, groups: np.ndarray, first: np.ndarray,
                  band_dot: np.ndarray, band_power: np.ndarray, intent_power: float, min_correlation: float,
                  prices: SwitchPrices, voluntary: tuple[float, float], reactive: tuple[float, float], *,
                  max_effort: float = 0.75, wearer: int = 0, bins: int = 1000, grid_ratio: float = 1.3,
                  lambdas: int = 25) -> PricedSchedule | None:
    """The lowest line ratio found, within ``max_effort`` × the voluntary effort, of a schedule that saws and
    pays its switches (module docstring); None where none was found.

    sq_error, effort, band_dot, band_power: (L, N) per level and step, as in
    :func:`~research.sawing_bound.sawing_front`; groups: (N,) labels whose sorted order is time
    order; first: (G,) per sorted group whether it begins a trial; voluntary, reactive: (effort [rad], RMS
    [m]) of the two parties. ValueError on bad input."""
    e2, ef = np.asarray(sq_error, dtype=float), np.asarray(effort, dtype=float)
    dot, pw = np.asarray(band_dot, dtype=float), np.asarray(band_power, dtype=float)
    if e2.ndim != 2 or not (e2.shape == ef.shape == dot.shape == pw.shape) or e2.shape[1] != np.size(groups):
        raise ValueError(f"sq_error, effort, band_dot and band_power must all be (levels, steps) with one group per "
                         f"step, got {e2.shape}, {ef.shape}, {dot.shape}, {pw.shape} and {np.size(groups)} groups")
    if not 0 < min_correlation <= 1 or not intent_power > 0:
        raise ValueError(f"need 0 < min_correlation <= 1 and intent_power > 0, got {min_correlation}, {intent_power}")
    levels, n = e2.shape
    _, sums = group_sums(np.concatenate([e2, ef, dot, pw]), groups)
    g_e2, g_ef, g_dot, g_pw = (sums[i * levels:(i + 1) * levels] for i in range(4))
    first = np.asarray(first, dtype=bool)
    if first.shape != (g_e2.shape[1],) or not first[0]:
        raise ValueError(f"first must be ({g_e2.shape[1]},) with the first group beginning a trial")
    p_e, p_t = prices.matrices(levels, wearer)
    if np.any(p_t < 0) or np.any(~np.isfinite(p_e)):
        raise ValueError("switch prices must be finite, the effort's >= 0")
    width = max(float(np.sum(g_ef.max(axis=0))), 1e-12) / bins
    shift, p_shift = np.floor(g_ef / width).astype(int), np.floor(p_t / width).astype(int)
    size = int(shift.max(axis=0).sum() + p_shift.max() * first.size) + 1
    ok = np.ones_like(g_e2, dtype=bool)
    root_y = min_correlation * np.sqrt(intent_power)
    s_lo, s_hi = float(g_pw.min(axis=0).sum()), float(g_pw.max(axis=0).sum())
    t_grid = np.geomspace(max(np.sqrt(s_lo), 1e-12), max(np.sqrt(s_hi), 2e-12), max(2, int(
        np.ceil(np.log(max(np.sqrt(s_hi / max(s_lo, 1e-30)), 1.0)) / np.log(np.sqrt(grid_ratio)))) + 1))
    scale = float(np.sum(np.ptp(g_e2, axis=0))) / max(float(np.sum(np.ptp(g_dot, axis=0))), 1e-30)
    cols = np.arange(g_e2.shape[1])[:, None]
    cap = max_effort * voluntary[0]
    best: PricedSchedule | None = None
    for t in t_grid:
        w = g_dot - root_y * g_pw / (2.0 * t)
        for lam in np.concatenate([[0.0], scale * np.geomspace(1e-3, 1e3, lambdas)]):
            dp, prev = chain_knapsack(g_e2 - lam * w, shift, ok, p_e, p_shift, first, size)
            reach = np.flatnonzero(np.isfinite(dp.min(axis=0)))
            a = _walk_back(dp, prev, shift, p_shift, first, reach)
            sw = (a[1:] != a[:-1]) & ~first[1:, None]
            m = (g_e2[a, cols].sum(0) + np.where(sw, p_e[a[:-1], a[1:]], 0.0).sum(0)) / n
            e = (g_ef[a, cols].sum(0) + np.where(sw, p_t[a[:-1], a[1:]], 0.0).sum(0)) / n
            s, x = g_pw[a, cols].sum(0), g_dot[a, cols].sum(0)
            rho = np.where(s > 0, x / np.sqrt(intent_power * np.maximum(s, 1e-300)), 0.0)
            for i in np.flatnonzero((rho >= min_correlation) & (e <= cap)):
                r = line_ratio(float(np.sqrt(max(m[i], 0.0))), float(e[i]), voluntary, reactive)
                if r is not None and (best is None or r < best.line_ratio):
                    best = PricedSchedule(a[:, i].copy(), float(m[i]), float(e[i]), r, float(rho[i]),
                                          int(sw[:, i].sum()))
    return best


def next_targets(target: float, cap: float, saw: float | None, effort: float, *, min_correlation: float = 0.6,
                 effort_cap: float = 0.75) -> tuple[float, float]:
    """The next round's stroke-correlation target and effort cap after a replay that sawed at ``saw`` (None: no
    cutting) with ``effort`` × the voluntary effort: the target raised by the shortfall below ``min_correlation``
    (+0.02, at most 1), the cap lowered by the excess over ``effort_cap`` (+0.01, at least 0.05)."""
    if saw is not None and saw < min_correlation:
        target = min(1.0, target + (min_correlation - saw) + 0.02)
    if effort > effort_cap:
        cap = max(0.05, cap - (effort - effort_cap) - 0.01)
    return target, cap
