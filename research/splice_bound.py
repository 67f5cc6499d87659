"""What any authority schedule could reach knowing the future: the splice bound (issue 28).

Given closed-loop runs of the same trials at constant authorities (``voluntary``, ``reactive``,
the constant mixtures), a schedule that gives each *group* of control steps (a segment of fixed
length, or a whole mode) one of those authorities is scored by splicing the runs' per-step
figures: with run l in group g,

    M = (1/N)·Σ_g Σ_{k∈g} e²_{l(g),k},    E = (1/N)·Σ_g Σ_{k∈g} θ_{l(g),k},

the mean squared tracking error [m²] and mean effort [rad] over the N steps. Splicing leaves out
what a switch costs (the wearer's reaction, the pick-up), so no schedule of those authorities
does better in the closed loop than the spliced figure: it is an optimistic bound.

:func:`splice_front` finds, for every reachable effort, the lowest M over all assignments (a
multiple-choice knapsack, solved exactly by dynamic programming over effort bins; efforts are
rounded *down* to their bin, so the front stays optimistic). :func:`best_line_ratio` reads off the
lowest line ratio RMS/RMS_line(E) (:mod:`mpcshare.line_ratio`) within an effort cap. Both are
checked against brute force over every assignment in ``tests/research``. No library
solves this small exact knapsack with the assignment recovered, so it is written here.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mpcshare.line_ratio import line_ratio

__all__ = ["SpliceFront", "assignments", "best_line_ratio", "effort_bins", "group_sums", "knapsack", "splice_front"]


@dataclass(frozen=True)
class SpliceFront:
    """The lowest mean squared error per effort bin.

    effort: (B,) mean effort [rad] of each reachable bin (a lower bound of the assignment's);
    mse: (B,) the lowest mean squared error [m²] there; :meth:`assignment` the run per group of
    that assignment.
    """

    effort: np.ndarray
    mse: np.ndarray
    bins: np.ndarray  # (B,) the DP's bin of each point
    picks: np.ndarray  # (G, reachable bins) the run taken for group g to reach each bin
    shift: np.ndarray  # (L, G) the bins run l's effort takes in group g

    def assignment(self, index: int) -> np.ndarray:
        """(G,) the run index per group (sorted labels) of the front's point ``index``."""
        return assignments(self.picks, self.shift, self.bins[index:index + 1])[:, 0]


def group_sums(values: np.ndarray, groups: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(the group labels (G,), per run and group the sum of ``values`` (L, N) over the group's steps (L, G))."""
    labels, idx = np.unique(np.asarray(groups), return_inverse=True)
    v = np.asarray(values, dtype=float)
    return labels, np.stack([np.bincount(idx, weights=row, minlength=labels.size) for row in v])


def splice_front(sq_error: np.ndarray, effort: np.ndarray, groups: np.ndarray, *,
                 allowed: np.ndarray | None = None, bins: int = 4000) -> SpliceFront:
    """The (effort, MSE) front over assignments of one run per group (module docstring).

    sq_error, effort: (L, N) per run and control step, e² [m²] and θ [rad]; groups: (N,) a label per
    step; allowed: (L, G) which runs a group may take (groups in sorted label order; None: all).
    ValueError on mismatched shapes, non-finite figures or a group with no allowed run.
    """
    e2, ef = np.asarray(sq_error, dtype=float), np.asarray(effort, dtype=float)
    if e2.ndim != 2 or e2.shape != ef.shape or e2.shape[1] != np.size(groups) or e2.shape[1] == 0:
        raise ValueError(f"sq_error and effort must both be (runs, steps) with one group per step, got "
                         f"{e2.shape}, {ef.shape} and {np.size(groups)} groups")
    if not (np.all(np.isfinite(e2)) and np.all(np.isfinite(ef)) and np.all(ef >= 0)):
        raise ValueError("sq_error and effort must be finite, effort >= 0")
    n, runs = e2.shape[1], e2.shape[0]
    _, sums = group_sums(np.concatenate([e2, ef]), groups)
    g_e2, g_ef = sums[:runs], sums[runs:]
    ok = np.ones_like(g_e2, dtype=bool) if allowed is None else np.asarray(allowed, dtype=bool)
    if ok.shape != g_e2.shape or not np.all(ok.any(axis=0)):
        raise ValueError(f"allowed must be (runs, groups) = {g_e2.shape} with a run allowed in every group")
    width, shift, size = effort_bins(g_ef, ok, bins)
    best, picks = knapsack(g_e2, shift, ok, size)
    reach = np.flatnonzero(np.isfinite(best))
    return SpliceFront(reach * width / n, best[reach] / n, reach, picks, shift)


def effort_bins(g_effort: np.ndarray, ok: np.ndarray, bins: int) -> tuple[float, np.ndarray, int]:
    """(bin width [rad·steps], per run and group the bins its effort takes (L, G), the number of bins) for
    ``bins`` bins up to the largest reachable summed effort; efforts are rounded down."""
    width = max(float(np.sum(np.max(np.where(ok, g_effort, 0.0), axis=0))), 1e-12) / bins
    shift = np.floor(g_effort / width).astype(int)
    return width, shift, int(np.sum(np.max(np.where(ok, shift, 0), axis=0))) + 1


def knapsack(cost: np.ndarray, shift: np.ndarray, ok: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """The multiple-choice knapsack: (per bin b < size the lowest Σ_g cost[l(g), g] over assignments with
    Σ_g shift[l(g), g] = b (inf where none) (size,), the run taken for group g to reach each bin (G, size)).

    cost, shift, ok: (L, G) per run and group the cost, the bins of effort and whether it is allowed."""
    best = np.full(size, np.inf)
    best[0] = 0.0
    picks = np.zeros((cost.shape[1], size), dtype=np.int16)
    for g in range(cost.shape[1]):
        new = np.full(size, np.inf)
        for run in np.flatnonzero(ok[:, g]):
            s = shift[run, g]
            cand = np.full(size, np.inf)
            cand[s:] = best[:size - s] + cost[run, g]
            better = cand < new
            new[better] = cand[better]
            picks[g, better] = run
        best = new
    return best, picks


def assignments(picks: np.ndarray, shift: np.ndarray, bins: np.ndarray) -> np.ndarray:
    """(G, B) the run per group of the knapsack's assignment reaching each of ``bins`` (B,)."""
    b = np.asarray(bins, dtype=int).copy()
    out = np.zeros((picks.shape[0], b.size), dtype=int)
    for g in range(picks.shape[0] - 1, -1, -1):  # walk back through the groups
        out[g] = run = picks[g, b].astype(int)
        b -= shift[run, g]
    return out


def best_line_ratio(front: SpliceFront, voluntary: tuple[float, float], reactive: tuple[float, float],
                    max_effort: float | None = 0.75) -> tuple[float | None, int | None]:
    """(the lowest line ratio on ``front`` with effort ≤ ``max_effort`` × the voluntary effort (None: no
    cap), the front's index of it); (None, None) where none qualifies.

    voluntary, reactive: (effort [rad], RMS [m]) of the two parties, the line's ends.
    """
    best, where = None, None
    cap = np.inf if max_effort is None else max_effort * voluntary[0]
    for i, (e, m) in enumerate(zip(front.effort, front.mse)):
        if e > cap:
            continue
        r = line_ratio(float(np.sqrt(m)), float(e), voluntary, reactive)
        if r is not None and (best is None or r < best):
            best, where = r, i
    return best, where
