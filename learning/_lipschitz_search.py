"""Exact branch-and-bound search of point-wise Lipschitz quotients in one group.

Per leaf A (rows of a k-d leaf in the feature space of ``_lipschitz_bounds``):

1. bound every leaf pair (A, B) by ``ub_AB ≥ ‖Δy‖/‖Δx‖`` from the boxes; visit
   the leaves B with ``ub_AB ≥ min_{i∈A} L_i`` in decreasing ``ub_AB``, where
   ``L_i`` is the best exact quotient found so far for point i (a lower bound
   of q_i, so pruning with ``ub < L_i`` never loses the maximiser);
2. for a chunk of such leaves, keep only the rows with ``L_i ≤ ub`` and screen
   all their pairs with one float32 product (``S_ij ≥ 0``; conservative by
   construction); when many survive, screen again with the full-dimensional
   float32 product, which is much tighter;
3. recompute the survivors exactly in float64 (``_lipschitz_exact``) and raise
   ``L``; the next chunk is screened against the raised bounds.

Rows of A are written only by the task of A, so leaves run in parallel threads
(numpy releases the GIL in products and ufuncs) and the result does not depend
on the schedule. ``Kernel`` isolates the array library: numpy here, torch in
``_lipschitz_torch``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ._lipschitz_bounds import Features, leaf_boxes, leaf_upper_ratios, row_features, thresholds
from ._lipschitz_exact import pair_ratios, update_best

__all__ = ["NumpyKernel", "SearchStats", "search_leaf", "LeafContext"]


@dataclass
class SearchStats:
    """Counters of one search (summed over leaves)."""

    pairs_screened: int = 0
    pairs_full_screened: int = 0
    pairs_exact: int = 0

    def add(self, other: "SearchStats") -> None:
        self.pairs_screened += other.pairs_screened
        self.pairs_full_screened += other.pairs_full_screened
        self.pairs_exact += other.pairs_exact


class NumpyKernel:
    """Screening and exact evaluation with numpy (float32 products via BLAS)."""

    chunk_elems = 1 << 20  # a·c elements screened at once (≈ 4 MB float32)

    def __init__(self, f: Features, X: np.ndarray, Y: np.ndarray) -> None:
        self.f, self.X, self.Y = f, X, Y

    def screen(self, rows: np.ndarray, T: np.ndarray, cols: np.ndarray, full: bool
               ) -> tuple[np.ndarray, np.ndarray]:
        """(row, col) positions (within rows/cols) of pairs with S ≥ 0."""
        f = self.f
        if full:
            R = row_features(f.ws[rows], f.nbx[rows], f.xs[rows], f.nx[rows], T)
            C = f.col_x[cols]
        else:
            R = row_features(f.ws[rows], f.nb[rows], f.zs[rows], f.na[rows], T)
            C = f.col_z[cols]
        S = R @ C.T
        return np.nonzero(S >= 0.0)

    def exact(self, gi: np.ndarray, gj: np.ndarray) -> np.ndarray:
        """Exact quotients of pairs given by *original* indices."""
        return pair_ratios(self.X, self.Y, gi, gj)


@dataclass
class LeafContext:
    """Everything a leaf task needs; q and partner are in leaf order."""

    f: Features
    kernel: object
    q: np.ndarray
    partner: np.ndarray
    full_fraction: float = 0.02  # survivors/screened above which the full-d screen pays off
    boxes: tuple = field(default=None)

    def __post_init__(self) -> None:
        if self.boxes is None:
            self.boxes = leaf_boxes(self.f)


def search_leaf(ctx: LeafContext, a: int) -> SearchStats:
    """Complete the quotients of the rows of leaf ``a`` (see module doc)."""
    f, q, partner, kern = ctx.f, ctx.q, ctx.partner, ctx.kernel
    st = SearchStats()
    s0, e0 = int(f.leaf_start[a]), int(f.leaf_start[a + 1])
    rows_all = np.arange(s0, e0)
    zlo, zhi, wlo, whi, zc = ctx.boxes
    ub = leaf_upper_ratios(a, zlo, zhi, wlo, whi, f.delta_z, f.delta_y)
    Lmin = q[s0:e0].min()
    cand = np.nonzero(ub >= Lmin)[0]
    if len(cand) == 0:
        return st
    # Decreasing bound, then nearest centroid first (tightens L early).
    dc = ((zc[cand] - zc[a]) ** 2).sum(axis=1)
    cand = cand[np.lexsort((dc, -ub[cand]))]
    cub = ub[cand]
    sizes = np.diff(f.leaf_start)[cand]
    use_z = True
    pos = 0
    seen = 0
    nc = len(cand)
    while pos < nc:
        L = q[s0:e0]
        top = cub[pos]
        active = rows_all[L <= top]
        if len(active) == 0:
            break
        Lmin = q[active].min()
        # Take leaves while their bound still reaches the weakest active row.
        # Geometric growth (at most the columns already seen): bounds tighten early.
        budget = max(min(kern.chunk_elems // len(active), seen), int(sizes[pos]))
        end = pos
        taken = 0
        while end < nc and taken < budget and cub[end] >= Lmin:
            taken += int(sizes[end])
            end += 1
        if end == pos:
            break
        leaves = cand[pos:end]
        pos = end
        seen += taken
        cols = np.concatenate([np.arange(f.leaf_start[b], f.leaf_start[b + 1]) for b in leaves])
        T = thresholds(q[active], f.scale_x, f.scale_y)
        full_direct = (not use_z) and f.xs is not None
        ri, cj = kern.screen(active, T, cols, full_direct)
        st.pairs_screened += len(active) * len(cols)
        if (not full_direct and f.xs is not None
                and len(ri) > ctx.full_fraction * len(active) * len(cols)):
            # Many survivors: the tight full-dimensional screen is cheaper than exact work.
            ur, ri_inv = np.unique(ri, return_inverse=True)
            uc, cj_inv = np.unique(cj, return_inverse=True)
            r2, c2 = kern.screen(active[ur], T[ur], cols[uc], True)
            st.pairs_full_screened += len(ur) * len(uc)
            if len(ri) > 0.3 * len(active) * len(cols):
                use_z = False  # z bound is useless here (i.i.d.-like data): go full-d directly
            ri, cj = ur[r2], uc[c2]
        if len(ri) == 0:
            continue
        gi = active[ri]
        gj = cols[cj]
        r = kern.exact(f.perm[gi], f.perm[gj])
        st.pairs_exact += len(r)
        update_best(q, partner, gi, f.perm[gj], r)
    return st
