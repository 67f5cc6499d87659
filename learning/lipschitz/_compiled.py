"""Compiled (numba) loops of the exact search: exact pair quotients, the running maximum
with its partner, and the crediting of one exact pair to many labelings.

Arithmetic (what "exact" means in this package): ‖a − b‖ is the square root of the sum of squared
direct differences in float64, accumulated in four interleaved partial sums (columns c ≡ 0, 1, 2,
3 mod 4, then (s0 + s1) + (s2 + s3)): a fixed order, so a pair's quotient is the same bits wherever
it is evaluated, and r_ij == r_ji. Sums that may have under- or overflowed (norm < 1e-150 or
> 1e150) are recomputed scaled by the largest |difference|. Conventions (``_exact``): 0/0
(identical in x and y) → NaN (skipped), y/0 → inf.

All functions are ``nogil`` (the search runs them in its own threads) and cached on disk
(``cache=True``), so the compile cost is paid once per machine. Why hand-written loops (no library
computes maxima of ratios over scattered pairs): docs/design.md, "Conventions of the analysis";
their cost: docs/results.md, "Benchmarks".
"""

from __future__ import annotations

import math

import numba
import numpy as np

__all__ = ["credit_multi", "full_lower_ratios", "full_survivors", "grouped_lower_ratios", "grouped_survivors",
           "pair_ratios_compiled", "update_best_compiled"]

_TINY = 1e-150
_HUGE = 1e150


@numba.njit(cache=True, nogil=True, inline="always")
def _norm_diff(A, i, j):  # pragma: no cover - compiled
    """‖A[i] − A[j]‖₂ by direct differences (fixed summation order, see module doc)."""
    d = A.shape[1]
    s0 = 0.0
    s1 = 0.0
    s2 = 0.0
    s3 = 0.0
    c = 0
    while c + 4 <= d:
        t0 = A[i, c] - A[j, c]
        t1 = A[i, c + 1] - A[j, c + 1]
        t2 = A[i, c + 2] - A[j, c + 2]
        t3 = A[i, c + 3] - A[j, c + 3]
        s0 += t0 * t0
        s1 += t1 * t1
        s2 += t2 * t2
        s3 += t3 * t3
        c += 4
    if c < d:
        t = A[i, c] - A[j, c]
        s0 += t * t
    if c + 1 < d:
        t = A[i, c + 1] - A[j, c + 1]
        s1 += t * t
    if c + 2 < d:
        t = A[i, c + 2] - A[j, c + 2]
        s2 += t * t
    nrm = math.sqrt((s0 + s1) + (s2 + s3))
    if nrm < _TINY or nrm > _HUGE:
        # Scaled accumulation: rare (near-identical or astronomically far pairs).
        m = 0.0
        for c in range(d):
            m = max(m, abs(A[i, c] - A[j, c]))
        if m == 0.0:
            return 0.0
        s = 0.0
        for c in range(d):
            t = (A[i, c] - A[j, c]) / m
            s += t * t
        nrm = m * math.sqrt(s)
    return nrm


@numba.njit(cache=True, nogil=True)
def _ratios(X, Y, gi, gj, out):  # pragma: no cover - compiled
    for k in range(gi.shape[0]):
        i = gi[k]
        j = gj[k]
        dx = _norm_diff(X, i, j)
        dy = _norm_diff(Y, i, j)
        if dx == 0.0:
            out[k] = np.nan if dy == 0.0 else np.inf
        else:
            out[k] = dy / dx


def pair_ratios_compiled(X: np.ndarray, Y: np.ndarray, gi: np.ndarray, gj: np.ndarray) -> np.ndarray:
    """``‖Y[gi]−Y[gj]‖ / ‖X[gi]−X[gj]‖`` per pair (float64 C-contiguous X, Y; see module doc).

    NaN for pairs identical in x and y (skipped, including gi == gj), inf for
    identical x with different y.
    """
    gi = np.ascontiguousarray(gi, dtype=np.int64)
    gj = np.ascontiguousarray(gj, dtype=np.int64)
    out = np.empty(len(gi), dtype=np.float64)
    if len(gi):
        _ratios(X, Y, gi, gj, out)
    return out


