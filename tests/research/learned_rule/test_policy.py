"""The learned rule's probabilities, its hysteresis in the arbiter and the feature log's alignment."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from research.learned_rule.features import feature_names
from research.learned_rule.policy import FeatureLog, ImitationPolicy, LearnedRule, log_arrays

F = len(feature_names(2))


def mode_rule(gain: float = 10.0) -> LearnedRule:
    """Robot leads (α 1) in mode 1, the wearer in mode 0."""
    coef = np.zeros((2, F))
    coef[1, 1] = gain
    return LearnedRule(np.array([0.0, 1.0]), np.zeros(F), np.ones(F), coef, np.array([0.0, -gain / 2]), 2)


def step(p):
    return SimpleNamespace(mode_proba=np.asarray(p, dtype=float), novelty=0.0, u_v=None, u_r=None)


def test_proba_is_a_softmax():
    r = mode_rule()
    p = r.proba(np.zeros((3, F)))
    np.testing.assert_allclose(p.sum(axis=1), 1.0)
    np.testing.assert_allclose(p[0], np.exp([0, -5]) / np.exp([0, -5]).sum())


def test_bad_rules_raise():
    with pytest.raises(ValueError, match="0 or in"):
        LearnedRule(np.array([0.0, 0.3]), np.zeros(F), np.ones(F), np.zeros((2, F)), np.zeros(2), 2)
    with pytest.raises(ValueError, match="scale"):
        LearnedRule(np.array([0.0, 1.0]), np.zeros(F), np.zeros(F), np.zeros((2, F)), np.zeros(2), 2)


def test_switches_only_after_the_dwell_and_logs_every_step():
    log: list = []
    pol = ImitationPolicy(mode_rule(), period_s=0.1, margin=0.1, min_dwell_s=1.0, log=log)
    arb = SimpleNamespace(alpha=0.0)
    assert pol.decide(0.0, step([1, 0]), arb).alpha == 0.0
    a = pol.decide(0.5, step([0, 1]), arb)  # mode 1 says the robot, but the wearer's level is only 0.5 s old
    assert a.alpha == 0.0
    b = pol.decide(1.0, step([0, 1]), arb)
    assert b.alpha == 1.0 and b.ramp and b.beta is None
    assert pol.decide(1.5, step([1, 0]), arb).alpha == 1.0  # held for the dwell again
    assert [r[2] for r in log] == [0.0, 0.0, 1.0, 1.0]


def test_margin_keeps_the_level_when_unsure():
    pol = ImitationPolicy(mode_rule(gain=0.1), margin=0.2, min_dwell_s=0.0)
    arb = SimpleNamespace(alpha=0.0)
    pol.decide(0.0, step([1, 0]), arb)
    assert pol.decide(0.2, step([0, 1]), arb).alpha == 0.0  # p(robot) − p(wearer) ≈ 0.025 < 0.2


def test_feature_log_delegates_and_aligns():
    log: list = []
    inner = SimpleNamespace(overrides=True, reset=lambda: None,
                            decide=lambda t, i, a: SimpleNamespace(alpha=0.75 if t >= 0.02 else 0.0))
    wrapped = FeatureLog(inner, 2, log)
    assert wrapped.overrides
    for t in (0.0, 0.01, 0.02):
        wrapped.decide(t, step([1, 0]), None)
    X, a = log_arrays(log, np.array([0.0, 0.01, 0.02, 0.03]))
    assert X.shape == (4, F) and a.tolist() == [0.0, 0.0, 0.75, 0.75]
    with pytest.raises(RuntimeError, match="never decided"):
        log_arrays([], np.zeros(1))
