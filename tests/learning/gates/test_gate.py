"""Tests of learning.gates.gate: per-mode calibrated gates, constant gates, fast path."""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.exceptions import NotFittedError
from sklearn.metrics import accuracy_score, brier_score_loss

from learning.gates.gate import ModeGates
from learning.lipschitz import pointwise_quotients
from learning.preprocessing.preprocess import Preprocessor, Standardizer, causal_windows
from learning.preprocessing.resample import causal_downsample
from sim.demonstrator import generate_demonstrations


def separable(n: int, D: int = 6, n_modes: int = 3, seed: int = 0, noise: float = 0.0):
    """Rows whose label is 1 inside a mode-specific ball, 0 outside (flipped with prob. ``noise``)."""
    rng = np.random.default_rng(seed)
    X = rng.standard_normal((n, D))
    m = rng.integers(0, n_modes, n)
    centres = np.linspace(-0.5, 0.5, n_modes)[:, None] * np.ones(D)
    r = np.linalg.norm(X - centres[m], axis=1)
    y = (r < np.median(r)).astype(int)
    flip = rng.random(n) < noise
    y[flip] = 1 - y[flip]
    return X, m, y


@pytest.fixture(scope="module")
def demo_windows():
    """2 subjects × 1.5 min of the generator, causal 10 Hz, standardised, RMS windows, with
    labels Z = within-mode quotient ≤ its 70th percentile; mode 1 forced all-predictable."""
    demos = causal_downsample(generate_demonstrations(2, 1.5, seed=3))
    pre = Preprocessor(obs=Standardizer("sensor", field="obs").fit(demos),
                       act=Standardizer("sensor", field="act").fit(demos), target_hz=10.0, window_s=1.0)
    w = causal_windows(pre.standardize(demos), 1.0, rms=True)
    q = pointwise_quotients(w.X, w.Y, groups=w.mode)
    Z = np.zeros(len(w), dtype=int)
    for j in np.unique(w.mode):
        sel = w.mode == j
        Z[sel] = q[sel] <= np.percentile(q[sel], 70)
    Z[w.mode == 1] = 1
    return w, Z


def test_gates_on_demonstrations_with_one_class_mode_and_empty_mode(demo_windows):
    w, Z = demo_windows
    n_modes = int(w.mode.max()) + 2  # the last mode has no points
    g = ModeGates(min_class_count=10, seed=0).fit(w.X, w.mode, Z, n_modes)
    assert set(g.constant_modes_) == {1, n_modes - 1}
    assert g.constant_modes_[1]["value"] == 1 and g.constant_modes_[1]["n_negative"] == 0
    assert g.constant_modes_[n_modes - 1]["value"] == 0
    assert "no training points" in g.constant_modes_[n_modes - 1]["reason"]
    p = g.predict_proba(w.X, w.mode)
    assert np.all(p[w.mode == 1] == 1.0)
    assert g.proba_one(w.X[0], n_modes - 1) == 0.0
    # the fitted gates separate the labels on their training data better than chance
    for j in (0, 2, 3):
        sel = w.mode == j
        assert type(g.gates_[j].named_steps["gate"]).__name__ == "CalibratedClassifierCV"
        assert brier_score_loss(Z[sel], p[sel]) < brier_score_loss(Z[sel], np.full(sel.sum(), Z[sel].mean()))
    d = g.describe()
    assert d["constant_modes"]["1"]["value"] == 1 and len(d["n_train"]) == n_modes


def test_min_class_count_makes_minority_mode_constant():
    X, m, y = separable(600, n_modes=2, seed=1)
    y[m == 0] = 1
    y[np.flatnonzero(m == 0)[:5]] = 0  # 5 negatives < min_class_count
    g = ModeGates(min_class_count=20).fit(X, m, y, 2)
    assert list(g.constant_modes_) == [0]
    assert g.constant_modes_[0]["n_negative"] == 5 and g.constant_modes_[0]["value"] == 1
    assert g.predict(X[m == 0], m[m == 0]).tolist() == [1] * int((m == 0).sum())


@pytest.mark.parametrize("kernel", ["rbf", "nystroem"])
def test_calibrated_and_better_than_constant_on_separable_data(kernel):
    X, m, y = separable(3000, seed=2, noise=0.05)
    Xt, mt, yt = separable(1500, seed=3, noise=0.05)
    g = ModeGates(kernel=kernel, n_components=150, seed=0).fit(X, m, y, 3)
    p = g.predict_proba(Xt, mt)
    assert p.min() >= 0.0 and p.max() <= 1.0
    brier_const = brier_score_loss(yt, np.full(yt.size, y.mean()))
    assert brier_score_loss(yt, p) < 0.5 * brier_const
    assert accuracy_score(yt, p >= 0.5) > 0.85
    # calibration: in the confident bins the positive rate follows the probability
    assert abs(p.mean() - yt.mean()) < 0.05
    hi, lo = p > 0.8, p < 0.2
    assert yt[hi].mean() > 0.8 and yt[lo].mean() < 0.2


