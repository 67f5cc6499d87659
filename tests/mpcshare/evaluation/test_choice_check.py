"""The rule choice's prediction beside the evaluation's figures."""

from __future__ import annotations

import pytest

from mpcshare.bundle.rule import CalibratedRule
from mpcshare.evaluation.choice_check import choice_check, rule_run
from mpcshare.reports.headline import headline_lines

_RUNS = [{"name": "voluntary", "strategy": "voluntary"}, {"name": "gate", "strategy": "gate"},
         {"name": "random", "strategy": "gate", "schedule": "random"}]
_STRATEGIES = {"voluntary": {"tracking_rmse_m": 0.010, "voluntary_effort": 0.10, "line_ratio": 1.0},
               "reactive": {"tracking_rmse_m": 0.020, "voluntary_effort": 0.02, "line_ratio": 1.0},
               "gate": {"tracking_rmse_m": 0.012, "voluntary_effort": 0.05, "line_ratio": 0.79,
                        "saw_correlation": 0.9, "saw_amplitude_ratio": 0.8}}
_PREDICTED = {"line_ratio": 0.663, "effort_vs_voluntary": 0.45, "tracking_rmse_m": 0.011, "saw_correlation": 0.88,
              "saws": True}


def test_the_check_sets_the_prediction_beside_the_realised_figures_and_flags_a_gap_over_0_1():
    rule = CalibratedRule("gate", {"wearer_modes": [1]}, {"predicted": _PREDICTED})
    check = choice_check(rule, _STRATEGIES, _RUNS)
    assert check["run"] == "gate" and check["predicted"]["line_ratio"] == pytest.approx(0.663)
    assert check["realised"] == {"line_ratio": 0.79, "effort_vs_voluntary": pytest.approx(0.5),
                                 "tracking_rmse_m": 0.012, "saw_correlation": 0.9}
    assert check["line_ratio_gap"] == pytest.approx(0.127) and check["differs"]
    line = headline_lines(_STRATEGIES, markdown=False, rule_check=check)[-1]
    assert line.startswith("The choice: NO, off by +0.13.") and "line ratio 0.66" in line and "0.79" in line
    close = choice_check(CalibratedRule("gate", {}, {"predicted": {**_PREDICTED, "line_ratio": 0.75}}),
                         _STRATEGIES, _RUNS)
    assert not close["differs"] and "yes, within 0.1" in headline_lines(_STRATEGIES, rule_check=close)[-1]
    assert len(headline_lines(_STRATEGIES)) == len(headline_lines(_STRATEGIES, rule_check=check)) - 1
    assert check["cross_validated_line_ratio"] is None and "left one" not in line
    assert check["basis"] == "choice trials"


def test_the_check_judges_the_prediction_left_one_trial_out_where_there_is_one():
    """The least of many candidates' figures on the trials it was chosen on is biased low; the figure of the
    rule chosen on the other choice trials, on the one left out, is the prediction the check judges."""
    rule = CalibratedRule("gate", {}, {"predicted": _PREDICTED, "cross_validated": {"line_ratio": 0.758}})
    check = choice_check(rule, _STRATEGIES, _RUNS)
    assert check["cross_validated_line_ratio"] == 0.758 and check["basis"] == "left one trial out"
    assert check["line_ratio_gap"] == pytest.approx(0.79 - 0.758) and not check["differs"]
    assert check["predicted"]["line_ratio"] == pytest.approx(0.663)  # the in-sample figures stay beside it
    line = headline_lines(_STRATEGIES, markdown=False, rule_check=check)[-1]
    assert line.startswith("The choice: yes, within 0.1.") and "line ratio 0.76 left one choice trial out" in line
    assert "(on the trials it was chosen on: line ratio 0.66" in line
    assert "differs from the predicted one by +0.03" in line
    far = choice_check(CalibratedRule("gate", {}, {"predicted": {**_PREDICTED, "line_ratio": 0.78},
                                                   "cross_validated": {"line_ratio": 0.6}}), _STRATEGIES, _RUNS)
    assert far["differs"] and far["line_ratio_gap"] == pytest.approx(0.19)  # close in sample, far left out


def test_no_check_without_a_prediction_or_a_run_of_the_rules_strategy():
    assert choice_check(None, _STRATEGIES, _RUNS) is None
    assert choice_check(CalibratedRule("gate", {}, {}), _STRATEGIES, _RUNS) is None  # an older choice
    assert choice_check(CalibratedRule("mix25", {}, {"predicted": _PREDICTED}), _STRATEGIES, _RUNS) is None
    assert rule_run("gate", _RUNS[2:]) is None  # a replayed schedule does not run the rule
    assert rule_run("gate", [{"name": "gate_mpc", "strategy": "gate"}]) == "gate_mpc"
