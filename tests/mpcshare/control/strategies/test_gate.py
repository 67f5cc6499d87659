"""The default gate: whole wearer modes, anticipated from the transition matrix, held after, the push."""

from __future__ import annotations

import math

import numpy as np
import pytest

from mpcshare.control.arbitration import Arbiter
from mpcshare.control.strategies.base import ModeFigures
from mpcshare.control.strategies.gate import GateSettings, mode_forecast

V = [0.05, 0.7, 0.0]  # mode 1 is a stroke mode: 70 % of its held-out points unpredictable
A = np.array([[0.8, 0.2, 0.0], [0.0, 0.9, 0.1], [0.1, 0.0, 0.9]])  # 0 → 1 → 2 → 0
FIGURES = ModeFigures(np.array(V), A, 0.1)


def _arbiter(**options) -> Arbiter:
    return Arbiter("gate", beta=0.5, min_dwell_s=0.0, handover_s=0.0, figures=FIGURES, settings=options)


def _onehot(j: int) -> np.ndarray:
    return np.eye(3)[j]


def test_the_forecast_is_the_matrix_power_against_brute_force():
    F = mode_forecast(np.array(V), A, 4)
    for k in range(5):
        np.testing.assert_allclose(F[k], np.linalg.matrix_power(A, k) @ V, atol=1e-15)
    pi = np.array([0.2, 0.3, 0.5])
    assert max(pi @ np.linalg.matrix_power(A, k) @ V for k in range(5)) == pytest.approx(np.max(F @ pi))


def test_a_stroke_mode_goes_to_the_wearer_whole_and_is_held_after():
    arb = _arbiter(lead_s=0.0, hold_s=0.5)
    assert arb.decide(0.0, 0.9, mode_proba=_onehot(0)).alpha == 1.0  # the robot leads mode 0
    # mode 1 with a gate probability that flickers around 0.5: the whole mode goes to the wearer
    alphas = [arb.decide(0.1 * k, 0.5 + 0.1 * (-1) ** k, mode_proba=_onehot(1)).alpha for k in range(1, 30)]
    assert set(alphas) == {0.0}
    # the mode ends: the wearer keeps the lead for hold_s, then the robot takes it back
    after = {round(0.1 * k, 1): arb.decide(3.0 + 0.1 * k, 0.9, mode_proba=_onehot(2)).alpha for k in range(10)}
    assert after[0.0] == after[0.4] == 0.0 and after[0.5] == after[0.9] == 1.0
    assert len(arb.handovers) == 3  # robot at the start, wearer, robot


def test_anticipation_hands_over_before_the_stroke_mode():
    """π·A^k·v looks lead_s ahead: mode 0 leads into mode 1 (0.1 per tick), so a lead of 1 s hands the
    wearer the lead while mode 0 is still certain; without a lead it does not."""
    no_lead, lead = _arbiter(lead_s=0.0), _arbiter(lead_s=1.0, share_off=0.25)
    assert no_lead.decide(0.0, 0.9, mode_proba=_onehot(0)).alpha == 1.0
    d = lead.decide(0.0, 0.9, mode_proba=_onehot(0))
    expected = max(np.linalg.matrix_power(A, k)[0] @ V for k in range(11))
    assert d.alpha == 0.0 and expected >= GateSettings().share_on and f"{expected:.2f}" in d.reason
    assert lead.decide(0.1, 0.9, mode_proba=_onehot(2)).alpha == 0.0  # held ...
    assert lead.decide(1.0, 0.9, mode_proba=_onehot(2)).alpha == 1.0  # ... then back to the robot


def test_the_wearer_pushing_against_the_robot_takes_the_lead():
    arb = _arbiter(push_mps=0.05, push_s=0.3, hold_s=0.5, lead_s=0.0)
    u_r = np.array([0.1, 0.0, 0.0])
    for k in range(50):  # a gentle push, then a strong one along the robot: the robot keeps leading
        u_v = np.array([-0.03, 0, 0]) if k < 25 else np.array([0.2, 0, 0])
        assert arb.decide(0.01 * k, 0.9, mode_proba=_onehot(0), u_r=u_r, u_v=u_v).alpha == 1.0
    alphas = [arb.decide(0.5 + 0.01 * k, 0.9, mode_proba=_onehot(0), u_r=u_r, u_v=np.array([-0.1, 0, 0])).alpha
              for k in range(60)]
    first = alphas.index(0.0)
    assert 0.25 <= 0.01 * first <= 0.35  # after ≈ push_s of pushing (1 − 1/e of the leaky integral)
    rest = [arb.decide(1.1 + 0.01 * k, 0.9, mode_proba=_onehot(0), u_r=u_r, u_v=np.zeros(3)).alpha
            for k in range(100)]
    assert rest[0] == 0.0 and rest[-1] == 1.0 and 0.5 <= 0.01 * rest.index(1.0) <= 0.8  # fades, then hold_s


