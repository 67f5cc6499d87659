"""Exactness of learning.lipschitz.pointwise_quotients against a float64 brute force."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from learning.lipschitz import SearchOptions, pointwise_quotients


def brute_force(X, Y, groups=None):
    """q_i and all maximising partners by the definition: float64 direct differences."""
    X = np.asarray(X, dtype=np.float64)
    Y = np.asarray(Y, dtype=np.float64)
    X = X[:, None] if X.ndim == 1 else X
    Y = Y[:, None] if Y.ndim == 1 else Y
    N = len(X)
    g = np.zeros(N) if groups is None else np.asarray(groups)
    q = np.zeros(N)
    for i in range(N):
        j = np.flatnonzero(g == g[i])
        j = j[j != i]
        dx = np.sqrt(((X[j] - X[i]) ** 2).sum(1))
        dy = np.sqrt(((Y[j] - Y[i]) ** 2).sum(1))
        keep = ~((dx == 0) & (dy == 0))
        with np.errstate(divide="ignore", invalid="ignore"):
            r = dy[keep] / dx[keep]
        if len(r):
            q[i] = max(0.0, r.max())
    return q


def assert_exact(q, ref, rtol=1e-9):
    q, ref = np.asarray(q), np.asarray(ref)
    assert q.shape == ref.shape
    assert np.array_equal(np.isinf(q), np.isinf(ref))
    fin = np.isfinite(ref)
    err = np.abs(q[fin] - ref[fin])
    assert np.all(err <= rtol * np.abs(ref[fin])), f"max rel err {np.max(err / np.maximum(ref[fin], 1e-300))}"


def assert_partner(X, Y, q, p, groups=None):
    """partner[i] attains q[i] (same group, j ≠ i), and is -1 exactly where q = 0."""
    X = np.asarray(X, dtype=np.float64).reshape(len(q), -1)
    Y = np.asarray(Y, dtype=np.float64).reshape(len(q), -1)
    assert np.array_equal(p < 0, q == 0)
    for i in np.flatnonzero(p >= 0):
        j = p[i]
        assert j != i
        if groups is not None:
            assert groups[j] == groups[i]
        dx = np.sqrt(((X[i] - X[j]) ** 2).sum())
        dy = np.sqrt(((Y[i] - Y[j]) ** 2).sum())
        r = np.inf if dx == 0 else dy / dx
        assert r == q[i] or abs(r - q[i]) <= 1e-9 * q[i]


def smooth_windows(n, seed, channels=4, lags=6):
    """Windowed smooth time series, the structure the pruning is built for."""
    rng = np.random.default_rng(seed)
    T = n + lags
    t = np.arange(T) / 10.0
    f = rng.uniform(0.05, 0.8, size=(channels, 3))
    ph = rng.uniform(0, 2 * np.pi, size=(channels, 3))
    o = np.sin(2 * np.pi * f[None] * t[:, None, None] + ph[None]).sum(-1)
    X = np.stack([o[lags - k: T - k] for k in range(lags)], axis=1).reshape(T - lags, -1)[:n]
    Y = np.tanh(X[:, :3]) + 0.1 * np.sin(np.arange(n) / 7.0)[:, None]
    return X, Y


# Sizes above the dense small-group path (512) so the bounds and screens are exercised.
@pytest.mark.parametrize("n,d,dy", [(700, 3, 1), (1200, 20, 3), (1500, 60, 2)])
def test_random_gaussian_exact(n, d, dy):
    rng = np.random.default_rng(n)
    X, Y = rng.normal(size=(n, d)), rng.normal(size=(n, dy))
    q, p = pointwise_quotients(X, Y, return_partner=True, backend="numpy")
    assert_exact(q, brute_force(X, Y))
    assert_partner(X, Y, q, p)


def test_windowed_exact_and_pruned():
    X, Y = smooth_windows(2500, 1)
    q, _, s = pointwise_quotients(X, Y, backend="numpy", block=64, return_stats=True)
    assert_exact(q, brute_force(X, Y))
    # The exact stage sees a small fraction of the ordered pairs.
    assert s.pairs_exact < 0.05 * 2 * s.n_pairs


def test_near_duplicates_exact():
    """X + 1e-9 noise: the float32 expansion would lose these pairs entirely."""
    rng = np.random.default_rng(3)
    base = rng.normal(size=(300, 12))
    X = np.repeat(base, 3, axis=0) + 1e-9 * rng.normal(size=(900, 12))
    Y = np.repeat(rng.normal(size=(300, 2)), 3, axis=0) + 1e-7 * rng.normal(size=(900, 2))
    q, p = pointwise_quotients(X, Y, return_partner=True, backend="numpy")
    ref = brute_force(X, Y)
    assert_exact(q, ref)
    assert_partner(X, Y, q, p)
    assert np.median(ref) > 1.0  # quotients set by the near-duplicate pairs


def test_large_offset_exact():
    """X + 1e6: ‖a‖²+‖b‖²−2ab cancels catastrophically; the result must not care."""
    rng = np.random.default_rng(4)
    X = rng.normal(size=(800, 10))
    Y = rng.normal(size=(800, 3))
    Xo = X + 1e6
    X2 = np.concatenate([Xo, Xo[:200] + 1e-6 * rng.normal(size=(200, 10))])
    Y2 = np.concatenate([Y, Y[:200] + 0.5])
    q = pointwise_quotients(X2, Y2 + 1e6, backend="numpy")
    assert_exact(q, brute_force(X2, Y2 + 1e6))


def test_exact_duplicates_inf_and_skipped():
    rng = np.random.default_rng(5)
    X = rng.normal(size=(600, 5))
    Y = rng.normal(size=(600, 2))
    X = np.concatenate([X, X[:100]])          # identical x ...
    Y = np.concatenate([Y, Y[:50], Y[50:100] + 1.0])  # ... same y (skipped) or different y (inf)
    q, p = pointwise_quotients(X, Y, return_partner=True, backend="numpy")
    ref = brute_force(X, Y)
    assert_exact(q, ref)
    assert np.isinf(q[50:100]).all() and np.isinf(q[650:700]).all()
    assert np.isfinite(q[:50]).all() and np.isfinite(q[600:650]).all()
    assert (p[50:100] == np.arange(650, 700)).all()
    assert_partner(X, Y, q, p)


def test_all_duplicates_same_output_gives_zero():
    X = np.ones((700, 3))
    Y = np.full((700, 2), 2.0)
    q, p = pointwise_quotients(X, Y, return_partner=True, backend="numpy")
    assert (q == 0).all() and (p == -1).all()


def test_constant_output():
    rng = np.random.default_rng(6)
    X = rng.normal(size=(900, 7))
    Y = np.full((900, 2), 3.5)
    q, p = pointwise_quotients(X, Y, return_partner=True, backend="numpy")
    assert (q == 0).all() and (p == -1).all()
    assert_exact(q, brute_force(X, Y))


def test_grouped_exact():
    rng = np.random.default_rng(7)
    X = rng.normal(size=(2000, 8))
    Y = rng.normal(size=(2000, 2))
    g = rng.choice([3, 10, 11, 42], size=2000, p=[0.45, 0.45, 0.05, 0.05])
    q, p = pointwise_quotients(X, Y, g, return_partner=True, backend="numpy")
    assert_exact(q, brute_force(X, Y, g))
    assert_partner(X, Y, q, p, g)


def test_single_point_and_singleton_groups():
    q, p = pointwise_quotients(np.zeros((1, 3)), np.ones((1, 2)), return_partner=True)
    assert q.tolist() == [0.0] and p.tolist() == [-1]
    X = np.arange(10.0)[:, None]
    Y = X ** 2
    q = pointwise_quotients(X, Y, groups=np.arange(10))
    assert (q == 0).all()
    q = pointwise_quotients(X, Y, groups=np.repeat([0, 1], 5))
    assert_exact(q, brute_force(X, Y, np.repeat([0, 1], 5)))


def test_one_dimensional_inputs():
    x = np.linspace(0, 1, 50)
    y = np.sin(3 * x)
    assert_exact(pointwise_quotients(x, y), brute_force(x, y))


def test_extreme_magnitudes_rescaled():
    """Differences of 1e-200 (squares underflow) and 1e200 (squares overflow) stay exact."""
    x = np.array([[0.0], [1e-200], [3e-200]])
    y = np.array([[0.0], [1e-200], [1e-200]])
    q = pointwise_quotients(x, y)
    assert np.allclose(q, [1.0, 1.0, 1 / 3], rtol=1e-12)
    q = pointwise_quotients(np.array([[0.0], [1e200], [3e200]]),
                            np.array([[0.0], [2e200], [2e200]]))
    assert np.allclose(q, [2.0, 2.0, 2 / 3], rtol=1e-12)


def test_threads_and_blocks_do_not_change_result():
    X, Y = smooth_windows(1600, 2)
    q1, p1 = pointwise_quotients(X, Y, return_partner=True, n_jobs=1, block=32, backend="numpy")
    q2, p2 = pointwise_quotients(X, Y, return_partner=True, n_jobs=2, block=300, backend="numpy")
    assert np.array_equal(q1, q2) and np.array_equal(p1, p2)


def test_progress_bar_runs_on_a_terminal_only(capsys, monkeypatch):
    import sys

    X, Y = smooth_windows(700, 3)
    q = pointwise_quotients(X, Y, progress=True, backend="numpy")
    assert capsys.readouterr().err == ""  # captured, as a pipe: no bar (learning.progress)
    assert_exact(q, brute_force(X, Y))
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True, raising=False)
    pointwise_quotients(X, Y, progress=True, backend="numpy")
    assert "Lipschitz" in capsys.readouterr().err


@pytest.mark.parametrize("X,Y,match", [
    (np.zeros((0, 2)), np.zeros((0, 1)), "X is empty"),
    (np.zeros((3, 2)), np.zeros((4, 1)), "X has 3 rows but Y has 4"),
    (np.zeros((3, 2, 1)), np.zeros((3, 1)), "X must be 1-D or 2-D"),
    (np.zeros((3, 0)), np.zeros((3, 1)), "X has no columns"),
    (np.array([[0.0], [np.nan], [1.0]]), np.zeros((3, 1)), "X contains NaN or inf at row 1"),
    (np.zeros((3, 1)), np.array([[0.0], [1.0], [np.inf]]), "Y contains NaN or inf at row 2"),
])
def test_input_errors(X, Y, match):
    with pytest.raises(ValueError, match=match):
        pointwise_quotients(X, Y)


def test_group_errors():
    with pytest.raises(ValueError, match="groups has 2 entries"):
        pointwise_quotients(np.zeros((3, 1)), np.zeros((3, 1)), groups=[0, 1])
    with pytest.raises(ValueError, match="backend"):
        pointwise_quotients(np.zeros((3, 1)), np.zeros((3, 1)), backend="cupy")


# Magnitudes where the naive sum of squares neither under- nor overflows (the
# implementation rescales those, see test_extreme_magnitudes_rescaled).
finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False, width=64).filter(
    lambda v: v == 0.0 or abs(v) > 1e-100)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(data=st.data(), n=st.integers(1, 40), d=st.integers(1, 4), dy=st.integers(1, 3))
def test_property_small_exact(data, n, d, dy):
    """Small inputs with many ties/duplicates drawn from a tiny value set."""
    vals = st.sampled_from([0.0, 1.0, -1.0, 0.5, 1e-9, 3.0]) | finite
    X = data.draw(arrays(np.float64, (n, d), elements=vals))
    Y = data.draw(arrays(np.float64, (n, dy), elements=vals))
    q, p = pointwise_quotients(X, Y, return_partner=True)
    assert_exact(q, brute_force(X, Y))
    assert_partner(X, Y, q, p)


@settings(max_examples=8, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(seed=st.integers(0, 2**31), n=st.integers(520, 900), d=st.integers(1, 24),
       dup=st.floats(0, 0.5), scale=st.sampled_from([1e-8, 1.0, 1e4]),
       offset=st.sampled_from([0.0, 1e5]))
def test_property_search_path_exact(seed, n, d, dup, scale, offset):
    """Search path (n > 512): random scale/offset and a fraction of near-duplicates."""
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, d)) * scale + offset
    Y = rng.normal(size=(n, 2))
    k = int(dup * n)
    if k:
        src = rng.integers(0, n - k, size=k)
        X[n - k:] = X[src] + rng.normal(size=(k, d)) * scale * 1e-7
    q = pointwise_quotients(X, Y, backend="numpy", block=64)
    assert_exact(q, brute_force(X, Y))


@pytest.mark.parametrize("tile,chunk", [(64, 128), (100, 192)])
def test_symmetric_pass_equals_one_sided(tile, chunk):
    """Each unordered pair screened once (both points credited) = the one-sided search,
    including the partner convention (smallest index among tied maximisers)."""
    X, Y = smooth_windows(1500, 9)
    rng = np.random.default_rng(9)
    # Exact ties: duplicated rows make several partners attain the same maximum.
    X = np.concatenate([X, X[:200], X[100:300] + 1e-9 * rng.normal(size=(200, X.shape[1]))])
    Y = np.concatenate([Y, Y[:200] + 0.01, Y[100:300]])
    sym = SearchOptions(search="symmetric", tile=tile, chunk=chunk)
    qs, ps = pointwise_quotients(X, Y, return_partner=True, backend="numpy", block=64, n_jobs=2,
                                 options=sym)
    q1, p1 = pointwise_quotients(X, Y, return_partner=True, backend="numpy", block=64, n_jobs=1,
                                 options=SearchOptions(search="per_leaf"))
    assert np.array_equal(qs, q1) and np.array_equal(ps, p1)
    assert_exact(qs, brute_force(X, Y))
    assert_partner(X, Y, qs, ps)
    # smallest maximiser: no j < partner attains q (checked on a sample of rows)
    for i in rng.choice(len(X), 60, replace=False):
        if ps[i] <= 0:
            continue
        j = np.arange(ps[i])
        j = j[j != i]
        dx = np.sqrt(((X[j] - X[i]) ** 2).sum(1))
        dy = np.sqrt(((Y[j] - Y[i]) ** 2).sum(1))
        with np.errstate(divide="ignore", invalid="ignore"):
            r = dy / dx
        assert not np.any(r == qs[i])


@pytest.mark.parametrize("backend", ["numpy", "torch"])
def test_symmetric_full_d_mode_iid(backend):
    """i.i.d. data switches the symmetric pass to the full-d two-sided screen; still exact."""
    rng = np.random.default_rng(12)
    X = rng.normal(size=(1400, 40))
    X = np.concatenate([X, X[:100] + 1e-9 * rng.normal(size=(100, 40))])
    Y = rng.normal(size=(1500, 2))
    q, p, s = pointwise_quotients(X, Y, backend=backend, device="cpu" if backend == "torch" else None,
                                  n_jobs=2, options=SearchOptions(tile=128, chunk=512),
                                  return_stats=True)
    assert s.pairs_full_screened > 0.3 * s.n_pairs
    assert_exact(q, brute_force(X, Y))
    assert_partner(X, Y, q, p)


def test_symmetric_pass_chooses_the_screen_per_chunk():
    """Low-rank smooth points and i.i.d. points in one group: chunks of the same pass
    use the z screen where it prunes and the full-d screen where it does not; exact."""
    rng = np.random.default_rng(3)
    t = np.linspace(0, 20, 1500)[:, None]
    smooth = np.sin(t * rng.uniform(0.2, 2.0, size=(1, 40)) + rng.uniform(0, 6, size=(1, 40)))
    X = np.concatenate([smooth, 0.3 * rng.normal(size=(1500, 40))])
    Y = np.concatenate([np.sin(t * np.array([[0.7, 1.3]])), rng.normal(size=(1500, 2))])
    q, p, s = pointwise_quotients(X, Y, n_jobs=2, options=SearchOptions(tile=128, chunk=512),
                                  return_stats=True)
    assert s.pairs_screened > 0.2 * s.n_pairs
    assert s.pairs_full_screened > 0.2 * s.n_pairs
    assert_exact(q, brute_force(X, Y))
    assert_partner(X, Y, q, p)


def test_stats_are_returned_per_call_and_default_return_is_unchanged():
    """No state between calls: each call returns its own counters; the default result
    is the bare array, with the same values."""
    X, Y = smooth_windows(900, 4)
    small = pointwise_quotients(X[:600], Y[:600], backend="numpy", return_stats=True)
    big = pointwise_quotients(X, Y, backend="numpy", return_stats=True)
    assert small.stats.n_pairs == 600 * 599 // 2 and big.stats.n_pairs == 900 * 899 // 2
    assert big.stats.to_dict()["n_pairs"] == big.stats.n_pairs
    q = pointwise_quotients(X, Y, backend="numpy")
    assert isinstance(q, np.ndarray) and np.array_equal(q, big.q)
    q, p = pointwise_quotients(X, Y, backend="numpy", return_partner=True)
    assert np.array_equal(p, big.partner)
    dense = pointwise_quotients(X[:600], Y[:600], backend="numpy",
                                options=SearchOptions(small_group=600), return_stats=True)
    assert np.array_equal(dense.q, small.q)
    assert dense.stats.pairs_exact == 600 * 599 and dense.stats.pairs_screened == 0
    with pytest.raises(ValueError, match="search must be 'symmetric' or 'per_leaf'"):
        SearchOptions(search="fast")


@pytest.mark.parametrize("name", ["warmup_leaves", "multi_warmup_leaves", "tile", "chunk", "small_group"])
def test_search_options_name_the_bad_setting(name):
    with pytest.raises(ValueError, match=f"{name} must be a positive integer"):
        SearchOptions(**{name: 0})


def test_warmup_leaves_change_the_work_not_the_result():
    X, Y = smooth_windows(4000, seed=3)
    one = pointwise_quotients(X, Y, backend="numpy", return_stats=True, options=SearchOptions(warmup_leaves=1))
    four = pointwise_quotients(X, Y, backend="numpy", return_stats=True, options=SearchOptions(warmup_leaves=4))
    assert np.array_equal(one.q, four.q) and np.array_equal(one.partner, four.partner)
    assert one.stats.pairs_full_screened != four.stats.pairs_full_screened
