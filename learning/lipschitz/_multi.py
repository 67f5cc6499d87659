"""Quotients of many labelings of the same points in one pass over the pairs.

For labelings g¹ … gᴸ of the same N points (L × N labels),

    Q[l, i] = max_{j ≠ i, gˡ_j = gˡ_i} ‖y_i − y_j‖ / ‖x_i − x_j‖      [units of y per unit of x]

is, for every l, exactly what ``pointwise_quotients(X, Y, groups=gˡ)`` returns (same bits, same
partner: the smallest index on ties), but every unordered pair is screened once for all
labelings: a pair is kept when its float32 bound reaches the smallest current lower bound
``t_i = min_l Q[l, i]`` of either point, recomputed exactly once (``_compiled``) and credited to
every labeling in which both points share a group. The bounds are those of the symmetric pass
(``_search.symmetric_pass``); a pair that attains Q[l, i] has ratio ≥ Q[l, i] ≥ t_i, so it
survives whatever the bounds were.

It pays for labelings whose quotients are alike (random groupings of equal sizes with no
grouping); a labeling whose quotients are far below the others' (task modes, a clustering)
lowers t_i for all and should get its own ``pointwise_quotients`` call (measured:
docs/results.md, "Benchmarks"). Labelings that are not (L, N) with L ≥ 1 raise ``ValueError``.
"""

from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np

from ._bounds import Features, leaf_boxes, threshold_scalar, thresholds
from ._compiled import credit_multi, grouped_lower_ratios, grouped_survivors
from ._search import ChunkScreen, PairCounters, run_tiles, spread_sample

__all__ = ["check_labelings", "multi_pass", "pointwise_quotients_multi", "time_neighbour_pairs"]


def check_labelings(labelings, n: int) -> np.ndarray:
    """(L, N) labels → point-major (N, L) int64 codes 0…(groups − 1) per labeling; clear errors."""
    lab = np.asarray(labelings)
    if lab.ndim == 1:
        lab = lab[None, :]
    if lab.ndim != 2:
        raise ValueError(f"labelings must be (n_labelings, N) = (L, {n}), got shape {lab.shape}")
    if lab.shape[1] != n:
        raise ValueError(f"labelings must be (n_labelings, N) = (L, {n}): X has {n} rows, "
                         f"got shape {lab.shape}")
    if lab.shape[0] == 0:
        raise ValueError(f"labelings is empty (shape {lab.shape}); pass at least one labeling")
    if lab.dtype.kind == "f":
        bad = ~np.isfinite(lab)
        if bad.any():
            m, i = np.argwhere(bad)[0]
            raise ValueError(f"labelings contains NaN or inf at labeling {m}, row {i}")
    codes = np.empty((lab.shape[1], lab.shape[0]), dtype=np.int64)
    for m in range(lab.shape[0]):
        codes[:, m] = np.unique(lab[m], return_inverse=True)[1].reshape(-1)
    return codes


def time_neighbour_pairs(labels: np.ndarray, lags: int) -> tuple[np.ndarray, np.ndarray]:
    """Unique pairs (i < j) of rows k and k + s (s = 1 … lags) of each group of each
    labeling: cheap, strong initial bounds on windowed time series."""
    n, L = labels.shape
    keys = []
    for m in range(L):
        order = np.argsort(labels[:, m], kind="stable")
        g = labels[order, m]
        for s in range(1, min(lags, n - 1) + 1):
            same = g[:-s] == g[s:]
            a, b = order[:-s][same], order[s:][same]
            keys.append(np.minimum(a, b) * n + np.maximum(a, b))
    if not keys:
        return np.zeros(0, np.int64), np.zeros(0, np.int64)
    # sort and drop repeats (np.unique hashes int64 keys: 3.35 s against 0.32 s for 21
    # labelings of 107k rows, measured)
    k = np.concatenate(keys)
    k.sort()
    if len(k):
        k = k[np.concatenate(([True], k[1:] != k[:-1]))]
    return k // n, k % n