@numba.njit(cache=True, nogil=True)
def _update_best(q, partner, rows, cols, r):  # pragma: no cover - compiled
    for k in range(rows.shape[0]):
        v = r[k]
        if not v > 0.0:  # NaN (skipped) and 0 never set a partner
            continue
        i = rows[k]
        if v > q[i] or (v == q[i] and cols[k] < partner[i]):
            q[i] = v
            partner[i] = cols[k]


def update_best_compiled(q: np.ndarray, partner: np.ndarray, rows: np.ndarray, cols_orig: np.ndarray,
                         r: np.ndarray) -> None:
    """In place ``q[rows] = max(q[rows], r)`` keeping the smallest partner index on ties
    (same contract as ``_exact.update_best``; a point whose best is 0 keeps partner -1)."""
    if len(r):
        _update_best(q, partner, np.ascontiguousarray(rows, dtype=np.int64),
                     np.ascontiguousarray(cols_orig, dtype=np.int64), np.ascontiguousarray(r))


@numba.njit(cache=True, nogil=True, inline="always")
def _credit_one(Q, P, LB, tmin, qmin, i, j, labels, v):  # pragma: no cover - compiled
    if v < qmin[i]:  # below every labeling's current maximum: nothing to credit
        return
    changed = False
    for m in range(labels.shape[1]):
        if labels[i, m] != labels[j, m]:
            continue
        if v > Q[i, m] or (v == Q[i, m] and j < P[i, m]):
            Q[i, m] = v
            P[i, m] = j
            changed = True
            if v > LB[i, m]:
                LB[i, m] = v
    if changed:
        t = np.inf
        u = np.inf
        for m in range(labels.shape[1]):
            t = min(t, LB[i, m])
            u = min(u, Q[i, m])
        tmin[i] = t
        qmin[i] = u


@numba.njit(cache=True, nogil=True)
def _credit_multi(Q, P, LB, tmin, qmin, labels, gi, gj, r):  # pragma: no cover - compiled
    for k in range(gi.shape[0]):
        v = r[k]
        if not v > 0.0:  # NaN (skipped) and 0 never set a partner
            continue
        _credit_one(Q, P, LB, tmin, qmin, gi[k], gj[k], labels, v)
        _credit_one(Q, P, LB, tmin, qmin, gj[k], gi[k], labels, v)


def credit_multi(Q: np.ndarray, P: np.ndarray, LB: np.ndarray, tmin: np.ndarray, qmin: np.ndarray,
                 labels: np.ndarray, gi: np.ndarray, gj: np.ndarray, r: np.ndarray) -> None:
    """Credit exact quotients ``r`` of pairs (gi, gj) to both points in every labeling
    ``m`` with ``labels[gi, m] == labels[gj, m]``. Point-major (N, L) arrays: Q running
    maxima, P their partners (smallest index on ties), LB lower bounds (raised to Q),
    tmin (N,) = min_m LB[:, m] and qmin (N,) = min_m Q[:, m] kept up to date (a pair
    below qmin of a point is skipped for it after one read); labels (N, L) integer codes."""
    if len(r):
        _credit_multi(Q, P, LB, tmin, qmin, labels, np.ascontiguousarray(gi, dtype=np.int64),
                      np.ascontiguousarray(gj, dtype=np.int64), np.ascontiguousarray(r))


@numba.njit(cache=True, nogil=True, inline="always")
def _gram_sq_dist(G, a, c, n_row, n_col):  # pragma: no cover - compiled
    """Squared distance ``n_row + n_col − 2·G[a, c]`` from a float32 Gram entry and two
    (margined) squared norms, in float64 (in this order, so every kernel rounds alike)."""
    return -2.0 * np.float64(G[a, c]) + n_row + np.float64(n_col[c])


