"""Conservative screening features and leaf boxes for exact Lipschitz quotients.

Lower bound on ‖x_i − x_j‖: with the centred point v = x − m, an orthonormal basis P (k × d) of
leading principal directions (fitted on a subsample; any orthonormal P is valid) and the residual
r = v − PᵀPv, Pythagoras gives

    ‖x_i − x_j‖² = ‖P(v_i − v_j)‖² + ‖r_i − r_j‖² ≥ ‖P(v_i − v_j)‖² + (‖r_i‖ − ‖r_j‖)²,

so the K = k + 1 features z = [Pv, ‖r‖] satisfy ‖z_i − z_j‖ ≤ ‖x_i − x_j‖. A pair (i, j) can
matter for row i (lower bound L_i on q_i) only if ‖Δy‖ ≥ L_i‖Δx‖; it is pruned when

    S_ij = ub(‖Δy‖²) − T_i·lb(‖Δx‖²) < 0,   T_i ≤ L_i²,

ONE float32 matrix product of row [−2ŵ_i, 1, 2T_iẑ_i, −T_i, b_i − T_i·a_i] and column
[ŵ_j, b_j, ẑ_j, a_j, 1] (:func:`row_features`; ŵ, ẑ the power-of-two-scaled centred y and z,
b = (1 + c)‖ŵ‖², a = (1 − c)‖ẑ‖²). The margin c = 2(K' + 16)·u (:func:`margin_constant`) covers
the rounding of the inputs, of the product of length K' and of the final additions, so S ≥ 0
whenever the true quotient reaches L_i; u is the product's unit roundoff (2⁻²⁴ for float32, larger
for TF32/bf16 backends). A PCA basis that is not orthonormal raises ``FloatingPointError``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "F32_UNIT_ROUNDOFF",
    "Features",
    "build_features",
    "build_leaves",
    "leaf_upper_ratios",
    "margin_constant",
]

F32_UNIT_ROUNDOFF = 2.0 ** -24
_F64_U = 2.0 ** -53
_T_MAX = 2.0 ** 100  # cap on T so T·‖z‖² stays far inside float32 range (‖z‖ ≤ 1 after scaling)
_DEFAULT_K = 12  # principal components of the screen, at least
_MAX_K = 32  # ... and at most (see ``choose_components``)
_RESID_TARGET = 0.05  # residual variance fraction above which components are added
_NORM_FLOOR = 2.0 ** -60  # absolute floor on scaled squared norms: covers float32 subnormals


def margin_constant(inner_dim: int, unit_roundoff: float = F32_UNIT_ROUNDOFF) -> float:
    """Relative margin c on ‖·‖² for a float32 product of the given inner length."""
    return 2.0 * (inner_dim + 16) * unit_roundoff


@dataclass
class Features:
    """Screening data for one group, rows in *leaf order* (see ``perm``).

    Attributes:
        perm: (n,) original index of each leaf-ordered row.
        leaf_start: (n_leaves + 1,) row offsets of the leaves.
        z: (n, K) float64 lower-bound features (unscaled).
        w: (n, d_y) float64 centred outputs (unscaled).
        col_z: (n, K + d_y + 3) float32 column features [ŵ, b, ẑ, a, 1] for the z screen.
        col_x: (n, d + d_y + 3) float32 column features for the full-d screen, or None.
        zs, ws, xs: float32 scaled features (rows): ẑ, ŵ, x̂.
        na, nb, nx: float32 a = (1−c)‖ẑ‖², b = (1+c)‖ŵ‖² (z screen), a for full-d screen.
        scale_x, scale_y: powers of two applied to x (and z) and y before float32.
        delta_z, delta_y: absolute float64 error bounds on z and w (per group, max).
        c_z, c_x: margins used for the z screen and the full-d screen.
    """

    perm: np.ndarray
    leaf_start: np.ndarray
    z: np.ndarray
    w: np.ndarray
    zs: np.ndarray
    ws: np.ndarray
    xs: np.ndarray | None
    na: np.ndarray
    nb: np.ndarray
    nbx: np.ndarray | None
    nx: np.ndarray | None
    nx_lo: np.ndarray | None
    nx_hi: np.ndarray | None
    nw_lo: np.ndarray | None
    nw_hi: np.ndarray | None
    col_z: np.ndarray
    col_x: np.ndarray | None
    scale_x: float
    scale_y: float
    delta_z: float
    delta_y: float
    c_z: float
    c_x: float


def _pow2_scale(max_abs: float) -> float:
    """Power of two s with s·max_abs ≤ 1 (exact scaling); 1 for zero data."""
    if not np.isfinite(max_abs) or max_abs <= 0.0:
        return 1.0
    return float(2.0 ** (-np.ceil(np.log2(max_abs))))


def _pca_basis(V: np.ndarray, k: int | None, max_rows: int = 20000, max_k: int = 12
               ) -> np.ndarray:
    """Orthonormal (k × d) basis of leading principal directions of V (centred).

    Fitted on at most ``max_rows`` evenly spaced rows (deterministic); any
    orthonormal basis gives a valid bound, a good one a tight bound. ``k=None``:
    ``choose_components`` from the spectrum, at most ``max_k``.
    """
    n = V.shape[0]
    step = max(1, n // max_rows)
    S = V[::step]
    C = S.T @ S
    evals, vecs = np.linalg.eigh(C)
    if k is None:
        k = choose_components(evals[::-1], max_k)
    if k == 0:
        return np.zeros((0, V.shape[1]))
    P = vecs[:, ::-1][:, :k].T.copy()
    # Re-orthonormalise so ‖PPᵀ − I‖ is at rounding level (the bound needs orthonormal rows).
    Q, _ = np.linalg.qr(P.T)
    P = Q.T
    err = np.abs(P @ P.T - np.eye(k)).max() if k else 0.0
    if err > 1e-13:  # pragma: no cover - QR output is orthonormal to ~1e-16
        raise FloatingPointError(f"PCA basis not orthonormal ({err:.2e})")
    return np.ascontiguousarray(P)


def choose_components(evals_desc: np.ndarray, max_k: int) -> int:
    """Number k of principal components of the lower bound (eigenvalues in decreasing order):
    at least ``_DEFAULT_K`` (12), more while the residual variance exceeds 5 %, at most
    ``_MAX_K`` (32) and ``max_k``.

    The bound ‖z_i − z_j‖ ≤ ‖x_i − x_j‖ loses what the residual norm does not capture, so data
    with a large residual get more components and the others keep a short screen (measured:
    docs/results.md, "Benchmarks").
    """
    d = len(evals_desc)
    lo = min(d, _DEFAULT_K, max_k)
    hi = min(d, _MAX_K, max_k)
    tot = float(np.sum(np.maximum(evals_desc, 0.0)))
    if tot <= 0.0:
        return lo
    resid = 1.0 - np.cumsum(np.maximum(evals_desc, 0.0)) / tot  # resid[k-1]: residual with k
    k = lo
    while k < hi and resid[k - 1] > _RESID_TARGET:
        k += 1
    return int(k)


def build_leaves(z: np.ndarray, leaf_size: int) -> tuple[np.ndarray, np.ndarray]:
    """k-d split of the rows of z into leaves of ≤ leaf_size points.

    Each segment is split at its median along the feature of largest spread.
    Returns (perm, leaf_start): perm lists row indices leaf by leaf.
    """
    n = len(z)
    perm = np.arange(n)
    segments = [(0, n)]
    done: list[tuple[int, int]] = []
    while segments:
        nxt = []
        for s, e in segments:
            if e - s <= leaf_size:
                done.append((s, e))
                continue
            idx = perm[s:e]
            sub = z[idx]
            axis = int(np.argmax(sub.max(axis=0) - sub.min(axis=0))) if z.shape[1] else 0
            half = (e - s) // 2
            if z.shape[1]:
                part = np.argpartition(sub[:, axis], half)
                perm[s:e] = idx[part]
            nxt.append((s, s + half))
            nxt.append((s + half, e))
        segments = nxt
    done.sort()
    leaf_start = np.array([s for s, _ in done] + [n], dtype=np.int64)
    return perm, leaf_start


def build_features(X: np.ndarray, Y: np.ndarray, idx: np.ndarray, *, leaf_size: int,
                   n_components: int | None, full_screen: bool,
                   unit_roundoff: float = F32_UNIT_ROUNDOFF, chunk: int = 65536) -> Features:
    """Features of the points ``idx`` (original indices) of one group; see module doc."""
    n = len(idx)
    d = X.shape[1]
    dy = Y.shape[1]
    Xg = X[idx] if len(idx) != len(X) else X
    Yg = Y[idx] if len(idx) != len(Y) else Y
    m = Xg.mean(axis=0)
    if n_components is not None:
        k = int(max(0, min(n_components, d)))
        P = _pca_basis(Xg[:: max(1, n // 20000)] - m, k) if k else np.zeros((0, d))
    else:  # from the spectrum (choose_components), at most n/8 for small groups
        P = _pca_basis(Xg[:: max(1, n // 20000)] - m, None, max_k=max(1, n // 8))
        k = P.shape[0]
    K = k + 1
    z, vmax = _project(Xg, m, P, chunk)
    # Absolute float64 error of the computed z (subtraction, product, residual):
    # ≤ few·(d + k)·u64·‖v‖; generous constant.
    delta_z = 8.0 * (d + k + 4) * _F64_U * vmax
    # Centre y on the median row so exactly equal outputs stay exactly equal (→ 0).
    my = Yg[np.argsort(Yg[:, 0], kind="stable")[n // 2]] if dy else np.zeros(0)
    w = Yg - my
    wmax = float(np.sqrt((w * w).sum(axis=1)).max()) if dy else 0.0
    delta_y = 8.0 * (dy + 4) * _F64_U * wmax

    perm, leaf_start = build_leaves(z, leaf_size)
    z = z[perm]
    w = w[perm]

    sx = _pow2_scale(float(np.abs(z).max()) if z.size else 0.0)
    sy = _pow2_scale(float(np.abs(w).max()) if w.size else 0.0)
    zs = (z * sx).astype(np.float32)
    ws = (w * sy).astype(np.float32)
    c_z = margin_constant(K + dy + 4, unit_roundoff)
    nz = np.maximum(np.einsum("ij,ij->i", zs.astype(np.float64), zs.astype(np.float64)), _NORM_FLOOR)
    nw = np.maximum(np.einsum("ij,ij->i", ws.astype(np.float64), ws.astype(np.float64)), _NORM_FLOOR)
    na = ((1.0 - c_z) * nz).astype(np.float32)
    nb = ((1.0 + c_z) * nw).astype(np.float32)
    col_z = np.empty((n, dy + K + 3), dtype=np.float32)
    col_z[:, :dy] = ws
    col_z[:, dy] = nb
    col_z[:, dy + 1:dy + 1 + K] = zs
    col_z[:, dy + 1 + K] = na
    col_z[:, dy + 2 + K] = 1.0

    c_x = margin_constant(d + dy + 4, unit_roundoff)
    full = _full_columns(Xg, perm, m, sx, ws, nw, c_x, chunk) if full_screen else dict.fromkeys(
        ("xs", "nx", "col_x", "nbx", "nx_lo", "nx_hi", "nw_lo", "nw_hi"))
    return Features(perm=idx[perm], leaf_start=leaf_start, z=z, w=w, zs=zs, ws=ws, na=na, nb=nb, col_z=col_z,
                    scale_x=sx, scale_y=sy, delta_z=delta_z, delta_y=delta_y, c_z=c_z, c_x=c_x, **full)


def _project(Xg: np.ndarray, m: np.ndarray, P: np.ndarray, chunk: int) -> tuple[np.ndarray, float]:
    """(n, k + 1) z = [P·(x − m), ‖residual‖] in float64, and max ‖x − m‖ (for the error bound)."""
    n, k = len(Xg), P.shape[0]
    z = np.empty((n, k + 1))
    vmax = 0.0
    for s in range(0, n, chunk):
        e = min(s + chunk, n)
        V = Xg[s:e] - m  # one rounding per coordinate: relative error ≤ u64
        Z = V @ P.T
        R = V - Z @ P
        z[s:e, :k] = Z
        z[s:e, k] = np.sqrt(np.einsum("ij,ij->i", R, R))
        vmax = max(vmax, float(np.sqrt(np.einsum("ij,ij->i", V, V)).max()))
    return z, vmax


def _full_columns(Xg: np.ndarray, perm: np.ndarray, m: np.ndarray, sx: float, ws: np.ndarray, nw: np.ndarray,
                  c_x: float, chunk: int) -> dict[str, np.ndarray]:
    """The full-dimensional screen's float32 columns of the points ``Xg[perm]`` (module docstring; read a
    chunk at a time, never copied whole):
    [ws, (1 + c_x)‖w‖², x·sx, (1 − c_x)‖x‖², 1] and the norms' lower and upper bounds."""
    n, d, dy = len(perm), Xg.shape[1], ws.shape[1]
    col_x = np.empty((n, dy + d + 3), dtype=np.float32)
    nxx = np.empty(n)
    for s in range(0, n, chunk):
        e = min(s + chunk, n)
        V32 = ((Xg[perm[s:e]] - m) * sx).astype(np.float32)
        col_x[s:e, dy + 1:dy + 1 + d] = V32
        V64 = V32.astype(np.float64)
        nxx[s:e] = np.einsum("ij,ij->i", V64, V64)
    nxx = np.maximum(nxx, _NORM_FLOOR)
    nx = ((1.0 - c_x) * nxx).astype(np.float32)
    nbx = ((1.0 + c_x) * nw).astype(np.float32)
    col_x[:, :dy] = ws
    col_x[:, dy] = nbx
    col_x[:, dy + 1 + d] = nx
    col_x[:, dy + 2 + d] = 1.0
    return {"xs": col_x[:, dy + 1:dy + 1 + d], "nx": nx, "col_x": col_x, "nbx": nbx, "nx_lo": nx,
            "nx_hi": ((1.0 + c_x) * nxx).astype(np.float32), "nw_lo": ((1.0 - c_x) * nw).astype(np.float32),
            "nw_hi": nbx}


