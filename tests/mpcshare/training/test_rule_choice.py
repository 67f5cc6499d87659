"""The closed-loop choice of the gate's settings: candidates, the line ratio, the criterion."""

from __future__ import annotations

import numpy as np
import pytest

from mpcshare.control.strategies.gate import check_settings
from mpcshare.training import rule_choice
from mpcshare.training.rule_choice import candidates, choose_rule, line_ratio, rule_markdown


def test_candidates_are_the_nested_wearer_mode_sets():
    v = np.array([0.06, 0.05, 0.7, 0.0])
    c = candidates(v)
    assert [x["wearer_modes"] for x in c] == [[2], [0, 2], [0, 1, 2], []]  # last: the robot leads every mode
    for x in c:  # each threshold separates the set from the rest, with hysteresis, and is a valid setting
        s = check_settings(x["settings"])
        inside = v[x["wearer_modes"]] if x["wearer_modes"] else np.array([1.0])
        outside = np.delete(v, x["wearer_modes"])
        assert inside.min() >= s["share_on"] > s["share_off"] > outside.max()
    assert [x["wearer_modes"] for x in candidates(np.array([0.3, 0.3]))] == [[]]  # equal shares: all or none
    assert [x["wearer_modes"] for x in candidates(np.array([1.0, 0.2]))] == [[0]]  # a mode always unpredictable


def test_line_ratio_against_the_straight_line():
    vol = {"tracking_rmse_m": 0.010, "voluntary_effort": 0.08}
    rea = {"tracking_rmse_m": 0.020, "voluntary_effort": 0.02}
    assert line_ratio(0.010, 0.08, vol, rea) == pytest.approx(1.0)
    assert line_ratio(0.015, 0.05, vol, rea) == pytest.approx(1.0)  # the midpoint lies on the line
    assert line_ratio(0.012, 0.05, vol, rea) == pytest.approx(0.8)
    # equal efforts: the line is the better party (mpcshare.line_ratio, the one definition)
    assert line_ratio(0.012, 0.05, vol, dict(vol)) == pytest.approx(1.2)
    assert line_ratio(0.030, 0.10, vol, rea) == pytest.approx(3.0)  # beyond both efforts: the better party


def test_the_criterion_prefers_the_best_line_within_the_effort_cap(monkeypatch):
    """With simulated figures (the loop replaced): the lowest line ratio among efforts <= 0.75x wins;
    when none is below the cap, or the robot alone costs the wearer as much, the lowest RMS."""
    figures = {"voluntary": (0.010, 0.08), "reactive": (0.020, 0.02)}
    by_on = {}

    def fake(bundle, demos, trials, strategy, options, duration_s, wearer, seed):
        rms, eff = figures[strategy] if strategy != "gate" else by_on[options["share_on"]]
        return {"tracking_rmse_m": rms, "voluntary_effort": eff, "limit_violations": 0}

    class Bundle:
        model_hz = 10.0
        modes = None
        metrics = {"gate": {"per_mode": {"0": {"n": 100, "n_positive": 94}, "1": {"n": 100, "n_positive": 30},
                                         "2": {"n": 100, "n_positive": 100}}}}

    monkeypatch.setattr(rule_choice, "_pooled", fake)
    ons = [c["settings"]["share_on"] for c in candidates(np.array([0.06, 0.7, 0.0]))]
    by_on.update({ons[0]: (0.014, 0.04), ons[1]: (0.0105, 0.07)})  # line ratios 0.82 (0.33x), 0.84 (0.88x)
    by_on[ons[2]] = (0.021, 0.075)  # the robot leads every mode: the wearer corrects it hard
    choice = choose_rule(Bundle(), None, [3])
    assert choice["wearer_modes"] == [1] and "lowest line ratio" in choice["why"]
    by_on.update({ons[0]: (0.014, 0.07)})
    choice = choose_rule(Bundle(), None, [3])
    assert choice["wearer_modes"] == [0, 1] and "no candidate" in choice["why"]  # 10.5 mm
    assert "| gate | [0, 1] |" in rule_markdown(choice)
    by_on.update({ons[0]: (0.0105, 0.04), ons[1]: (0.0104, 0.05)})
    figures["reactive"] = (0.020, 0.065)  # the robot alone costs 0.81x: the line is ill-posed
    choice = choose_rule(Bundle(), None, [3])
    assert choice["wearer_modes"] == [0, 1] and "reactive alone costs 0.81x" in choice["why"]
    by_on[ons[2]] = (0.009, 0.066)  # the robot leading every mode tracks best: the choice keeps it leading
    assert choose_rule(Bundle(), None, [3])["wearer_modes"] == []
    with pytest.raises(ValueError, match="at least one held-out trial"):
        choose_rule(Bundle(), None, [])
