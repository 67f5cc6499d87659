"""The online features by hand: posterior, time in mode, leaky speeds."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from research.learned_rule.features import EPS, TAU_S, OnlineFeatures, feature_names


def step(p=None, u_v=None, u_r=None, novelty=0.0):
    return SimpleNamespace(mode_proba=None if p is None else np.asarray(p, dtype=float), novelty=novelty,
                           u_v=None if u_v is None else np.asarray(u_v, dtype=float),
                           u_r=None if u_r is None else np.asarray(u_r, dtype=float))


def test_features_by_hand():
    f = OnlineFeatures(2)
    x0 = f.update(0.0, step([1.0, 0.0], [0.01, 0, 0], [-0.02, 0, 0]))
    assert x0.size == len(feature_names(2))
    assert x0[0] == 1.0 and x0[2] == pytest.approx(math.log(0.01))  # in mode 0 for 0 s
    assert x0[-3] == pytest.approx(math.log(0.01 + EPS)) and x0[-2] == pytest.approx(math.log(0.02 + EPS))
    assert x0[-1] == pytest.approx(0.01)  # the wearer pushes against the robot at 1 cm/s
    x1 = f.update(0.1, step([1.0, 0.0], [0.04, 0, 0], [0.02, 0, 0]))
    assert x1[2] == pytest.approx(math.log(0.11)) and x1[3] == pytest.approx(math.log(0.11))
    k = 0.1 / TAU_S
    assert x1[-3] == pytest.approx(math.log(0.01 + k * 0.03 + EPS)) and x1[-1] == pytest.approx(0.01 - k * 0.01)
    x2 = f.update(0.2, step([0.2, 0.8]))  # the most probable mode changes: its clock restarts
    assert x2[2] == pytest.approx(math.log(0.01)) and x2[4] == pytest.approx(0.8 * math.log(0.01))
    assert x2[5] == pytest.approx(-(0.2 * math.log(0.2) + 0.8 * math.log(0.8)))


def test_unknown_posterior_is_uniform_and_reset_forgets():
    f = OnlineFeatures(3)
    x = f.update(5.0, step(None, novelty=float("nan")))
    np.testing.assert_allclose(x[:3], 1 / 3)
    assert x[8] == 50.0  # a NaN novelty counts as the most novel
    f.reset()
    assert f.update(9.0, step([0, 0, 1]))[3] == pytest.approx(math.log(0.01))


def test_bad_sizes_raise():
    with pytest.raises(ValueError, match="n_modes"):
        OnlineFeatures(0)
