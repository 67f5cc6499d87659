"""The exact pair quotients (learning.lipschitz._exact): conventions for ties and the float64 range."""

from __future__ import annotations

import numpy as np

from learning.lipschitz import pair_norms, pair_ratios


def test_compiled_pair_ratios_conventions_and_range():
    rng = np.random.default_rng(0)
    X = rng.normal(size=(50, 7)) * 10.0 ** rng.integers(-140, 140, size=(50, 1))
    Y = rng.normal(size=(50, 2)) * 10.0 ** rng.integers(-140, 140, size=(50, 1))
    X[1], Y[1] = X[0], Y[0]  # identical pair: skipped (NaN)
    X[2] = X[0]  # identical x, different y: inf
    X[3] = X[4] + 1e-170  # sum of squares underflows: scaled recomputation
    Y[5], Y[6] = 1e200, -1e200  # sum of squares overflows: scaled recomputation
    i, j = np.meshgrid(np.arange(50), np.arange(50), indexing="ij")
    i, j = i.ravel(), j.ravel()
    r = pair_ratios(X, Y, i, j)
    ref = pair_norms(Y, i, j) / np.where(pair_norms(X, i, j) == 0, np.nan, pair_norms(X, i, j))
    same = (X[i] == X[j]).all(1)
    assert np.all(np.isnan(r[same & (Y[i] == Y[j]).all(1)]))
    assert np.all(np.isinf(r[same & ~(Y[i] == Y[j]).all(1)]))
    ok = ~same
    assert np.all(np.abs(r[ok] - ref[ok]) <= 1e-13 * ref[ok])
    assert np.array_equal(r, pair_ratios(X, Y, j, i), equal_nan=True)  # r_ij == r_ji bit for bit
