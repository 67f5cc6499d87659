"""The fit recovers a rule the features determine; one level gives the constant rule."""

from __future__ import annotations

import numpy as np
import pytest

from research.learned_rule.fit import fit_rule


def test_recovers_a_separable_rule():
    rng = np.random.default_rng(0)
    X = rng.normal(size=(600, 4))
    level = np.where(X[:, 0] > 0.5, 1.0, np.where(X[:, 1] > 0, 0.5, 0.0))
    rule = fit_rule(X, level, 2, C=100.0)
    assert rule.alphas.tolist() == [0.0, 0.5, 1.0]
    assert np.mean(rule.alphas[np.argmax(rule.proba(X), axis=1)] == level) > 0.9


def test_two_levels_and_one_level():
    X = np.linspace(-1, 1, 50)[:, None]
    two = fit_rule(X, (X[:, 0] > 0).astype(float), 2)
    assert two.coef.shape == (2, 1) and two.proba(np.array([1.0]))[1] > 0.5 > two.proba(np.array([-1.0]))[1]
    one = fit_rule(X, np.full(50, 0.75), 2)
    assert one.alphas.tolist() == [0.75] and one.proba(X).tolist() == [[1.0]] * 50


def test_bad_input_raises():
    with pytest.raises(ValueError, match="X \\(N, F\\)"):
        fit_rule(np.zeros((3, 2)), np.zeros(4), 2)
    with pytest.raises(ValueError, match="finite"):
        fit_rule(np.array([[np.nan]]), np.zeros(1), 2)