@pytest.mark.parametrize("kernel", ["rbf", "nystroem"])
def test_fast_path_equals_sklearn(kernel):
    X, m, y = separable(900, D=10, seed=4, noise=0.1)
    m[m == 2] = 1
    y[m == 0] = 0  # mode 0 single-class → constant
    g = ModeGates(kernel=kernel, n_components=80, seed=5).fit(X, m, y, 3)
    Xt, mt, _ = separable(300, D=10, seed=6)
    Xt[:5] *= 40.0  # far from every support vector: probability from the intercept only
    p = g.predict_proba(Xt, mt)
    fast = np.array([g.proba_one(x, j) for x, j in zip(Xt, mt)])
    np.testing.assert_allclose(fast, p, rtol=0, atol=1e-9)
    assert isinstance(g.proba_one(Xt[0], np.int64(1)), float)


def test_subsample_is_stratified_seeded_and_capped():
    X, m, y = separable(4000, n_modes=2, seed=7, noise=0.1)
    g1 = ModeGates(max_samples_per_mode=500, seed=11).fit(X, m, y, 2)
    g2 = ModeGates(max_samples_per_mode=500, seed=11).fit(X, m, y, 2)
    g3 = ModeGates(max_samples_per_mode=500, seed=12).fit(X, m, y, 2)
    assert g1.n_train_ == [500, 500]
    Xt, mt, _ = separable(200, n_modes=2, seed=8)
    np.testing.assert_array_equal(g1.predict_proba(Xt, mt), g2.predict_proba(Xt, mt))
    assert not np.array_equal(g1.predict_proba(Xt, mt), g3.predict_proba(Xt, mt))
    # stratified: the kept positive share equals the mode's share (to one row)
    for j in range(2):
        rows = g1.train_rows_[j]
        assert np.all(m[rows] == j) and np.unique(rows).size == 500
        assert abs(y[rows].sum() - 500 * y[m == j].mean()) <= 1.0
        assert len(g1.gates_[j].named_steps["gate"].calibrated_classifiers_) == g1.n_folds
    # a rare class keeps at least min_class_count rows (its proportional share would be 2)
    yr = np.zeros_like(y)
    yr[np.flatnonzero(m == 0)[:25]] = 1
    yr[np.flatnonzero(m == 1)[:-25]] = 1
    rare = ModeGates(max_samples_per_mode=200, min_class_count=20).fit(X, m, yr, 2)
    assert yr[rare.train_rows_[0]].sum() == 20 and (1 - yr[rare.train_rows_[1]]).sum() == 20
    assert rare.n_train_ == [200, 200]
    full = ModeGates(max_samples_per_mode=None).fit(X, m, y, 2)
    assert full.n_train_ == [int((m == 0).sum()), int((m == 1).sum())]


def test_bad_input_errors():
    X, m, y = separable(300, seed=12)
    with pytest.raises(NotFittedError):
        ModeGates().predict_proba(X, m)
    with pytest.raises(NotFittedError):
        ModeGates().proba_one(X[0], 0)
    with pytest.raises(ValueError, match="kernel must be one of"):
        ModeGates(kernel="poly").fit(X, m, y, 3)
    with pytest.raises(ValueError, match="labels must be 0 or 1"):
        ModeGates().fit(X, m, np.where(y == 1, 2, 0), 3)
    with pytest.raises(ValueError, match=r"modes\[\d+\] = 3 is outside 0..2"):
        ModeGates().fit(X, np.where(m == 0, 3, m), y, 3)
    with pytest.raises(ValueError, match="modes must have shape"):
        ModeGates().fit(X, m[:-1], y, 3)
    with pytest.raises(ValueError, match="labels must have shape"):
        ModeGates().fit(X, m, y[:-1], 3)
    with pytest.raises(ValueError, match="2-D"):
        ModeGates().fit(X[:, 0], m, y, 3)
    with pytest.raises(ValueError, match="modes must be integers"):
        ModeGates().fit(X, m + 0.5, y, 3)
    bad = X.copy()
    bad[7, 2] = np.nan
    with pytest.raises(ValueError, match="row 7 is not finite"):
        ModeGates().fit(bad, m, y, 3)
    g = ModeGates().fit(X, m, y, 3)
    with pytest.raises(ValueError, match="have 5 features, the gates were fitted on 6"):
        g.predict_proba(X[:, :5], m)
    with pytest.raises(ValueError, match=r"window must have shape \(6,\)"):
        g.proba_one(X[:2], 0)
    with pytest.raises(ValueError, match="mode must be an integer in 0..2"):
        g.proba_one(X[0], 3)
    with pytest.raises(ValueError, match="threshold"):
        g.predict(X, m, threshold=1.5)
