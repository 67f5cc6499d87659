"""torch kernel of the Lipschitz search: the same screens and exact step on CPU or CUDA.

The leaf bookkeeping stays in numpy (``_search``); this kernel holds the
float32 features and the float64 data on the device and returns index arrays.
Reduced-precision float32 products (TF32 / bf16, allowed by
``torch.set_float32_matmul_precision``) are accounted for by a larger unit
roundoff in the screening margins, so the result stays exact.
"""

from __future__ import annotations

import numpy as np
import torch

from ._bounds import F32_UNIT_ROUNDOFF, Features, thresholds
from ._exact import pair_norms

__all__ = ["TorchKernel", "resolve_device", "torch_unit_roundoff"]


def resolve_device(device=None) -> torch.device:
    """The given device, else CUDA when available, else CPU."""
    if device is None:
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    return torch.device(device)


def torch_unit_roundoff(device: torch.device) -> float:
    """Unit roundoff of float32 matrix products under the current torch settings."""
    u = F32_UNIT_ROUNDOFF
    if torch.get_float32_matmul_precision() != "highest":
        u = 2.0 ** -8  # bf16 inputs in the worst case ("medium")
    if device.type == "cuda" and getattr(torch.backends.cuda.matmul, "allow_tf32", False):
        u = max(u, 2.0 ** -11)  # TF32: 10 explicit mantissa bits
    return u


