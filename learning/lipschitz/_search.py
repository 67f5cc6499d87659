"""Exact branch-and-bound search of point-wise Lipschitz quotients q_i = max_j ‖Δy‖/‖Δx‖ in one group.

Every search keeps a lower bound L_i ≤ q_i per point (an exact quotient found so far) and discards
a pair only when a conservative float32 bound (``_bounds``) proves its ratio below the bound it is
screened against, so the maximiser is never lost; survivors are recomputed exactly in float64
(``_exact``, ``_compiled``) and raise L.

* Symmetric (``SearchOptions(search="symmetric")``, the default): :func:`warm_leaf` raises each
  k-d leaf's bounds against its nearest leaves and a sample spread over the group
  (:func:`spread_sample`); :func:`symmetric_pass` then screens every unordered pair once against
  min(T_i, T_j), rows in ascending bound, and credits a survivor to both points. A chunk whose
  one-product z screen keeps too much is screened again with the full-dimensional bound
  (:class:`ChunkScreen`).
* Per leaf (``search="per_leaf"``, the reference the symmetric pass is tested against, and the
  warm-up of groups without full-d features): :func:`search_leaf` visits, for leaf A, the leaves B
  with box bound ub_AB ≥ min_{i∈A} L_i in decreasing ub_AB, screening chunks against the raised L.

Rows of a leaf or tile are written only by its own task, so tasks run in threads (numpy releases
the GIL) and the result does not depend on the schedule. Kernels: numpy ``_kernel``, torch ``_torch``.
Why no tile-level bounds, and the measured defaults: docs/results.md, "Benchmarks".
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field

import numpy as np

from ._bounds import (
    Features,
    leaf_boxes,
    leaf_upper_ratios,
    threshold_scalar,
    thresholds,
)
from ._exact import update_best

__all__ = [
    "ChunkScreen",
    "LeafContext",
    "PairCounters",
    "nearest_leaves",
    "run_tiles",
    "search_leaf",
    "spread_sample",
    "symmetric_pass",
    "warm_leaf",
]


@dataclass
class PairCounters:
    """Counters of one search (summed over leaves)."""

    pairs_screened: int = 0
    pairs_full_screened: int = 0
    pairs_exact: int = 0

    def add(self, other: PairCounters) -> None:
        self.pairs_screened += other.pairs_screened
        self.pairs_full_screened += other.pairs_full_screened
        self.pairs_exact += other.pairs_exact


@dataclass
class LeafContext:
    """Everything a leaf task needs; q and partner are in leaf order."""

    f: Features
    kernel: object
    q: np.ndarray
    partner: np.ndarray
    full_fraction: float = 0.005  # survivors/screened above which the full-d screen pays off
    boxes: tuple = field(default=None)
    lb: np.ndarray | None = None  # shared lower bounds of q (leaf order), ≥ q, ≤ true q


    def __post_init__(self) -> None:
        if self.boxes is None:
            self.boxes = leaf_boxes(self.f)


def nearest_leaves(ctx: LeafContext, a: int, m: int) -> np.ndarray:
    """The ``m`` leaves whose z centroids are nearest to that of leaf ``a`` (a first), nearest first."""
    zc = ctx.boxes[4]
    dc = ((zc - zc[a]) ** 2).sum(axis=1)
    m = min(m, len(dc))
    near = np.argpartition(dc, m - 1)[:m] if m < len(dc) else np.arange(len(dc))
    return near[np.lexsort((near, dc[near]))]


def _leaf_candidates(ctx: LeafContext, a: int, L: np.ndarray, leaves: np.ndarray | None
                     ) -> tuple[np.ndarray, np.ndarray]:
    """(leaves to search, their upper bounds on the quotient): every leaf whose box bound reaches
    min L, by decreasing bound then nearest centroid first (tightens L early); or ``leaves`` as
    given, unbounded (the warm-up)."""
    if leaves is not None:
        cand = np.asarray(leaves)
        return cand, np.full(len(cand), np.inf)
    f = ctx.f
    zlo, zhi, wlo, whi, zc = ctx.boxes
    ub = leaf_upper_ratios(a, zlo, zhi, wlo, whi, f.delta_z, f.delta_y)
    cand = np.nonzero(ub >= L.min())[0]
    dc = ((zc[cand] - zc[a]) ** 2).sum(axis=1)
    cand = cand[np.lexsort((dc, -ub[cand]))]
    return cand, ub[cand]


def search_leaf(ctx: LeafContext, a: int, leaves: np.ndarray | None = None) -> PairCounters:
    """Complete the quotients of the rows of leaf ``a`` (see module doc).

    With ``leaves`` given, only those leaves are searched, in that order (a
    warm-up that raises the lower bounds; q stays the exact maximum over the
    pairs evaluated). Lower bounds found on the way go to ``ctx.lb`` if set.
    """
    f, q, partner, kern = ctx.f, ctx.q, ctx.partner, ctx.kernel
    st = PairCounters()
    s0, e0 = int(f.leaf_start[a]), int(f.leaf_start[a + 1])
    rows_all = np.arange(s0, e0)
    # Local lower bounds: ≥ the exact maxima found so far, ≤ the true q_i.
    L = q[s0:e0].copy()
    if ctx.lb is not None:
        np.maximum(L, ctx.lb[s0:e0], out=L)
    cand, cub = _leaf_candidates(ctx, a, L, leaves)
    if len(cand) == 0 and leaves is None:
        return st
    sizes = np.diff(f.leaf_start)[cand]
    has_full = f.xs is not None
    use_z = True
    pos = seen = 0
    nc = len(cand)
    while pos < nc:
        top = cub[pos]
        act = np.flatnonzero(L <= top)
        if len(act) == 0:
            break
        Lmin = L[act].min()
        # Geometric growth (at most the columns already seen): bounds tighten early.
        budget = max(min(kern.chunk_elems // len(act), seen), int(sizes[pos]))
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
        n_ac = len(act) * len(cols)
        full = has_full and not use_z
        T = thresholds(L[act], f.scale_x, f.scale_y)
        ri, cj = kern.screen(rows_all[act], T, cols, full)
        if full:
            st.pairs_full_screened += n_ac
        else:
            st.pairs_screened += n_ac
        if has_full and len(ri) > ctx.full_fraction * n_ac:
            # Many survivors: full-d two-sided bounds are cheaper than exact work,
            # and they raise L without exact evaluation.
            if not full and len(ri) > 0.3 * n_ac and seen > taken:
                use_z = False  # z bound is useless here (i.i.d.-like data)
            ur = np.unique(ri)
            uc = np.unique(cj)
            r2, c2, Lr = kern.tight(rows_all[act[ur]], cols[uc], L[act[ur]])
            L[act[ur]] = Lr
            st.pairs_full_screened += len(ur) * len(uc)
            ri, cj = ur[r2], uc[c2]
        if len(ri) == 0:
            continue
        gi = rows_all[act[ri]]
        gj = cols[cj]
        r = kern.exact(f.perm[gi], f.perm[gj])
        st.pairs_exact += len(r)
        update_best(q, partner, gi, f.perm[gj], r)
        np.maximum(L, q[s0:e0], out=L)
    if ctx.lb is not None:
        np.maximum(ctx.lb[s0:e0], L, out=ctx.lb[s0:e0])
    return st


def warm_leaf(ctx: LeafContext, a: int, m: int = 1, extra: np.ndarray | None = None) -> PairCounters:
    """Raise the lower bounds ``ctx.lb`` of leaf ``a``'s rows from its ``m`` nearest leaves
    and the points ``extra`` (leaf-order positions; a sample spread over the whole group).

    Only the full-dimensional two-sided float32 bounds are used (no exact
    evaluation): max_j sqrt(lb‖Δy‖²/ub‖Δx‖²) is a provable lower bound of q_i,
    and the symmetric pass evaluates every pair that matters exactly anyway.
    """
    f, lb = ctx.f, ctx.lb
    st = PairCounters()
    rows = np.arange(f.leaf_start[a], f.leaf_start[a + 1])
    near = nearest_leaves(ctx, a, m) if m > 1 else np.array([a])
    cols = np.concatenate([np.arange(f.leaf_start[b], f.leaf_start[b + 1]) for b in near]
                          + ([] if extra is None else [extra]))
    _, _, Lr, _ = ctx.kernel.sym_tight(rows, cols, lb[rows], lb[cols], None)
    np.maximum(lb[rows], Lr, out=Lr)
    lb[rows] = Lr  # rows of leaf a are written only by this task
    st.pairs_full_screened += len(rows) * len(cols)
    return st


def spread_sample(n: int, k: int, seed: int = 0) -> np.ndarray:
    """``k`` distinct positions out of ``n`` (sorted, seeded): the far partners of the warm-up.

    The point attaining q_i is often far from x_i, out of reach of the nearest leaves; many
    distant pairs then have quotients close to q_i, and a sample finds one (how far:
    docs/results.md, "Benchmarks").
    """
    if k <= 0:
        return np.zeros(0, dtype=np.int64)
    return np.sort(np.random.default_rng(seed).choice(n, min(k, n), replace=False))


def symmetric_pass(ctx: LeafContext, pool, bar=None, tile: int = 256, chunk: int = 2048,
                   batch: int = 2048, sym_full_fraction: float = 0.02) -> PairCounters:
    """Screen every unordered pair once, crediting a surviving pair to both points.

    Orientation: a pair (i, j) cannot reach q_i nor q_j when
    ``ub‖Δy‖² < min(T_i, T_j)·lb‖Δx‖²`` (T ≤ L² of the point; pruning with the
    smaller threshold is conservative for both). The points are sorted by their
    lower bound ``ctx.lb`` (ascending) and cut into row tiles; tile A is screened
    against itself (a full square with each row's own threshold; both orders of
    each pair are seen) and against every later point, with the row thresholds
    ``min(T_i, min_{j in chunk} T_j)`` — since later points have larger bounds
    this is nearly always T_i. Survivors are recomputed exactly and update both
    points under a lock (the other thread may own either point); thresholds are
    re-read from the shared bounds before every chunk, so they only tighten.
    The set of maxima does not depend on the schedule: every pair that attains
    q_i survives whatever the bounds were (see ``_bounds``), so q and the
    partner (smallest index among the maximisers) are the same as the one-sided search.
    """
    n = len(ctx.f.perm)
    tiles = _SymmetricTiles(ctx, tile, chunk, batch, sym_full_fraction)
    return run_tiles(tiles.task, n, tile, pool, bar, ctx.kernel)


class _SymmetricTiles:
    """The tile tasks of :func:`symmetric_pass` and the state they share (the pass order, the lock
    under which survivors update q, partner and the lower bounds of both points)."""

    def __init__(self, ctx: LeafContext, tile: int, chunk: int, batch: int, full_fraction: float) -> None:
        self.ctx, self.tile, self.chunk, self.batch, self.full_fraction = ctx, tile, chunk, batch, full_fraction
        self.n = len(ctx.f.perm)
        self.order = np.argsort(ctx.lb, kind="stable")
        ctx.kernel.sym_prepare(self.order)
        self.lock = threading.Lock()

    def raise_lb(self, idx: np.ndarray, L: np.ndarray) -> None:
        lb = self.ctx.lb
        with self.lock:
            lb[idx] = np.maximum(lb[idx], L)

    def credit(self, gi: np.ndarray, gj: np.ndarray, r: np.ndarray, both: bool) -> None:
        """Exact quotients r of pairs (gi, gj) to q and partner of gi (and of gj where ``both``)."""
        c = self.ctx
        with self.lock:
            update_best(c.q, c.partner, gi, c.f.perm[gj], r)
            if both:
                update_best(c.q, c.partner, gj, c.f.perm[gi], r)
            c.lb[gi] = np.maximum(c.lb[gi], c.q[gi])
            if both:
                c.lb[gj] = np.maximum(c.lb[gj], c.q[gj])

    def flush(self, pend: list, st: PairCounters) -> None:
        """Survivors evaluated in batches (per-call overhead), then credited; ``pend`` emptied."""
        for diag in (True, False):
            sel = [(gi, gj, pi, pj) for gi, gj, dg, pi, pj in pend if dg == diag]
            if not sel:
                continue
            gi = np.concatenate([a[0] for a in sel])
            gj = np.concatenate([a[1] for a in sel])
            # exact quotients by pass positions: the data in pass order (cache-friendly)
            r = self.ctx.kernel.sym_exact(np.concatenate([a[2] for a in sel]), np.concatenate([a[3] for a in sel]))
            st.pairs_exact += len(r)
            self.credit(gi, gj, r, not diag)
        pend.clear()

    def task(self, s: int) -> tuple[PairCounters, int]:
        """Row tile [s, s + tile) of the pass order against itself and every later point."""
        f, kern, lb, order, n = self.ctx.f, self.ctx.kernel, self.ctx.lb, self.order, self.n
        st = PairCounters()
        e = min(s + self.tile, n)
        rows = order[s:e]
        spans = [(s, e)] + [(c0, min(c0 + self.chunk, n)) for c0 in range(e, n, self.chunk)]
        pend: list[tuple[np.ndarray, np.ndarray, bool, np.ndarray, np.ndarray]] = []
        n_pend = 0
        screen = ChunkScreen(kern, f.xs is not None, self.full_fraction)
        for c0, c1 in spans:
            diag = c0 == s
            cols = order[c0:c1]
            n_ac = (e - s) * (c1 - c0)
            ri, cj, chunk_full = screen.z_screen(s, e, c0, c1, lb[rows], lb[cols], f.scale_x, f.scale_y, st)
            if chunk_full:
                ri, cj, Lr, Lc = kern.sym_tight(rows, cols, lb[rows], lb[cols], None if diag else np.inf)
                st.pairs_full_screened += n_ac
                self.raise_lb(rows, Lr)
                if not diag:
                    self.raise_lb(cols, Lc)
            if len(ri) == 0:
                continue
            pend.append((rows[ri], order[c0 + cj], diag, s + ri, c0 + cj))
            n_pend += len(ri)
            if n_pend >= self.batch:
                self.flush(pend, st)
                n_pend = 0
        self.flush(pend, st)
        return st, (e - s) * (e - s - 1) // 2 + (e - s) * (n - e)


class ChunkScreen:
    """The screen of one chunk of a tile's columns in a pass (``symmetric_pass``, ``_multi``).

    The z screen or the full-d screen is chosen per chunk, not once for all tiles (the first
    chunks of a tile, points of nearby bound that lie close by, can keep many pairs where later
    chunks keep almost none). A chunk whose z screen keeps more than ``full_fraction`` is
    screened again with the full-d screen, which is cheaper than evaluating that many pairs
    exactly; after two such chunks in a row off the diagonal (i.i.d.-like rows) the rest of
    the tile skips the z screen. One object per tile task, so the counters do not depend on
    the thread schedule. Costs behind the threshold: docs/results.md, "Benchmarks".
    """

    def __init__(self, kern, has_full: bool, full_fraction: float) -> None:
        self.kern, self.has_full, self.full_fraction = kern, has_full, full_fraction
        self.tile_full = False
        self.n_full = 0  # consecutive chunks of this tile that needed the full-d screen

    def z_screen(self, s: int, e: int, c0: int, c1: int, row_lb: np.ndarray, col_lb: np.ndarray,
                 sx: float, sy: float, st: PairCounters) -> tuple[np.ndarray | None, np.ndarray | None, bool]:
        """Survivors (positions in rows [s, e) × columns [c0, c1) of the pass order) of the
        z screen against the rows' lower bounds (capped by the columns' smallest off the
        diagonal), and whether the chunk needs the full-d screen (then the survivors are
        to be replaced; ``None`` when the z screen was skipped)."""
        if self.tile_full:
            return None, None, True
        diag = c0 == s
        n_ac = (e - s) * (c1 - c0)
        T = thresholds(row_lb, sx, sy)
        if not diag:
            np.minimum(T, threshold_scalar(col_lb.min(), sx, sy), out=T)
        ri, cj = self.kern.sym_screen(s, e, T, c0, c1)
        st.pairs_screened += n_ac
        if self.has_full and len(ri) > self.full_fraction * n_ac and n_ac >= 1 << 16:
            self.n_full += 1
            self.tile_full = self.n_full >= 2 and not diag  # twice off the diagonal: i.i.d.-like rows
            return ri, cj, True
        if not diag:
            self.n_full = 0
        return ri, cj, False


def run_tiles(task, n: int, tile: int, pool, bar, kern) -> PairCounters:
    """Run ``task(s)`` for the row tiles s = 0, tile, 2·tile, … < n (in ``pool`` if given),
    sum their counters, advance ``bar`` by each tile's pairs, and release the kernel's
    pass-order copies (``kern.sym_release``) whatever happens."""
    total = PairCounters()
    starts = list(range(0, n, tile))
    try:
        results = map(task, starts) if pool is None else pool.map(task, starts)
        for st, work in results:
            total.add(st)
            if bar is not None:
                bar.update(work)
    finally:
        kern.sym_release()
    return total
