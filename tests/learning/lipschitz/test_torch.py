"""The torch backend of learning.lipschitz on the CPU: the exact quotients and the numpy backend's partners."""

from __future__ import annotations

import numpy as np

from learning.lipschitz import pointwise_quotients
from tests.learning.lipschitz.test_quotients import assert_exact, brute_force


def test_torch_backend_cpu_matches():
    rng = np.random.default_rng(8)
    X = rng.normal(size=(900, 30))
    X = np.concatenate([X, X[:100] + 1e-9])
    Y = rng.normal(size=(1000, 3))
    q, p = pointwise_quotients(X, Y, return_partner=True, backend="torch", device="cpu")
    _, pn = pointwise_quotients(X, Y, return_partner=True, backend="numpy")
    assert_exact(q, brute_force(X, Y))
    assert np.array_equal(p, pn)
