"""Arbitration: the paper's rule, the additions (hysteresis, dwell, overrides) and the baselines."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mpcshare.control.arbitration import STRATEGIES, Arbiter, fuse, reactive_velocity


def test_gate_rule_alpha_and_beta():
    arb = Arbiter("paper_gate", beta=0.3, min_dwell_s=0.0, handover_s=0.0)
    d = arb.decide(0.0, 0.9)
    assert (d.alpha, d.beta) == (1.0, 0.3)
    d = arb.decide(0.1, 0.1)
    assert (d.alpha, d.beta) == (0.0, 1.0)
    assert [(h.alpha_from, h.alpha_to) for h in arb.handovers] == [(0.0, 1.0), (1.0, 0.0)]
    assert arb.handovers[0].t == 0.0 and "predictable" in arb.handovers[0].reason


def test_baselines_are_fixed():
    v, r = Arbiter("voluntary", beta=0.2), Arbiter("reactive", beta=0.2)
    for t, p in enumerate([0.0, 1.0, float("nan"), 0.5]):
        assert (v.decide(t, p).alpha, v.decide(t, p).beta) == (0.0, 1.0)
        dr = r.decide(t, p, novelty=1e9, prediction_finite=False)
        assert (dr.alpha, dr.beta) == (1.0, 0.0)
    assert v.handovers == [] and r.handovers == []


def test_blend_ramp_and_beta():
    arb = Arbiter("blend", beta=0.4, settings={"blend_range": (0.5, 0.9)})
    for p, a in [(0.2, 0.0), (0.5, 0.0), (0.7, 0.5), (0.9, 1.0), (1.0, 1.0)]:
        d = arb.decide(0.0, p)
        assert d.alpha == pytest.approx(a)
        assert d.beta == pytest.approx(1.0 - a * 0.6)
    d = arb.decide(1.0, 0.95, novelty=50.0)  # no threshold given: novelty ignored
    assert d.alpha == 1.0


def test_hysteresis_does_not_chatter():
    """A probability oscillating around 0.5 every tick leaves α where it was."""
    arb = Arbiter("paper_gate", beta=0.5, settings={"on_threshold": 0.6, "off_threshold": 0.4}, min_dwell_s=0.0,
                  handover_s=0.0)
    alphas = [arb.decide(0.1 * k, 0.5 + 0.08 * (-1) ** k).alpha for k in range(100)]
    assert set(alphas) == {0.0} and arb.handovers == []
    arb.decide(10.0, 0.95)  # the robot leads, then the same oscillation: it keeps leading
    alphas = [arb.decide(10.1 + 0.1 * k, 0.5 + 0.08 * (-1) ** k).alpha for k in range(100)]
    assert set(alphas) == {1.0} and len(arb.handovers) == 1
    # without hysteresis (thresholds equal) and without dwell it toggles every tick: the test can fail
    raw = Arbiter("paper_gate", settings={"on_threshold": 0.5, "off_threshold": 0.5}, min_dwell_s=0.0, handover_s=0.0)
    toggles = [raw.decide(0.1 * k, 0.5 + 0.08 * (-1) ** k).alpha for k in range(100)]
    assert len(raw.handovers) == 100 and len(set(toggles)) == 2


def test_dwell_time_limits_switch_rate():
    arb = Arbiter("paper_gate", settings={"on_threshold": 0.5, "off_threshold": 0.5}, min_dwell_s=0.5, handover_s=0.0)
    for k in range(100):  # 10 s of a gate flipping between 0.1 and 0.9 every 0.1 s
        arb.decide(0.1 * k, 0.9 if k % 2 == 0 else 0.1)
    times = [h.t for h in arb.handovers]
    assert len(times) >= 2 and np.all(np.diff(times) >= 0.5 - 1e-12)


@pytest.mark.parametrize("strategy", ["paper_gate", "gate", "blend"])
def test_overrides_force_alpha_zero_at_once(strategy):
    """With ``novelty_persist_s`` 0 every override acts on the step it appears (the default waits 0.3 s for
    novelty: the next test)."""
    arb = Arbiter(strategy, beta=0.5, novelty_threshold=10.0, min_dwell_s=5.0, handover_s=0.0, novelty_persist_s=0.0)
    assert arb.decide(0.0, 1.0).alpha == 1.0
    d = arb.decide(0.1, 1.0, novelty=11.0)  # within the dwell time, yet α = 0 at once
    assert (d.alpha, d.beta) == (0.0, 1.0) and "novelty" in d.reason
    assert arb.handovers[-1].reason.startswith("novelty")
    assert arb.decide(0.2, 1.0, novelty=float("nan")).alpha == 0.0
    assert "not finite" in arb.decide(0.3, 1.0, prediction_finite=False).reason
    assert arb.decide(0.4, 1.0, available=False).reason == "no gate decision available"
    assert arb.decide(0.5, float("nan")).alpha == 0.0


@pytest.mark.parametrize("strategy", ["paper_gate", "gate", "blend"])
def test_the_novelty_override_waits_for_novelty_that_persists(strategy):
    """With ``novelty_persist_s`` 0.3: one 10 Hz tick above the threshold hands nothing over; novelty above it
    for 0.3 s without a break does, and the other overrides (and a NaN novelty) still act at once."""
    arb = Arbiter(strategy, beta=0.5, novelty_threshold=10.0, min_dwell_s=0.0, handover_s=0.0, novelty_persist_s=0.3)
    t = [0.01 * k for k in range(200)]
    novelty = [11.0 if 0.5 <= tk < 0.6 else 5.0 for tk in t]  # one tick above the threshold
    novelty = [11.0 if 1.0 <= tk < 1.5 else n for tk, n in zip(t, novelty)]  # then 0.5 s above it
    alphas = [arb.decide(tk, 1.0, novelty=n).alpha for tk, n in zip(t, novelty)]
    assert min(alphas[:100]) == 1.0  # the single tick: the robot keeps the lead
    first = next(tk for tk, a in zip(t, alphas) if a == 0.0)
    assert first == pytest.approx(1.3)  # 0.3 s after the novelty rose
    assert any(h.reason.startswith("novelty") for h in arb.handovers)
    assert arb.decide(2.0, 1.0, novelty=5.0).alpha == 1.0
    assert arb.decide(2.01, 1.0, novelty=float("nan")).alpha == 0.0  # the filter failed: at once
    assert arb.decide(2.02, 1.0, prediction_finite=False).alpha == 0.0
    with pytest.raises(ValueError, match="novelty_persist_s must be finite and ≥ 0"):
        Arbiter(strategy, novelty_persist_s=-0.1)


def test_misuse_raises_clear_errors():
    with pytest.raises(ValueError, match="valid choices: " + ", ".join(STRATEGIES) + "$"):
        Arbiter("paper")
    for b in (-0.1, 1.5, float("nan")):
        with pytest.raises(ValueError, match="beta must be in"):
            Arbiter("paper_gate", beta=b)
    with pytest.raises(ValueError, match="off_threshold"):
        Arbiter("paper_gate", settings={"on_threshold": 0.3, "off_threshold": 0.6})


def test_reactive_velocity_and_fusion():
    p_ref = np.array([0.1, 0.0, 0.05])
    u = reactive_velocity(p_ref + [0.01, 0.0, 0.0], p_ref, gain=5.0, max_speed=0.2)
    np.testing.assert_allclose(u, [0.05, 0.0, 0.0])
    u = reactive_velocity(p_ref + [0.3, 0.4, 0.0], p_ref, gain=5.0, max_speed=0.2)
    assert math.isclose(np.linalg.norm(u), 0.2) and np.allclose(u / 0.2, [0.6, 0.8, 0.0])
    np.testing.assert_allclose(fuse(0.5, np.ones(3), 0.25, np.full(3, 2.0)), np.ones(3))


def test_gate_hands_over_along_a_ramp_and_overrides_act_at_once():
    arb = Arbiter("paper_gate", beta=0.5, min_dwell_s=0.0, handover_s=0.5)
    alphas = [arb.decide(0.01 * k, 0.95).alpha for k in range(60)]
    assert alphas[0] == 0.0 and alphas[10] == pytest.approx(0.2) and alphas[50] == 1.0
    d = arb.decide(0.6, 0.95)
    assert (d.alpha, d.beta) == (1.0, 0.5)
    d = arb.decide(0.61, 0.1)
    assert d.alpha == pytest.approx(0.98) and d.beta == pytest.approx(1 - 0.98 * 0.5)
    assert arb.decide(0.62, 0.1, prediction_finite=False).alpha == 0.0  # no prediction: at once
    with pytest.raises(ValueError, match="handover_s"):
        Arbiter("paper_gate", handover_s=-1.0)
