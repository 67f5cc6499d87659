"""Validation and batching of trial sequences for the sequence models (LSTM predictor, ridge baseline).

A *sequence set* is a list of per-trial arrays: inputs (T_i, d_in), targets (T_i, d_u)
and boolean masks (T_i,) (True = the step counts in the loss).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["check_sequence_set", "chunk_sequences", "pad_sequences", "shifted_targets"]


def check_sequence_set(sequences: Any, targets: Any = None, masks: Any = None, *, what: str = "sequences",
                       d_in: int | None = None, d_out: int | None = None
                       ) -> tuple[list[np.ndarray], list[np.ndarray] | None, list[np.ndarray] | None]:
    """Validate a list of (T_i, d_in) inputs, (T_i, d_u) targets and (T_i,) bool masks.

    ``masks=None`` means every step counts. Errors name the list, the sequence and the row.
    """
    if isinstance(sequences, np.ndarray) or not isinstance(sequences, Sequence):
        raise TypeError(f"{what} must be a list of (T, d) arrays, one per trial; got {type(sequences).__name__}")
    if len(sequences) == 0:
        raise ValueError(f"{what} is empty: need at least one trial")
    xs: list[np.ndarray] = []
    for i, s in enumerate(sequences):
        a = np.asarray(s, dtype=float)
        if a.ndim != 2 or a.shape[0] < 1:
            raise ValueError(f"{what}[{i}] must be 2-D (T, d) with T ≥ 1, got shape {a.shape}")
        d_ref = d_in if d_in is not None else (xs[0].shape[1] if xs else a.shape[1])
        if a.shape[1] != d_ref:
            raise ValueError(f"{what}[{i}] has {a.shape[1]} input channels, expected {d_ref}")
        bad = np.flatnonzero(~np.isfinite(a).all(axis=1))
        if bad.size:
            raise ValueError(f"{what}[{i}] row {bad[0]} is not finite")
        xs.append(a)
    ys = None
    if targets is not None:
        if isinstance(targets, np.ndarray) or not isinstance(targets, Sequence) or len(targets) != len(xs):
            raise ValueError(f"targets for {what} must be a list of {len(xs)} arrays (one per trial)")
        ys = []
        for i, (t, a) in enumerate(zip(targets, xs)):
            b = np.asarray(t, dtype=float)
            d_ref = d_out if d_out is not None else (ys[0].shape[1] if ys else (b.shape[1] if b.ndim == 2 else -1))
            if b.shape != (a.shape[0], d_ref):
                raise ValueError(f"targets[{i}] of {what} must have shape ({a.shape[0]}, {d_ref}), got {b.shape}")
            bad = np.flatnonzero(~np.isfinite(b).all(axis=1))
            if bad.size:
                raise ValueError(f"targets[{i}] of {what}: row {bad[0]} is not finite")
            ys.append(b)
    ms = None
    if masks is not None:
        if isinstance(masks, np.ndarray) or not isinstance(masks, Sequence) or len(masks) != len(xs):
            raise ValueError(f"masks for {what} must be a list of {len(xs)} boolean arrays (one per trial)")
        ms = []
        for i, (m, a) in enumerate(zip(masks, xs)):
            mm = np.asarray(m)
            if mm.shape != (a.shape[0],) or mm.dtype != bool:
                raise ValueError(f"masks[{i}] of {what} must be a bool array of shape ({a.shape[0]},), "
                                 f"got {mm.dtype} {mm.shape}")
            ms.append(mm)
    return xs, ys, ms


def chunk_sequences(xs: list[np.ndarray], ys: list[np.ndarray], ms: list[np.ndarray], chunk_len: int,
                    burn_in: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Cut sequences into chunks ``[s − burn_in, s + chunk_len)`` (clipped at 0 and T), right-padded.

    The loss weight is the mask on ``[s, s + chunk_len)`` and 0 on the burn-in and padding
    (right padding never changes the outputs before it). Chunks without a loss step are dropped.
    """
    L = chunk_len + burn_in
    d_in, d_out = xs[0].shape[1], ys[0].shape[1]
    X, Y, W = [], [], []
    for x, y, m in zip(xs, ys, ms):
        for s in range(0, x.shape[0], chunk_len):
            a, b = max(0, s - burn_in), min(x.shape[0], s + chunk_len)
            w = m[a:b].astype(np.float32)
            w[: s - a] = 0.0
            if not w.any():
                continue
            cx, cy, cw = np.zeros((L, d_in), np.float32), np.zeros((L, d_out), np.float32), np.zeros(L, np.float32)
            cx[: b - a], cy[: b - a], cw[: b - a] = x[a:b], y[a:b], w
            X.append(cx)
            Y.append(cy)
            W.append(cw)
    return np.stack(X), np.stack(Y), np.stack(W)


def pad_sequences(xs: list[np.ndarray], ys: list[np.ndarray], ms: list[np.ndarray]
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Whole sequences right-padded to the longest, with loss weights = mask (0 on padding)."""
    T = max(x.shape[0] for x in xs)
    X = np.zeros((len(xs), T, xs[0].shape[1]), np.float32)
    Y = np.zeros((len(xs), T, ys[0].shape[1]), np.float32)
    W = np.zeros((len(xs), T), np.float32)
    for k, (x, y, m) in enumerate(zip(xs, ys, ms)):
        X[k, : x.shape[0]], Y[k, : x.shape[0]], W[k, : x.shape[0]] = x, y, m
    return X, Y, W


def shifted_targets(y: np.ndarray, horizons: int) -> np.ndarray:
    """(T, d_u) → (T, d_u·(H+1)): row t is ``[y_t, y_{t+1}, …, y_{t+H}]`` (y_{T−1} repeated past the end)."""
    T = y.shape[0]
    idx = np.minimum(np.arange(T)[:, None] + np.arange(horizons + 1)[None, :], T - 1)
    return y[idx].reshape(T, -1)