def grouped_screen(f: Features, kern, rows: np.ndarray, cols: np.ndarray, lab_r: np.ndarray,
                   lab_c: np.ndarray, LBr: np.ndarray, LBc: np.ndarray, cap: bool
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Full-dimensional two-sided float32 screen of rows × cols (leaf-order positions) for
    many labelings: raises the lower bounds LBr (a, L), LBc (c, L) of each labeling by
    max sqrt(lb‖Δy‖² / ub‖Δx‖²) over the pairs sharing its group (provable lower bounds of
    Q, no exact work), then returns the survivors of ``ub‖Δy‖² ≥ T_i·lb‖Δx‖²`` with
    T_i from min_l LBr[i, l] (capped by the smallest column bound when ``cap``), and the
    raised bounds."""
    G, Gy, LBr, LBc = _grouped_bounds(f, kern, rows, cols, lab_r, lab_c, LBr, LBc)
    T = thresholds(LBr.min(axis=1), f.scale_x, f.scale_y)
    if cap:
        np.minimum(T, threshold_scalar(LBc.min(), f.scale_x, f.scale_y), out=T)
    k = (f.scale_y / f.scale_x) ** 2 * (1.0 - 2.0 ** -20)  # as ``thresholds``, rounded down
    with np.errstate(over="ignore"):
        Tr, Tc = LBr * LBr * k, LBc * LBc * k
    ri, cj = grouped_survivors(G, Gy, f.nx_lo[rows], f.nx_lo[cols], f.nw_hi[rows], f.nw_hi[cols],
                               T, Tr, Tc, lab_r, lab_c)
    return ri, cj, LBr, LBc


def warm_bounds(f: Features, kern, labels: np.ndarray, LB: np.ndarray, pool, m: int = 8,
                extra: np.ndarray | None = None) -> int:
    """Raise the lower bounds LB (N, L, original order) of every labeling from each leaf's
    ``m`` nearest leaves and the points ``extra`` (leaf-order positions, a sample spread
    over all points: ``_search.spread_sample``), with ``grouped_screen``'s bounds, both
    sides; returns the pairs screened."""
    zc = leaf_boxes(f)[4]
    n_leaves = len(f.leaf_start) - 1
    lock = threading.Lock()

    def task(a: int) -> int:
        dc = ((zc - zc[a]) ** 2).sum(axis=1)
        k = min(m, n_leaves)
        near = np.argpartition(dc, k - 1)[:k] if k < n_leaves else np.arange(n_leaves)
        rows = np.arange(f.leaf_start[a], f.leaf_start[a + 1])
        cols = np.concatenate([np.arange(f.leaf_start[b], f.leaf_start[b + 1]) for b in near]
                              + ([] if extra is None else [extra]))
        pr, pc = f.perm[rows], f.perm[cols]
        _, _, LBr, LBc = _grouped_bounds(f, kern, rows, cols, labels[pr], labels[pc], LB[pr], LB[pc])
        with lock:
            LB[pr] = np.maximum(LB[pr], LBr)
            LB[pc] = np.maximum(LB[pc], LBc)
        return len(rows) * len(cols)

    run = map if pool is None else pool.map
    return sum(run(task, range(n_leaves)))


def _grouped_bounds(f: Features, kern, rows, cols, lab_r, lab_c, LBr, LBc):
    """Gram matrices of rows × cols and the raised bounds (see ``grouped_screen``)."""
    G, Gy = kern._grams(rows, cols)
    conv = f.scale_x / f.scale_y
    with np.errstate(over="ignore"):
        Tr = (LBr / conv) ** 2
        Tc = (LBc / conv) ** 2
    Br, Bc = grouped_lower_ratios(G, Gy, f.nx_hi[rows], f.nx_hi[cols], f.nw_lo[rows], f.nw_lo[cols],
                                  lab_r, lab_c, Tr, Tc)
    lift = conv * (1.0 - 1e-5)  # float32 slack, as the single-labeling search
    return (G, Gy, np.maximum(LBr, np.sqrt(np.maximum(Br, 0.0)) * lift),
            np.maximum(LBc, np.sqrt(np.maximum(Bc, 0.0)) * lift))


def multi_pass(f: Features, kern, labels: np.ndarray, Q: np.ndarray, P: np.ndarray, LB: np.ndarray,
               qmin: np.ndarray, pool, bar=None, tile: int = 256, chunk: int = 4096, batch: int = 4096,
               sym_full_fraction: float = 0.02) -> PairCounters:
    """Screen every unordered pair once against the smallest lower bound of either point
    over all labelings; evaluate survivors exactly and credit them to every labeling in
    which both points share a group (see module doc). Q, P: point-major (N, L) in original
    order, updated in place; LB (N, L): lower bounds of Q (≥ Q), raised as the pass goes.
    Updates are made under a lock (a pair's two points may belong to two threads).

    Rows are taken in ascending ``t = min_l LB`` (leaf-order positions, cut into tiles);
    a tile is screened against itself and all later points with thresholds re-read
    before every chunk, so they only tighten. Where the low-dimensional screen keeps more
    than ``sym_full_fraction`` of a chunk, the chunk is screened again with the full-d
    screen (``grouped_screen``), which also raises every labeling's bounds.
    """
    n = len(f.perm)
    perm = f.perm
    np.maximum(LB, Q, out=LB)
    tmin = LB.min(axis=1)  # original order
    order = np.argsort(tmin[perm], kind="stable")
    kern.sym_prepare(order)
    lock = threading.Lock()
    sx, sy = f.scale_x, f.scale_y
    has_full = f.xs is not None

    def credit(oi: np.ndarray, oj: np.ndarray, r: np.ndarray) -> None:
        with lock:
            credit_multi(Q, P, LB, tmin, qmin, labels, oi, oj, r)

    def raise_lb(pts: np.ndarray, B: np.ndarray) -> None:
        with lock:
            LB[pts] = np.maximum(LB[pts], B)
            tmin[pts] = LB[pts].min(axis=1)

    def task(s: int) -> tuple[PairCounters, int]:
        st = PairCounters()
        e = min(s + tile, n)
        rows = order[s:e]
        pr = perm[rows]
        spans = [(s, e)] + [(c0, min(c0 + chunk, n)) for c0 in range(e, n, chunk)]
        pend: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
        n_pend = 0
        screen = ChunkScreen(kern, has_full, sym_full_fraction)

        def flush() -> None:
            if not pend:
                return
            oi = perm[np.concatenate([a[0] for a in pend])]
            oj = perm[np.concatenate([a[1] for a in pend])]
            r = kern.sym_exact(np.concatenate([a[2] for a in pend]), np.concatenate([a[3] for a in pend]))
            st.pairs_exact += len(r)
            credit(oi, oj, r)
            pend.clear()

        for c0, c1 in spans:
            diag = c0 == s
            cols = order[c0:c1]
            pc = perm[cols]
            n_ac = (e - s) * (c1 - c0)
            ri, cj, chunk_full = screen.z_screen(s, e, c0, c1, tmin[pr], tmin[pc], sx, sy, st)
            if chunk_full:
                ri, cj, Br, Bc = grouped_screen(f, kern, rows, cols, labels[pr], labels[pc],
                                                LB[pr], LB[pc], cap=not diag)
                st.pairs_full_screened += n_ac
                raise_lb(pr, Br)
                if not diag:
                    raise_lb(pc, Bc)
            if len(ri) == 0:
                continue
            pend.append((rows[ri], order[c0 + cj], s + ri, c0 + cj))
            n_pend += len(ri)
            if n_pend >= batch:
                flush()
                n_pend = 0
        flush()
        return st, (e - s) * (e - s - 1) // 2 + (e - s) * (n - e)

    return run_tiles(task, n, tile, pool, bar, kern)


def pointwise_quotients_multi(X, Y, labelings, *, return_partner: bool = False, block: int = 256,
                              n_jobs: int | None = None, progress: bool = False,
                              n_components: int | None = None, options=None,
                              return_stats: bool = False):
    """Exact quotients of every labeling in ``labelings`` (L, N) in one pass (module doc).

    Args:
        X: (N, d) inputs; Y: (N, d_y) outputs (as :func:`pointwise_quotients`).
        labelings: (L, N) labels (any values; a row of equal labels means no grouping);
            a 1-D (N,) array is one labeling.
        return_partner: also return P (L, N) int64, the partner attaining each Q (smallest
            index on ties; -1 where Q = 0).
        block, n_jobs, progress, n_components, options: as :func:`pointwise_quotients`
            (``options.search`` is ignored: always the symmetric pass). numpy backend.
        return_stats: return ``(Q, P, SearchStats)`` (``n_pairs``: unordered pairs of all N).

    Returns:
        Q (L, N) float64, equal for each l to ``pointwise_quotients(X, Y, labelings[l])``;
        or (Q, P); or (Q, P, stats).
    """
    from ._bounds import F32_UNIT_ROUNDOFF, build_features
    from ._kernel import NumpyKernel
    from ._quotients import SearchOptions, SearchStats, _blas_single_thread, check_inputs, default_jobs

    options = SearchOptions() if options is None else options
    if not isinstance(options, SearchOptions):
        raise TypeError(f"options must be a SearchOptions, got {type(options).__name__}")
    X, Y, _ = check_inputs(X, Y)
    N = len(X)
    labels = check_labelings(labelings, N)
    Q = np.zeros(labels.shape)  # point-major (N, L) while computing; (L, N) returned
    P = np.full(labels.shape, -1, dtype=np.int64)
    LB = np.zeros(labels.shape)
    tmin = np.zeros(N)
    qmin = np.zeros(N)
    n_pairs = N * (N - 1) // 2
    stats = PairCounters()
    n_jobs = max(1, int(default_jobs() if n_jobs is None else n_jobs))

    def done():
        QT, PT = np.ascontiguousarray(Q.T), np.ascontiguousarray(P.T)
        if return_stats:
            return QT, PT, SearchStats(n_pairs=n_pairs, pairs_screened=stats.pairs_screened,
                                     pairs_full_screened=stats.pairs_full_screened,
                                     pairs_exact=stats.pairs_exact)
        return (QT, PT) if return_partner else QT

    if N < 2 or (Y == Y[0]).all():  # constant output: every quotient is 0 or skipped
        return done()
    from ._exact import pair_ratios
    if N <= options.small_group:  # all pairs exactly
        i, j = np.triu_indices(N, 1)
        credit_multi(Q, P, LB, tmin, qmin, labels, i, j, pair_ratios(X, Y, i, j))
        stats.pairs_exact += 2 * len(i)
        return done()
    i, j = time_neighbour_pairs(labels, options.time_neighbours)
    credit_multi(Q, P, LB, tmin, qmin, labels, i, j, pair_ratios(X, Y, i, j))
    stats.pairs_exact += 2 * len(i)
    f = build_features(X, Y, np.arange(N), leaf_size=max(8, int(block)), n_components=n_components,
                       full_screen=True, unit_roundoff=F32_UNIT_ROUNDOFF)
    bar = None
    if progress:
        from learning.progress import progress_bar
        bar = progress_bar(total=n_pairs, unit="pair", unit_scale=True, desc="Lipschitz quotients",
                   leave=False)
    pool = ThreadPoolExecutor(max_workers=n_jobs) if n_jobs > 1 else None
    try:
        with _blas_single_thread():
            kern = NumpyKernel(f, X, Y)
            stats.pairs_full_screened += warm_bounds(f, kern, labels, LB, pool, options.multi_warmup_leaves,
                                                       spread_sample(N, options.warmup_sample))
            stats.add(multi_pass(f, kern, labels, Q, P, LB, qmin, pool, bar, tile=options.tile,
                                 chunk=options.chunk))
    finally:
        if pool is not None:
            pool.shutdown(wait=True)
        if bar is not None:
            bar.close()
    return done()