@numba.njit(cache=True, nogil=True)
def _full_survivors(G, Gy, nxl_r, nxl_c, nwh_r, nwh_c, T, out_r, out_c):  # pragma: no cover
    cnt = 0
    for a in range(G.shape[0]):
        ta = np.float64(T[a])
        xr = np.float64(nxl_r[a])
        yr = np.float64(nwh_r[a])
        for c in range(G.shape[1]):
            xlb = _gram_sq_dist(G, a, c, xr, nxl_c)
            yub = _gram_sq_dist(Gy, a, c, yr, nwh_c)
            if yub >= ta * xlb:
                out_r[cnt] = a
                out_c[cnt] = c
                cnt += 1
    return cnt


def _collect(kernel, G: np.ndarray, *args) -> tuple[np.ndarray, np.ndarray]:
    """Run a survivor ``kernel(G, *args, out_r, out_c) -> count`` over the (a × c) block of
    ``G`` and return the (row, column) positions it kept."""
    a, c = G.shape
    out_r = np.empty(a * c, dtype=np.int64)
    out_c = np.empty(a * c, dtype=np.int64)
    k = kernel(G, *args, out_r, out_c)
    return out_r[:k].copy(), out_c[:k].copy()


def full_survivors(G: np.ndarray, Gy: np.ndarray, nxl_r: np.ndarray, nxl_c: np.ndarray,
                   nwh_r: np.ndarray, nwh_c: np.ndarray, T: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Positions (a, c) with ``ub‖Δŵ‖² ≥ T_a · lb‖Δx̂‖²`` from the float32 Gram matrices
    G = x̂_r x̂_cᵀ, Gy = ŵ_r ŵ_cᵀ and the margined squared norms (``_bounds``):
    lb‖Δx̂‖² = nxl_r + nxl_c − 2G, ub‖Δŵ‖² = nwh_r + nwh_c − 2Gy. The additions and the
    product by T are done in float64 (exact for these float32 operands up to one
    rounding), so the test is at least as conservative as its float32 form."""
    return _collect(_full_survivors, G, Gy, nxl_r, nxl_c, nwh_r, nwh_c, T)


@numba.njit(cache=True, nogil=True)
def _full_lower(G, Gy, nxh_r, nxh_c, nwl_r, nwl_c, rowmax, colmax):  # pragma: no cover
    for a in range(G.shape[0]):
        xr = np.float64(nxh_r[a])
        yr = np.float64(nwl_r[a])
        best = rowmax[a]
        for c in range(G.shape[1]):
            xub = _gram_sq_dist(G, a, c, xr, nxh_c)
            ylb = _gram_sq_dist(Gy, a, c, yr, nwl_c)
            v = ylb / xub
            if v > best:
                best = v
            if v > colmax[c]:
                colmax[c] = v
        rowmax[a] = best


def full_lower_ratios(G: np.ndarray, Gy: np.ndarray, nxh_r: np.ndarray, nxh_c: np.ndarray,
                      nwl_r: np.ndarray, nwl_c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Row and column maxima of lb‖Δŵ‖² / ub‖Δx̂‖² (squared scaled quotient lower bounds)
    from the same Gram matrices: lb‖Δŵ‖² = nwl_r + nwl_c − 2Gy, ub‖Δx̂‖² = nxh_r + nxh_c − 2G
    (> 0 by the norm floor), in float64."""
    rowmax = np.full(G.shape[0], -np.inf)
    colmax = np.full(G.shape[1], -np.inf)
    _full_lower(G, Gy, nxh_r, nxh_c, nwl_r, nwl_c, rowmax, colmax)
    return rowmax, colmax


@numba.njit(cache=True, nogil=True)
def _grouped_lower(G, Gy, nxh_r, nxh_c, nwl_r, nwl_c, lab_r, lab_c, Tr, Tc, Br, Bc):  # pragma: no cover
    n_lab = lab_r.shape[1]
    a_n, c_n = G.shape
    rmin = np.empty(a_n)
    for a in range(a_n):
        m0 = np.inf
        for m in range(n_lab):
            m0 = min(m0, Tr[a, m])
        rmin[a] = m0
    cmin = np.empty(c_n)
    for c in range(c_n):
        m0 = np.inf
        for m in range(n_lab):
            m0 = min(m0, Tc[c, m])
        cmin[c] = m0
    for a in range(a_n):
        xr = np.float64(nxh_r[a])
        yr = np.float64(nwl_r[a])
        for c in range(c_n):
            xub = _gram_sq_dist(G, a, c, xr, nxh_c)
            ylb = _gram_sq_dist(Gy, a, c, yr, nwl_c)
            v = ylb / xub
            if v > rmin[a]:
                m0 = np.inf
                for m in range(n_lab):
                    if lab_r[a, m] == lab_c[c, m] and v > Tr[a, m]:
                        Tr[a, m] = v
                        Br[a, m] = v
                    m0 = min(m0, Tr[a, m])
                rmin[a] = m0
            if v > cmin[c]:
                m0 = np.inf
                for m in range(n_lab):
                    if lab_r[a, m] == lab_c[c, m] and v > Tc[c, m]:
                        Tc[c, m] = v
                        Bc[c, m] = v
                    m0 = min(m0, Tc[c, m])
                cmin[c] = m0


def grouped_lower_ratios(G: np.ndarray, Gy: np.ndarray, nxh_r: np.ndarray, nxh_c: np.ndarray,
                         nwl_r: np.ndarray, nwl_c: np.ndarray, lab_r: np.ndarray, lab_c: np.ndarray,
                         Tr: np.ndarray, Tc: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per labeling, the row and column maxima of lb‖Δŵ‖² / ub‖Δx̂‖² over the pairs whose
    two points share a group (``lab_r`` (a, L), ``lab_c`` (c, L) their labels) and that
    exceed the current values ``Tr`` (a, L) / ``Tc`` (c, L) (same squared scaled units;
    an entry that exceeds no current value of its row or column costs one comparison).
    Returns (a, L) and (c, L) arrays: the new maxima, −inf where nothing exceeded."""
    Br = np.full(Tr.shape, -np.inf)
    Bc = np.full(Tc.shape, -np.inf)
    _grouped_lower(G, Gy, nxh_r, nxh_c, nwl_r, nwl_c, lab_r, lab_c, np.array(Tr, dtype=np.float64),
                   np.array(Tc, dtype=np.float64), Br, Bc)
    return Br, Bc


@numba.njit(cache=True, nogil=True)
def _grouped_survivors(G, Gy, nxl_r, nxl_c, nwh_r, nwh_c, T, Tr, Tc, lab_r, lab_c,
                       out_r, out_c):  # pragma: no cover - compiled
    n_lab = lab_r.shape[1]
    cnt = 0
    for a in range(G.shape[0]):
        ta = np.float64(T[a])
        xr = np.float64(nxl_r[a])
        yr = np.float64(nwh_r[a])
        for c in range(G.shape[1]):
            xlb = _gram_sq_dist(G, a, c, xr, nxl_c)
            yub = _gram_sq_dist(Gy, a, c, yr, nwh_c)
            if yub < ta * xlb:
                continue
            # the smallest lower bound among the labelings in which the pair shares a group
            t = np.inf
            for m in range(n_lab):
                if lab_r[a, m] == lab_c[c, m]:
                    t = min(t, Tr[a, m], Tc[c, m])
            if yub >= t * xlb:
                out_r[cnt] = a
                out_c[cnt] = c
                cnt += 1
    return cnt


def grouped_survivors(G: np.ndarray, Gy: np.ndarray, nxl_r: np.ndarray, nxl_c: np.ndarray,
                      nwh_r: np.ndarray, nwh_c: np.ndarray, T: np.ndarray, Tr: np.ndarray,
                      Tc: np.ndarray, lab_r: np.ndarray, lab_c: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
    """``full_survivors`` for many labelings: an entry passing the row threshold ``T``
    (float32, ≤ the smallest bound of the row) is kept only if
    ``ub‖Δŵ‖² ≥ t·lb‖Δx̂‖²`` with t the smallest of Tr[a, m], Tc[c, m] (thresholds in the
    same squared scaled units, rounded down) over the labelings m in which both points
    share a group; a pair that shares no group is dropped."""
    return _collect(_grouped_survivors, G, Gy, nxl_r, nxl_c, nwh_r, nwh_c, T, Tr, Tc, lab_r, lab_c)
