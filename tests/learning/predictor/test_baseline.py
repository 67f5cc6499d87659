"""The ridge baseline on the window (learning.predictor.baseline): masks and shapes."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.exceptions import NotFittedError

from learning.predictor import RidgeWindowBaseline


def test_ridge_baseline_respects_masks_and_shapes():
    rng = np.random.default_rng(7)
    xs = [rng.standard_normal((60, 3)) for _ in range(3)]
    ys = [np.column_stack([x[:, 0] + 2 * np.vstack([x[:1], x[:-1]])[:, 1]]) for x in xs]
    masks = [rng.random(60) < 0.7 for _ in xs]
    ys_bad = [np.where(m[:, None], y, 99.0) for y, m in zip(ys, masks)]
    base = RidgeWindowBaseline(lags=2, alpha=1e-8).fit(xs, ys_bad, masks)
    pred = base.predict(xs[0])
    assert pred.shape == (60, 1)
    np.testing.assert_allclose(pred[1:], ys[0][1:], atol=1e-5)  # row 0: repeated first sample
    with pytest.raises(ValueError, match="lags must be"):
        RidgeWindowBaseline(lags=0).fit(xs, ys)
    with pytest.raises(NotFittedError):
        RidgeWindowBaseline().predict(xs[0])