def test_overrides_dwell_and_fallback():
    arb = Arbiter("gate", beta=0.5, min_dwell_s=1.0, handover_s=0.0, novelty_threshold=5.0, novelty_persist_s=0.0,
                  figures=FIGURES, settings={"lead_s": 0.0, "hold_s": 0.0})
    assert arb.decide(0.0, 0.9, mode_proba=_onehot(0)).alpha == 1.0
    assert arb.decide(0.5, 0.9, mode_proba=_onehot(1)).alpha == 1.0  # within the dwell
    assert arb.decide(1.0, 0.9, mode_proba=_onehot(1)).alpha == 0.0
    d = arb.decide(2.5, 0.9, novelty=9.0, mode_proba=_onehot(0))
    assert d.alpha == 0.0 and d.reason.startswith("novelty")
    # no per-mode figures: the paper's gate, said so
    paper = Arbiter("gate", beta=0.5, min_dwell_s=0.0, handover_s=0.0)
    d = paper.decide(0.0, 0.9, mode_proba=_onehot(1))
    assert d.alpha == 1.0 and d.reason.startswith("no per-mode figures")
    assert math.isnan(Arbiter("gate", figures=ModeFigures(np.array(V))).policy.score(None))


def test_settings_are_checked():
    assert Arbiter("gate", settings={}).settings == Arbiter("gate").settings == GateSettings()
    with pytest.raises(ValueError, match="unknown gate setting.*valid: share_on"):
        _arbiter(lead=1.0)
    with pytest.raises(ValueError, match="share_off <= share_on"):
        _arbiter(share_on=0.2, share_off=0.5)
    with pytest.raises(ValueError, match="voluntary shares must be K shares"):
        Arbiter("gate", figures=ModeFigures(np.array([0.5, 1.5])))


def test_measured_wearer_modes_replace_the_shares():
    """``wearer_modes`` (the closed-loop choice): v is their indicator, whatever the held-out shares say;
    s is then the forecast probability of a wearer mode within lead_s."""
    arb = _arbiter(wearer_modes=[2], share_on=0.5, share_off=0.3, lead_s=0.0, hold_s=0.0)
    assert arb.decide(0.0, 0.9, mode_proba=_onehot(1)).alpha == 1.0  # the shares' stroke mode: the robot leads
    assert arb.decide(0.1, 0.9, mode_proba=np.array([0.0, 0.45, 0.55])).alpha == 0.0  # P(mode 2) 0.55 >= 0.5
    assert arb.decide(0.2, 0.9, mode_proba=np.array([0.0, 0.6, 0.4])).alpha == 0.0  # above share_off: kept
    assert arb.decide(0.3, 0.9, mode_proba=np.array([0.0, 0.8, 0.2])).alpha == 1.0
    ahead = _arbiter(wearer_modes=[2], share_on=0.4, share_off=0.3, lead_s=1.0)
    p = max(np.linalg.matrix_power(A, k)[1, 2] for k in range(11))  # from mode 1, into mode 2 within 1 s: 0.41
    assert p >= 0.4 and ahead.decide(0.0, 0.9, mode_proba=_onehot(1)).alpha == 0.0
    for bad in ([3], [-1]):
        with pytest.raises(ValueError, match="gate setting wearer_modes"):
            _arbiter(wearer_modes=bad)


