"""Forecasts and their offline rows with a known error, for the skill tests."""

from __future__ import annotations

import numpy as np

from mpcshare.training.fast import FastRows


def fast_rows(n: int = 200, H1: int = 4, seed: int = 0):
    """Forecasts F (n, H1, 3) [m] = truth + N(0, 0.3²) and the rows they are scored on (two modes, one trial)."""
    rng = np.random.default_rng(seed)
    truth = np.cumsum(rng.normal(size=(n, H1, 3)), axis=1)
    F = truth + 0.3 * rng.normal(size=truth.shape)
    prev = np.arange(n) - 2
    prev[:2] = -1
    mode = rng.integers(0, 2, n)
    rows = FastRows(phi=np.zeros((n, 1)), slow=truth + rng.normal(size=truth.shape), truth=truth, mode=mode,
                    trial=np.zeros(n, int), prev=prev)
    return F, rows
