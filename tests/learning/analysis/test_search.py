"""Tests of learning.analysis.search: the within-grouping quotients of the search."""

from __future__ import annotations

import numpy as np
import pytest

from learning.analysis.reference import mode_evidence
from learning.analysis.search import within_group_quotients
from learning.lipschitz import pointwise_quotients


def _data(n: int = 1500, seed: int = 0):
    rng = np.random.default_rng(seed)
    t = np.arange(n) / 10.0
    X = np.column_stack([np.sin(t * f) for f in (0.3, 0.7, 1.1, 1.9)]) + 0.05 * rng.normal(size=(n, 4))
    Y = np.tanh(X[:, :2]) + 0.3 * (np.arange(n) // 100 % 2)[:, None]
    return X, Y


def test_within_group_quotients_equal_one_call_each_and_report_progress():
    X, Y = _data()
    rng = np.random.default_rng(1)
    groupings = {("modes", 2): np.arange(len(X)) // 100 % 2, ("reference", 2): rng.integers(0, 2, len(X)),
                 ("modes", 3): np.arange(len(X)) // 60 % 3}
    calls = []
    got = within_group_quotients(X, Y, groupings, done=lambda: calls.append(1))
    assert list(got) == list(groupings) and len(calls) == 3
    for key, g in groupings.items():
        assert np.array_equal(got[key], pointwise_quotients(X, Y, g))
    assert within_group_quotients(X, Y, {}) == {}


def test_mode_evidence_takes_known_reference_quotients_and_checks_them():
    X, Y = _data(800)
    trial = np.arange(len(X)) // 80
    labels = np.arange(len(X)) // 100 % 2
    ref = (np.arange(len(X)) // 50) % 2
    kw = dict(n_random=2, seed=0, reference_labels=ref)
    fresh = mode_evidence(X, Y, trial, np.arange(len(X)), X, labels, **kw)
    q_ref = pointwise_quotients(X, Y, ref)
    known = mode_evidence(X, Y, trial, np.arange(len(X)), X, labels, q_reference=q_ref, **kw)
    assert np.array_equal(known.q_reference, fresh.q_reference)
    assert known.vs_reference.p_value == fresh.vs_reference.p_value
    assert known.vs_reference.effect == fresh.vs_reference.effect
    with pytest.raises(ValueError, match=r"q_reference must be \(800,\)"):
        mode_evidence(X, Y, trial, np.arange(len(X)), X, labels, q_reference=q_ref[:-1], **kw)
    with pytest.raises(ValueError, match="needs the reference_labels"):
        mode_evidence(X, Y, trial, np.arange(len(X)), X, labels, n_random=2, q_reference=q_ref)
