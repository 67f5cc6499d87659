"""What a causal rule could reach, fitted in hindsight: an authority level per cell of what it observes (issue 28).

The splice searches (:mod:`~research.switch_priced`) choose an authority per second knowing
the future. A causal rule sees only the present: here a *table* T that gives every cell of an observed
feature (the controller's mode estimate; with it, the time in that mode, or the wearer's recent effort)
one level, the step's level l_k = T[cell_k]. Its figures are spliced from constant-level runs, with each
switch between consecutive steps of a trial priced (:func:`score_schedule`, the equations of
:mod:`~research.switch_priced` with a group per step). :func:`fit_table` finds the table with
the lowest line ratio within the effort cap whose knife saws, on the very steps it is scored on: first
every table constant over the second feature (whole modes, exhaustively), then single-cell changes
until none helps (coordinate descent). Fitted and scored on the same steps, it flatters the rule: if
even this misses a target, no rule that sees only these features meets it there. No library fits such a
table against a spliced, non-separable objective, so it is written here.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Callable

import numpy as np

from mpcshare.line_ratio import line_ratio
from research.switch_priced import SwitchPrices

__all__ = ["ScheduleScore", "TableFit", "fit_table", "score_schedule", "time_in_cell"]


@dataclass(frozen=True)
class ScheduleScore:
    """A per-step schedule's spliced figures: ``mse`` [m²], ``effort`` [rad], ``correlation`` (ρ), ``switches``
    and ``line_ratio`` (None: off the line)."""

    mse: float
    effort: float
    correlation: float
    switches: int
    line_ratio: float | None


def score_schedule(level: np.ndarray, sq_error: np.ndarray, effort: np.ndarray, band_dot: np.ndarray,
                   band_power: np.ndarray, intent_power: float, trial: np.ndarray, prices: SwitchPrices,
                   voluntary: tuple[float, float], reactive: tuple[float, float], wearer: int = 0) -> ScheduleScore:
    """The spliced figures of the level per step (N,) with a price per switch between consecutive steps of
    one trial (``trial`` (N,) its label per step); the other arrays (L, N) as in
    :func:`~research.switch_priced.priced_search`."""
    lv = np.asarray(level, dtype=int)
    trial = np.asarray(trial)
    if lv.ndim != 1 or lv.size != np.shape(sq_error)[1] or trial.shape != lv.shape:
        raise ValueError(f"level and trial must be (N,) with N = {np.shape(sq_error)[1]} steps, got {lv.shape} and "
                         f"{trial.shape}")
    if lv.min(initial=0) < 0 or lv.max(initial=0) >= np.shape(sq_error)[0]:
        raise ValueError(f"levels must lie in [0, {np.shape(sq_error)[0]}), got {lv.min()}..{lv.max()}")
    k, n = np.arange(lv.size), lv.size
    at = np.flatnonzero((lv[1:] != lv[:-1]) & (trial[1:] == trial[:-1])) + 1
    p_e, p_t = prices.matrices(np.shape(sq_error)[0], wearer)
    m = (float(np.asarray(sq_error)[lv, k].sum()) + float(p_e[lv[at - 1], lv[at]].sum())) / n
    e = (float(np.asarray(effort)[lv, k].sum()) + float(p_t[lv[at - 1], lv[at]].sum())) / n
    x, s = float(np.asarray(band_dot)[lv, k].sum()), float(np.asarray(band_power)[lv, k].sum())
    rho = x / np.sqrt(intent_power * s) if s > 0 and intent_power > 0 else 0.0
    return ScheduleScore(m, e, rho, int(at.size), line_ratio(float(np.sqrt(max(m, 0.0))), e, voluntary, reactive))


def time_in_cell(cell: np.ndarray, trial: np.ndarray, dt: float, edges_s: tuple[float, ...]) -> np.ndarray:
    """(N,) per step the bin of the time [s] since ``cell`` last changed (or its trial began) among ``edges_s``
    (ascending, the first 0): bin j holds edges_s[j] ≤ time < edges_s[j+1], the last bin has no end."""
    cell, trial = np.asarray(cell), np.asarray(trial)
    since = np.zeros(cell.size)
    for k in range(1, cell.size):
        since[k] = 0.0 if cell[k] != cell[k - 1] or trial[k] != trial[k - 1] else since[k - 1] + dt
    return np.searchsorted(np.asarray(edges_s, dtype=float), since, side="right") - 1


@dataclass(frozen=True)
class TableFit:
    """The fitted table (rows: the first feature's values, columns: the second's) and its score; ``whole``: the
    best table constant over the second feature (whole modes) and its score."""

    table: np.ndarray
    score: ScheduleScore
    whole: np.ndarray
    whole_score: ScheduleScore


def fit_table(first: np.ndarray, second: np.ndarray, score: Callable[[np.ndarray], ScheduleScore], levels: int, *,
              effort_cap: float, min_correlation: float, max_sweeps: int = 8) -> TableFit:
    """The table of the module docstring. ``first``, ``second``: (N,) non-negative integer features per step;
    ``score``: the level per step (N,) → :class:`ScheduleScore`; a table that misses the cap [rad] or the
    correlation is ranked behind every one that meets both, by how far it misses."""
    first, second = np.asarray(first, dtype=int), np.asarray(second, dtype=int)
    if first.shape != second.shape or first.ndim != 1 or first.min(initial=0) < 0 or second.min(initial=0) < 0:
        raise ValueError("first and second must be (N,) non-negative integer features of one length")
    rows, cols = first.max(initial=0) + 1, second.max(initial=0) + 1
    seen = np.unique(first)

    def rank(s: ScheduleScore) -> float:
        miss = max(s.effort / effort_cap - 1.0, 0.0) + max(min_correlation - s.correlation, 0.0)
        return (10.0 + miss) if miss > 0 or s.line_ratio is None else s.line_ratio

    best = None
    for whole in itertools.product(range(levels), repeat=seen.size):
        table = np.zeros((rows, cols), dtype=int)
        table[seen] = np.asarray(whole)[:, None]
        s = score(table[first, second])
        if best is None or rank(s) < rank(best[1]):
            best = (table, s)
    whole_table, whole_score = best
    table, current = whole_table.copy(), whole_score
    used = {(int(a), int(b)) for a, b in zip(first, second)}
    for _ in range(max_sweeps):
        improved = False
        for a, b in sorted(used):
            for lv in range(levels):
                if lv == table[a, b]:
                    continue
                old, table[a, b] = table[a, b], lv
                s = score(table[first, second])
                if rank(s) < rank(current) - 1e-12:
                    current, improved = s, True
                else:
                    table[a, b] = old
        if not improved:
            break
    return TableFit(table, current, whole_table, whole_score)