def thresholds(L: np.ndarray, scale_x: float, scale_y: float) -> np.ndarray:
    """T ≤ (L·s_y/s_x)², rounded down and capped, as float32 (see module doc).

    L ≥ 0 (finite or inf; never NaN).
    """
    with np.errstate(over="ignore", invalid="ignore"):
        T = L * (scale_y / scale_x)
        T *= T
        T *= 1.0 - 2.0 ** -20
    np.minimum(T, _T_MAX, out=T)  # inf → cap
    T32 = T.astype(np.float32)
    # Round toward zero where float32 rounding went up.
    up = T32.astype(np.float64) > T
    if up.any():
        T32[up] = np.nextafter(T32[up], np.float32(0))
    return T32


def threshold_scalar(L: float, scale_x: float, scale_y: float) -> np.float32:
    """``thresholds`` of one value."""
    return thresholds(np.array([float(L)]), scale_x, scale_y)[0]


def row_features(ws: np.ndarray, nb: np.ndarray, xs: np.ndarray, na: np.ndarray,
                 T: np.ndarray) -> np.ndarray:
    """Row features [−2ŵ, 1, 2Tẑ, −T, b − Ta] (float32) for the screen S = row·colᵀ.

    The columns are [ŵ, b, ẑ, a, 1]. The row constant b − T·a is formed in
    float64 (the product of two float32 numbers is exact) and rounded once to
    float32; its error, ≤ (u + u64)(b + T·a), is less than what merging the two
    terms saves in the dot-product bound (γ_K' − γ_{K'−1} ≥ u(1 + (2K'−1)u) for
    the same terms), so the margin ``margin_constant(K + d_y + 4)``, computed
    for the unmerged length, still covers the screen.
    """
    a, dy = ws.shape
    K = xs.shape[1]
    R = np.empty((a, dy + K + 3), dtype=np.float32)
    R[:, :dy] = ws
    R[:, :dy] *= -2.0
    R[:, dy] = 1.0
    R[:, dy + 1:dy + 1 + K] = xs
    R[:, dy + 1:dy + 1 + K] *= (2.0 * T)[:, None]
    R[:, dy + 1 + K] = -T
    R[:, dy + 2 + K] = nb.astype(np.float64) - T.astype(np.float64) * na.astype(np.float64)
    return R


