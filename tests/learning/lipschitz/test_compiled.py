"""The compiled updates (learning.lipschitz._compiled) keep the smallest partner."""

from __future__ import annotations

import numpy as np

from learning.lipschitz._compiled import credit_multi, update_best_compiled


def test_compiled_update_and_credit_keep_smallest_partner():
    q, p = np.zeros(3), np.full(3, -1)
    update_best_compiled(q, p, np.array([0, 0, 0, 1]), np.array([5, 2, 7, 4]),
                         np.array([2.0, 2.0, 1.0, np.nan]))
    assert q.tolist() == [2.0, 0.0, 0.0] and p.tolist() == [2, -1, -1]
    labels = np.array([[0, 0], [0, 1], [0, 0]])  # (N, L)
    Q, P, LB = np.zeros((3, 2)), np.full((3, 2), -1), np.zeros((3, 2))
    tmin, qmin = np.zeros(3), np.zeros(3)
    credit_multi(Q, P, LB, tmin, qmin, labels, np.array([0, 0]), np.array([1, 2]), np.array([3.0, 3.0]))
    assert Q.tolist() == [[3.0, 3.0], [3.0, 0.0], [3.0, 3.0]]
    assert P.tolist() == [[1, 2], [0, -1], [0, 0]]
    assert tmin.tolist() == [3.0, 0.0, 3.0] and qmin.tolist() == [3.0, 0.0, 3.0]