def test_a_robot_share_while_the_wearer_leads_is_the_convex_mixture():
    """``wearer_alpha`` a_w: in a wearer mode û = a_w·û_r + (1 − a_w)·û_v (the wearer still leads: a_w < 0.5);
    the robot's modes are unchanged (α = 1, the user's β)."""
    arb = _arbiter(wearer_modes=[1], wearer_alpha=0.25, share_on=0.5, share_off=0.3, lead_s=0.0, hold_s=0.0)
    d = arb.decide(0.0, 0.9, mode_proba=_onehot(0))
    assert (d.alpha, d.beta) == (1.0, 0.5)
    d = arb.decide(0.1, 0.9, mode_proba=_onehot(1))
    assert (d.alpha, d.beta) == (0.25, 0.75) and "the wearer leads" in d.reason
    assert [h.alpha_to for h in arb.handovers] == [1.0, 0.25]  # the start (robot), then to the wearer
    plain = _arbiter(wearer_modes=[1], share_on=0.5, share_off=0.3, lead_s=0.0, hold_s=0.0)
    plain.decide(0.0, 0.9, mode_proba=_onehot(0))
    d = plain.decide(0.1, 0.9, mode_proba=_onehot(1))
    assert (d.alpha, d.beta) == (0.0, 1.0)  # the default: the wearer alone
    for bad in (0.5, -0.1):
        with pytest.raises(ValueError, match=r"wearer_alpha must be in \[0, 0.5\)"):
            _arbiter(wearer_alpha=bad)


def test_the_robot_share_while_it_leads_is_the_expected_share_under_the_mode_posterior():
    """``robot_alphas`` a: a robot-led step is û = α·û_r + (1 − α)·û_v with α = π·a (smooth, the robot
    still leads: α ≥ 0.5); a wearer mode is still handed over whole; a, not K shares in [0.5, 1], is refused."""
    arb = _arbiter(wearer_modes=[1], robot_alphas=[0.5, 1.0, 0.75], share_on=0.5, share_off=0.3, lead_s=0.0,
                   hold_s=0.0)
    d = arb.decide(0.0, 0.9, mode_proba=_onehot(0))
    assert (d.alpha, d.beta) == (0.5, 0.5) and "the robot leads" in d.reason
    d = arb.decide(0.1, 0.9, mode_proba=np.array([0.6, 0.0, 0.4]))
    assert (d.alpha, d.beta) == pytest.approx((0.6, 0.4))  # 0.6·0.5 + 0.4·0.75
    assert arb.decide(0.2, 0.9, mode_proba=_onehot(1)).alpha == 0.0  # the wearer's mode, whole
    assert [h.alpha_to for h in arb.handovers] == [0.5, 0.0]  # the start (robot), then to the wearer only
    full = _arbiter(wearer_modes=[1], robot_alphas=[1.0, 1.0, 1.0], share_on=0.5, share_off=0.3, lead_s=0.0)
    assert full.decide(0.0, 0.9, mode_proba=_onehot(0)).beta == 0.5  # a share of 1: the user's β
    for bad in ([0.4, 1.0, 1.0], [1.0, 1.0], [1.0, 1.1, 1.0]):
        with pytest.raises(ValueError, match="robot_alphas"):
            _arbiter(robot_alphas=bad)


def test_a_bounded_lead_hands_back_after_wearer_max_s_until_the_wearer_modes_end():
    """wearer_max_s: the wearer leads mode 1 for 1 s, the robot (at its share) the rest of that stay; the
    next entry into mode 1 is handed over afresh."""
    arb = _arbiter(lead_s=0.0, hold_s=0.0, wearer_max_s=1.0, robot_alphas=[0.5, 0.5, 0.5])
    assert arb.decide(0.0, 0.9, mode_proba=_onehot(0)).alpha == 0.5
    stay = {round(0.1 * k, 1): arb.decide(0.1 * k, 0.5, mode_proba=_onehot(1)) for k in range(1, 40)}
    assert stay[0.1].alpha == stay[1.0].alpha == 0.0  # the wearer leads the first second
    assert stay[1.1].alpha == stay[3.9].alpha == 0.5 and "lead spent" in stay[3.9].reason
    assert arb.decide(4.0, 0.9, mode_proba=_onehot(2)).alpha == 0.5  # mode 1 ended: the bound resets
    assert arb.decide(4.1, 0.5, mode_proba=_onehot(1)).alpha == 0.0  # a new stay: the wearer again
    unbounded = _arbiter(lead_s=0.0, hold_s=0.0)
    assert all(unbounded.decide(0.1 * k, 0.5, mode_proba=_onehot(1)).alpha == 0.0 for k in range(1, 40))
    with pytest.raises(ValueError, match="wearer_max_s"):
        GateSettings(wearer_max_s=0.0)