class TorchKernel:
    """Screens and exact quotients with torch tensors on ``device``."""

    def __init__(self, f: Features, X: np.ndarray, Y: np.ndarray, device=None) -> None:
        self.f = f
        self.dev = resolve_device(device)
        self.chunk_elems = (1 << 24) if self.dev.type == "cuda" else (1 << 20)
        def t(a):
            return None if a is None else torch.from_numpy(np.ascontiguousarray(a)).to(self.dev)

        self.ws, self.zs, self.xs = t(f.ws), t(f.zs), t(f.xs)
        self.na, self.nb, self.nx, self.nbx = t(f.na), t(f.nb), t(f.nx), t(f.nbx)
        self.nx_lo, self.nx_hi, self.nw_lo, self.nw_hi = t(f.nx_lo), t(f.nx_hi), t(f.nw_lo), t(f.nw_hi)
        self.col_z, self.col_x = t(f.col_z), t(f.col_x)
        self.X, self.Y = t(X), t(Y)
        self.Xn, self.Yn = X, Y

    def _idx(self, a: np.ndarray) -> torch.Tensor:
        return torch.from_numpy(np.ascontiguousarray(a, dtype=np.int64)).to(self.dev)

    def _rowfeat(self, ws, nb, xs, na, T):
        # [−2ŵ, 1, 2Tẑ, −T, b − Ta], see _bounds.row_features.
        one = torch.ones_like(nb)[:, None]
        const = (nb.double() - T.double() * na.double()).float()[:, None]
        return torch.cat([-2.0 * ws, one, (2.0 * T)[:, None] * xs, -T[:, None], const], dim=1)

    def _where(self, mask: torch.Tensor, ncols: int) -> tuple[np.ndarray, np.ndarray]:
        flat = torch.nonzero(mask.reshape(-1)).reshape(-1).cpu().numpy()
        return np.divmod(flat, ncols)

    def screen(self, rows, T, cols, full: bool = False):
        r, c = self._idx(rows), self._idx(cols)
        Tt = torch.from_numpy(T).to(self.dev)
        if full:
            R = self._rowfeat(self.ws[r], self.nbx[r], self.xs[r], self.nx[r], Tt)
            S = R @ self.col_x[c].T
        else:
            R = self._rowfeat(self.ws[r], self.nb[r], self.zs[r], self.na[r], Tt)
            S = R @ self.col_z[c].T
        return self._where(S >= 0.0, len(cols))

    def sym_prepare(self, order: np.ndarray) -> None:
        """z-screen features in the order of the symmetric pass (see ``symmetric_pass``)."""
        self._o_src = self.f.perm[order]
        o = self._idx(order)
        self.o_col = self.col_z[o].contiguous()
        self.o_ws, self.o_nb, self.o_zs, self.o_na = self.ws[o], self.nb[o], self.zs[o], self.na[o]

    def sym_screen(self, s: int, e: int, T: np.ndarray, c0: int, c1: int):
        Tt = torch.from_numpy(T).to(self.dev)
        R = self._rowfeat(self.o_ws[s:e], self.o_nb[s:e], self.o_zs[s:e], self.o_na[s:e], Tt)
        return self._where(R @ self.o_col[c0:c1].T >= 0.0, c1 - c0)

    def sym_tight(self, rows, cols, Lr, Lc, cap):
        """See ``NumpyKernel.sym_tight``."""
        f = self.f
        r, c = self._idx(rows), self._idx(cols)
        G = -2.0 * (self.xs[r] @ self.xs[c].T)
        xub = G + self.nx_hi[r][:, None] + self.nx_hi[c][None, :]
        xlb = G + self.nx_lo[r][:, None] + self.nx_lo[c][None, :]
        Gy = -2.0 * (self.ws[r] @ self.ws[c].T)
        ylb = (Gy + self.nw_lo[r][:, None] + self.nw_lo[c][None, :]) / xub
        yub = Gy + self.nw_hi[r][:, None] + self.nw_hi[c][None, :]
        conv = f.scale_x / f.scale_y
        def lift(best) -> np.ndarray:
            return np.sqrt(np.maximum(best.double().cpu().numpy(), 0.0)) * conv * (1.0 - 1e-5)

        Lr = np.maximum(Lr, lift(ylb.amax(dim=1)))
        Lc = np.maximum(Lc, lift(ylb.amax(dim=0)))
        T = thresholds(Lr, f.scale_x, f.scale_y)
        if cap is not None:
            np.minimum(T, thresholds(np.array([min(cap, Lc.min())]), f.scale_x, f.scale_y)[0], out=T)
        Tt = torch.from_numpy(T).to(self.dev)
        ri, cj = self._where(yub >= Tt[:, None] * xlb, len(cols))
        return ri, cj, Lr, Lc

    def sym_exact(self, pi: np.ndarray, pj: np.ndarray) -> np.ndarray:
        """Exact quotients of pairs given by positions in the pass order."""
        return self.exact(self._o_src[pi], self._o_src[pj])

    def sym_release(self) -> None:
        self.o_col = self.o_ws = self.o_nb = self.o_zs = self.o_na = None

    def tight(self, rows, cols, L):
        f = self.f
        r, c = self._idx(rows), self._idx(cols)
        G = -2.0 * (self.xs[r] @ self.xs[c].T)
        xub = G + self.nx_hi[r][:, None] + self.nx_hi[c][None, :]
        xlb = G + self.nx_lo[r][:, None] + self.nx_lo[c][None, :]
        Gy = -2.0 * (self.ws[r] @ self.ws[c].T)
        ylb = Gy + self.nw_lo[r][:, None] + self.nw_lo[c][None, :]
        yub = Gy + self.nw_hi[r][:, None] + self.nw_hi[c][None, :]
        best = (ylb / xub).max(dim=1).values.double().cpu().numpy()
        Lnew = np.sqrt(np.maximum(best, 0.0)) * (f.scale_x / f.scale_y) * (1.0 - 1e-5)
        L = np.maximum(L, Lnew)
        T = torch.from_numpy(thresholds(L, f.scale_x, f.scale_y)).to(self.dev)
        ri, cj = self._where(yub >= T[:, None] * xlb, len(cols))
        return ri, cj, L

    def exact(self, gi, gj):
        i, j = self._idx(gi), self._idx(gj)
        dx = torch.sqrt(((self.X[i] - self.X[j]) ** 2).sum(dim=1)).cpu().numpy()
        dy = torch.sqrt(((self.Y[i] - self.Y[j]) ** 2).sum(dim=1)).cpu().numpy()
        # Sums of squares that may have under/overflowed: scaled recomputation on the host.
        for d, A in ((dx, self.Xn), (dy, self.Yn)):
            bad = np.flatnonzero((d < 1e-150) | (d > 1e150))
            if len(bad):
                d[bad] = pair_norms(A, np.asarray(gi)[bad], np.asarray(gj)[bad])
        with np.errstate(divide="ignore", invalid="ignore"):
            return dy / dx
