"""Exact float64 Lipschitz quotients of explicit pairs, and the running maximum.

For a pair (i, j) the quotient is ``r_ij = ‖y_i − y_j‖ / ‖x_i − x_j‖`` (Euclidean,
units of y per unit of x), computed by direct differences in float64 — never by
the ``‖a‖² + ‖b‖² − 2a·b`` expansion, which cancels for close pairs. Conventions
(docs/design.md): a pair identical in x and in y carries no evidence and is skipped
(returned as NaN here); identical x with different y gives ``inf``.

The running maximum keeps, per point, the largest quotient seen and the
*smallest* original index j that attains it, so the partner is well defined and
independent of the order in which pairs are visited.
"""

from __future__ import annotations

import numpy as np

from ._compiled import pair_ratios_compiled, update_best_compiled

__all__ = ["dense_exact", "pair_norms", "pair_ratios", "update_best"]

_PAIR_CHUNK = 1 << 15  # pairs per gather; bounds temporary memory to chunk·d·8 B
_TINY = 1e-150  # below/above these the sum of squares may under/overflow
_HUGE = 1e150


def pair_norms(A: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """``‖A[i] − A[j]‖₂`` per pair, float64, by direct differences.

    Sums of squares that may have under- or overflowed are recomputed with the
    scaled ``hypot`` reduction, so the result is accurate over the full range.
    """
    out = np.empty(len(i), dtype=np.float64)
    for s in range(0, len(i), _PAIR_CHUNK):
        e = min(s + _PAIR_CHUNK, len(i))
        diff = A[i[s:e]] - A[j[s:e]]
        nrm = np.sqrt(np.einsum("ij,ij->i", diff, diff))
        bad = (nrm < _TINY) | (nrm > _HUGE)
        if bad.any():
            # Scaled accumulation; rare (near-identical or astronomically far pairs).
            nrm[bad] = np.hypot.reduce(diff[bad], axis=1) if diff.shape[1] else 0.0
        out[s:e] = nrm
    return out


def pair_ratios(X: np.ndarray, Y: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Exact quotients ``‖Y[i]−Y[j]‖ / ‖X[i]−X[j]‖`` with the conventions above.

    Returns NaN for skipped pairs (identical in x and y, including i == j) and
    ``inf`` for identical x with different y. Evaluated by the compiled loop of
    ``_compiled`` (direct differences in a fixed summation order), so a pair has the
    same quotient, bit for bit, wherever the engine evaluates it.
    """
    X = np.ascontiguousarray(X, dtype=np.float64)
    Y = np.ascontiguousarray(Y, dtype=np.float64)
    return pair_ratios_compiled(X, Y, i, j)


def update_best(q: np.ndarray, partner: np.ndarray, rows: np.ndarray, cols_orig: np.ndarray,
                r: np.ndarray) -> None:
    """In-place ``q[rows] = max(q[rows], r)`` with the partner of the maximum.

    ``rows`` index ``q``/``partner``; ``cols_orig`` are the partners' original
    indices. Ties keep the smallest original index; NaN (skipped) pairs and
    quotients of 0 never set a partner (a point whose best quotient is 0 has
    partner -1).
    """
    update_best_compiled(q, partner, rows, cols_orig, r)


def dense_exact(X: np.ndarray, Y: np.ndarray, idx: np.ndarray, q: np.ndarray,
                partner: np.ndarray, row_block: int = 64) -> None:
    """All pairs among the points ``idx`` (original indices), exactly; updates q, partner.

    O(n²·d) time, O(row_block·n·d) memory. Used for small groups.
    """
    n = len(idx)
    if n < 2:
        return
    cols = np.tile(idx, 1)
    for s in range(0, n, row_block):
        e = min(s + row_block, n)
        ri = np.repeat(idx[s:e], n)
        cj = np.tile(cols, e - s)
        r = pair_ratios(X, Y, ri, cj)
        update_best(q, partner, ri, cj, r)
