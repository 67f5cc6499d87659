"""Step-by-step NumPy inference of the reactive predictor's LSTM, for the control loop.

Written by hand because one PyTorch call costs hundreds of µs of dispatch per step on
the target machine (``benchmarks/bench_learned.py``: ~17× slower than this at p50),
while the control tick allows 200 µs for the predictor.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["PredictorStream"]


class PredictorStream:
    """Step-by-step LSTM inference in NumPy (float64) carrying (h, c) between calls.

    ``step(x (d_in,)) -> (d_u,)`` standardised action now; with ``horizons = H > 0`` the
    read-out holds H + 1 stacked actions and :attr:`forecast` (H+1, d_u) keeps the last
    step's whole forecast (row h: h model steps ahead). ``reset()`` returns to the zero
    state (the state :meth:`ReactivePredictor.predict` starts from). A wrong shape or a
    non-finite input raises ValueError and leaves the state unchanged.

    Per step: ``z = W [x; h] + b`` with the rows of the i, f, o gates pre-scaled by ½, so
    that one ``tanh`` gives all four gates (σ(v) = ½ + ½·tanh(v/2)); then
    ``c = f ⊙ c + i ⊙ g``, ``h = o ⊙ tanh(c)``, ``û = W_y h + b_y``.
    """

    def __init__(self, w_ih: np.ndarray, w_hh: np.ndarray, bias: np.ndarray, w_out: np.ndarray,
                 b_out: np.ndarray, horizons: int = 0) -> None:
        H, d = int(w_hh.shape[1]), int(w_ih.shape[1])
        W = np.hstack([w_ih, w_hh]).astype(float)   # rows in torch order i, f, g, o
        b = np.asarray(bias, dtype=float)
        order = np.r_[0:2 * H, 3 * H:4 * H, 2 * H:3 * H]   # → i, f, o, g
        scale = np.r_[np.full(3 * H, 0.5), np.ones(H)]
        self._W = np.ascontiguousarray(W[order] * scale[:, None])
        self._b = b[order] * scale
        self._w_out = np.ascontiguousarray(w_out, dtype=float)
        self._b_out = np.asarray(b_out, dtype=float).copy()
        self._v = np.zeros(d + H)
        n_h = int(horizons) + 1
        if w_out.shape[0] % n_h:
            raise ValueError(f"read-out has {w_out.shape[0]} rows, not a multiple of horizons + 1 = {n_h}")
        self.hidden_size, self.input_dim, self.output_dim = H, d, int(w_out.shape[0]) // n_h
        self.horizons = n_h - 1
        self.reset()

    def reset(self) -> None:
        """Zero hidden and cell state."""
        self.h = np.zeros(self.hidden_size)
        self.c = np.zeros(self.hidden_size)
        self.forecast = np.full((self.horizons + 1, self.output_dim), np.nan)

    def step(self, x: np.ndarray) -> np.ndarray:
        """One LSTM cell update and the read-out (class docstring)."""
        x = np.asarray(x, dtype=float)
        if x.shape != (self.input_dim,):
            raise ValueError(f"stream input must have shape ({self.input_dim},), got {x.shape}")
        if not math.isfinite(x.sum()):
            raise ValueError("stream input is not finite; state left unchanged")
        H, d, v = self.hidden_size, self.input_dim, self._v
        v[:d] = x
        v[d:] = self.h
        z = self._W @ v
        z += self._b
        np.tanh(z, out=z)
        gates = z[:3 * H]
        gates *= 0.5
        gates += 0.5
        c = gates[H:2 * H] * self.c
        c += gates[:H] * z[3 * H:]
        self.c = c
        self.h = gates[2 * H:3 * H] * np.tanh(c)
        y = self._w_out @ self.h + self._b_out
        self.forecast = y.reshape(self.horizons + 1, self.output_dim)
        return y[:self.output_dim]
