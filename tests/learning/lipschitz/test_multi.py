"""learning.lipschitz.pointwise_quotients_multi: every labeling equals its own
pointwise_quotients call (same bits, same partner) and a float64 brute force."""

from __future__ import annotations

import numpy as np
import pytest

from learning.lipschitz import SearchOptions, pointwise_quotients, pointwise_quotients_multi
from tests.learning.lipschitz.test_quotients import assert_exact, brute_force, smooth_windows


def _labelings(n: int, seed: int, coherent: np.ndarray | None = None) -> np.ndarray:
    """No grouping, random groupings of several sizes, and optionally a coherent one."""
    rng = np.random.default_rng(seed)
    labs = [np.zeros(n, dtype=np.int64), rng.integers(0, 4, n), rng.integers(0, 2, n),
            rng.permutation(np.arange(n) % 3)]
    if coherent is not None:
        labs.append(coherent)
    return np.stack(labs)


def _check(X, Y, labs, **kw):
    Q, P = pointwise_quotients_multi(X, Y, labs, return_partner=True, **kw)
    assert Q.shape == P.shape == labs.shape
    for m, g in enumerate(labs):
        q, p = pointwise_quotients(X, Y, g, return_partner=True, backend="numpy")
        assert np.array_equal(Q[m], q), f"labeling {m}: differs from the single-labeling call"
        assert np.array_equal(P[m], p), f"labeling {m}: partner differs"
        assert_exact(Q[m], brute_force(X, Y, g))
    return Q


def test_windowed_many_labelings_equal_single_calls_and_brute_force():
    X, Y = smooth_windows(1500, seed=3)
    coherent = (X[:, 0] > np.median(X[:, 0])).astype(int)  # a grouping coherent in x
    _check(X, Y, _labelings(len(X), 0, coherent))


def test_iid_data_full_screen_path():
    rng = np.random.default_rng(1)
    X, Y = rng.normal(size=(1400, 12)), rng.normal(size=(1400, 2))
    _check(X, Y, _labelings(len(X), 1), n_jobs=2)


def test_duplicates_ties_and_inf():
    """Identical x and y (skipped), identical x with different y (inf), exact ties."""
    X, Y = smooth_windows(900, seed=5, channels=2, lags=3)
    X[100:110] = X[50]  # identical x ...
    Y[100:105] = Y[50]  # ... and y for some (skipped), different y for others (inf)
    X[600:700] = np.round(X[600:700], 1)  # many ties in x
    Y[600:700] = np.round(Y[600:700], 1)
    Q = _check(X, Y, _labelings(len(X), 2))
    assert np.isinf(Q[0]).any()


def test_dense_small_path_and_threads():
    X, Y = smooth_windows(300, seed=7)
    labs = _labelings(len(X), 3)
    _check(X, Y, labs)
    Q1 = pointwise_quotients_multi(X, Y, labs, n_jobs=1, options=SearchOptions(small_group=8))
    Q2 = pointwise_quotients_multi(X, Y, labs, n_jobs=2, options=SearchOptions(small_group=8), block=32)
    assert np.array_equal(Q1, Q2)
    assert np.array_equal(Q1, pointwise_quotients_multi(X, Y, labs))


def test_constant_output_and_singletons():
    X, _ = smooth_windows(700, seed=8)
    Q = pointwise_quotients_multi(X, np.ones(len(X)), _labelings(len(X), 4))
    assert np.all(Q == 0)
    Q, P = pointwise_quotients_multi(X[:5], X[:5, :1], np.arange(5)[None], return_partner=True)
    assert np.all(Q == 0) and np.all(P == -1)


def test_one_labeling_1d_and_any_label_values():
    X, Y = smooth_windows(800, seed=9)
    g = np.where(np.arange(len(X)) % 5 == 0, "a", "b")
    Q = pointwise_quotients_multi(X, Y, g)
    assert Q.shape == (1, len(X))
    assert np.array_equal(Q[0], pointwise_quotients(X, Y, g))


@pytest.mark.parametrize("labs, match", [
    (np.zeros((2, 5)), r"\(L, 6\).*shape \(2, 5\)"),
    (np.zeros((2, 3, 6)), r"shape \(2, 3, 6\)"),
    (np.zeros((0, 6)), "empty"),
    (np.array([[0, 1, np.nan, 0, 1, 1.0]]), "labeling 0, row 2"),
])
def test_labeling_errors_name_the_shape(labs, match):
    X = np.arange(12.0).reshape(6, 2)
    with pytest.raises(ValueError, match=match):
        pointwise_quotients_multi(X, X[:, :1], labs)