def leaf_boxes(f: Features) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Per-leaf bounding boxes of z and w and centroids of z."""
    st = f.leaf_start[:-1]
    zlo = np.minimum.reduceat(f.z, st, axis=0)
    zhi = np.maximum.reduceat(f.z, st, axis=0)
    if f.w.shape[1]:
        wlo = np.minimum.reduceat(f.w, st, axis=0)
        whi = np.maximum.reduceat(f.w, st, axis=0)
    else:
        wlo = whi = np.zeros((len(st), 0))
    cnt = np.diff(f.leaf_start)[:, None]
    zc = np.add.reduceat(f.z, st, axis=0) / cnt
    return zlo, zhi, wlo, whi, zc


def leaf_upper_ratios(a: int, zlo: np.ndarray, zhi: np.ndarray, wlo: np.ndarray, whi: np.ndarray,
                      delta_z: float, delta_y: float) -> np.ndarray:
    """Upper bound on ‖Δy‖/‖Δx‖ over all pairs of leaf a × leaf b, for every b.

    ‖Δx‖ ≥ box distance of z (minus the float64 error of z); ‖Δy‖ ≤ largest
    distance between the y boxes (plus the error of w).
    """
    gap = np.maximum(zlo - zhi[a], zlo[a] - zhi)
    np.maximum(gap, 0.0, out=gap)
    zmin = np.sqrt(np.einsum("ij,ij->i", gap, gap)) * (1.0 - 1e-12) - 2.0 * delta_z
    span = np.maximum(np.abs(whi - wlo[a]), np.abs(whi[a] - wlo))
    ymax = np.sqrt(np.einsum("ij,ij->i", span, span)) * (1.0 + 1e-12) + 2.0 * delta_y
    with np.errstate(divide="ignore", invalid="ignore"):
        ub = np.where(zmin > 0.0, ymax / np.where(zmin > 0.0, zmin, 1.0), np.inf)
    return ub
