"""Screening kernels of the exact search: which pairs may attain a quotient.

:class:`NumpyKernel` screens pairs with float32 matrix products through the
conservative bounds of ``_bounds`` and evaluates survivors exactly (``_exact``);
``_torch.TorchKernel`` is the same interface on torch. :func:`survivors` extracts the
positions of the entries ≥ 0 of a screen.
"""

from __future__ import annotations

import threading

import numpy as np

from ._bounds import Features, row_features, threshold_scalar, thresholds
from ._compiled import full_lower_ratios, full_survivors
from ._exact import pair_ratios

__all__ = ["NumpyKernel", "survivors"]

_tls = threading.local()  # per-thread boolean buffer of ``survivors``


def survivors(S: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(row, col) positions of the entries ``S ≥ 0`` of a float32 (a × c) matrix.

    Survivors are rare (≪ 1 %): a compare into a reused per-thread boolean
    buffer and numpy's boolean ``flatnonzero`` (a counting fast path) cost about
    0.2 ns per entry — cheaper than a segmented max (measured). NaN never survives.
    """
    a, c = S.shape
    buf = getattr(_tls, "buf", None)
    if buf is None or buf.size < S.size:
        buf = _tls.buf = np.empty(S.size, dtype=bool)
    B = buf[:S.size].reshape(a, c)
    np.greater_equal(S, 0.0, out=B)
    return np.divmod(np.flatnonzero(B), c)



class NumpyKernel:
    """Screening and exact evaluation with numpy (float32 products via BLAS)."""

    chunk_elems = 1 << 20  # a·c elements screened at once (≈ 4 MB float32)

    def __init__(self, f: Features, X: np.ndarray, Y: np.ndarray) -> None:
        self.f, self.X, self.Y = f, X, Y

    def screen(self, rows: np.ndarray, T: np.ndarray, cols: np.ndarray, full: bool = False
               ) -> tuple[np.ndarray, np.ndarray]:
        """(row, col) positions (within rows/cols) of pairs with S ≥ 0.

        ``full=False``: low-dimensional z screen; ``full=True``: the same one-product
        screen with all d coordinates (tight, d/K times the cost).
        """
        f = self.f
        if full:
            R = row_features(f.ws[rows], f.nbx[rows], f.xs[rows], f.nx[rows], T)
            S = R @ f.col_x[cols].T
        else:
            R = row_features(f.ws[rows], f.nb[rows], f.zs[rows], f.na[rows], T)
            S = R @ f.col_z[cols].T
        return survivors(np.ascontiguousarray(S))

    def sym_prepare(self, order: np.ndarray) -> None:
        """Copy the z-screen features, X and Y into the order of the symmetric pass (the
        exact stage then reads a tile's and a chunk's rows from contiguous memory:
        measured 350 → 100 ns a pair at d = 90, N = 50k)."""
        f = self.f
        src = f.perm[order]
        self.o_X = np.ascontiguousarray(self.X[src])
        self.o_Y = np.ascontiguousarray(self.Y[src])
        self.o_col = np.ascontiguousarray(f.col_z[order])
        self.o_ws, self.o_nb = f.ws[order], f.nb[order]
        self.o_zs, self.o_na = f.zs[order], f.na[order]

    def sym_screen(self, s: int, e: int, T: np.ndarray, c0: int, c1: int
                   ) -> tuple[np.ndarray, np.ndarray]:
        """Survivors (positions within [s, e) × [c0, c1) of the pass order) of the z screen.
        The product goes into a reused per-thread buffer (a fresh 4 MB result costs its page
        faults on every chunk: 1.19 → 1.01 ns a pair for 256 × 4096 tiles, measured)."""
        R = row_features(self.o_ws[s:e], self.o_nb[s:e], self.o_zs[s:e], self.o_na[s:e], T)
        size = (e - s) * (c1 - c0)
        buf = getattr(_tls, "prod", None)
        if buf is None or buf.size < size:
            buf = _tls.prod = np.empty(size, dtype=np.float32)
        S = buf[:size].reshape(e - s, c1 - c0)
        np.matmul(R, self.o_col[c0:c1].T, out=S)
        return survivors(S)

    def sym_tight(self, rows: np.ndarray, cols: np.ndarray, Lr: np.ndarray, Lc: np.ndarray,
                  cap: float | None) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Full-dimensional two-sided float32 screen of rows × cols (leaf-order indices).

        For data where the z screen keeps too many pairs (i.i.d.-like). Returns
        the survivors (positions) of ``ub‖Δy‖² ≥ T'_i·lb‖Δx‖²`` with T'_i the
        row threshold capped by ``cap`` (a threshold valid for every column), and
        the raised lower bounds of the rows and of the columns,
        max(L, max sqrt(lb‖Δy‖² / ub‖Δx‖²)) — provable lower bounds of q.
        """
        f = self.f
        G, Gy = self._grams(rows, cols)
        best_r, best_c = full_lower_ratios(G, Gy, f.nx_hi[rows], f.nx_hi[cols], f.nw_lo[rows], f.nw_lo[cols])
        conv = f.scale_x / f.scale_y

        def lift(best: np.ndarray) -> np.ndarray:
            return np.sqrt(np.maximum(best, 0.0)) * conv * (1.0 - 1e-5)

        Lr = np.maximum(Lr, lift(best_r))
        Lc = np.maximum(Lc, lift(best_c))
        T = thresholds(Lr, f.scale_x, f.scale_y)
        if cap is not None:
            np.minimum(T, threshold_scalar(min(cap, Lc.min()), f.scale_x, f.scale_y), out=T)
        ri, cj = full_survivors(G, Gy, f.nx_lo[rows], f.nx_lo[cols], f.nw_hi[rows], f.nw_hi[cols], T)
        return ri, cj, Lr, Lc

    def _grams(self, rows: np.ndarray, cols: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """float32 Gram matrices x̂_r x̂_cᵀ and ŵ_r ŵ_cᵀ (BLAS)."""
        f = self.f
        return f.xs[rows] @ f.xs[cols].T, f.ws[rows] @ f.ws[cols].T

    def sym_survivors(self, rows: np.ndarray, cols: np.ndarray, T: np.ndarray
                      ) -> tuple[np.ndarray, np.ndarray]:
        """Survivors (positions) of the full-dimensional two-sided screen
        ``ub‖Δy‖² ≥ T_i·lb‖Δx‖²`` of rows × cols with the given float32 thresholds
        (no bound is raised: for labelings, where group-free bounds are not valid)."""
        f = self.f
        G, Gy = self._grams(rows, cols)
        return full_survivors(G, Gy, f.nx_lo[rows], f.nx_lo[cols], f.nw_hi[rows], f.nw_hi[cols], T)

    def sym_exact(self, pi: np.ndarray, pj: np.ndarray) -> np.ndarray:
        """Exact quotients of pairs given by positions in the pass order (``sym_prepare``);
        the same numbers as ``exact`` of their original indices."""
        return pair_ratios(self.o_X, self.o_Y, pi, pj)

    def sym_release(self) -> None:
        self.o_col = self.o_ws = self.o_nb = self.o_zs = self.o_na = None
        self.o_X = self.o_Y = None

    def tight(self, rows: np.ndarray, cols: np.ndarray, L: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Full-dimensional two-sided float32 bounds of all pairs rows × cols.

        Returns the surviving (row, col) positions and the raised lower bounds
        L_i ← max(L_i, max_j sqrt(lb‖Δy‖² / ub‖Δx‖²)), which are provable lower
        bounds of q_i obtained without any exact evaluation.
        """
        f = self.f
        Gx = f.xs[rows] @ f.xs[cols].T
        Gx *= -2.0
        xub = Gx + f.nx_hi[rows][:, None]
        xub += f.nx_hi[cols][None, :]
        Gx += f.nx_lo[rows][:, None]
        Gx += f.nx_lo[cols][None, :]  # now: lower bound of ‖Δx̂‖²
        Gy = f.ws[rows] @ f.ws[cols].T
        Gy *= -2.0
        ylb = Gy + f.nw_lo[rows][:, None]
        ylb += f.nw_lo[cols][None, :]
        Gy += f.nw_hi[rows][:, None]
        Gy += f.nw_hi[cols][None, :]  # upper bound of ‖Δŵ‖²
        ylb /= xub  # lower bound of the squared scaled ratio (xub > 0 by the norm floor)
        best = ylb.max(axis=1).astype(np.float64)
        conv = f.scale_x / f.scale_y
        Lnew = np.sqrt(np.maximum(best, 0.0)) * conv * (1.0 - 1e-5)  # float32 division slack
        L = np.maximum(L, Lnew)
        T = thresholds(L, f.scale_x, f.scale_y)
        Gx *= T[:, None]
        flat = np.flatnonzero(Gy >= Gx)
        ri, cj = np.divmod(flat, len(cols))
        return ri, cj, L

    def exact(self, gi: np.ndarray, gj: np.ndarray) -> np.ndarray:
        """Exact quotients of pairs given by *original* indices."""
        return pair_ratios(self.X, self.Y, gi, gj)
