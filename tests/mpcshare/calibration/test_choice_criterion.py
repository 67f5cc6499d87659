"""The rule choice's criterion: sawing per cutting episode, and the prediction of the chosen row."""

from __future__ import annotations

from mpcshare.calibration.choice_criterion import predicted, saws_where_the_wearer_saws, wearer_saws


def test_a_row_must_saw_in_each_episode_where_the_wearer_alone_saws():
    alone = {"saws_by_trial": [True, False, None]}
    assert saws_where_the_wearer_saws({"saws_by_trial": [True, False, None]}, alone)  # the 2nd does not count
    assert not saws_where_the_wearer_saws({"saws_by_trial": [False, True, None]}, alone)
    pooled = {"saw_correlation": 0.9, "saw_amplitude_ratio": 0.9}  # no per-trial figures: the pooled ones
    assert saws_where_the_wearer_saws(pooled, alone) and not saws_where_the_wearer_saws({}, alone)
    assert wearer_saws(alone) and not wearer_saws({"saws_by_trial": [False, None]})
    assert not wearer_saws({"saw_correlation": None, "saw_amplitude_ratio": None})


def test_the_prediction_is_the_chosen_rows_figures():
    row = {"line_ratio": 0.66, "effort_vs_voluntary": 0.5, "tracking_rmse_m": 0.004, "saw_correlation": 0.9,
           "saw_amplitude_ratio": 0.9, "saws_by_trial": [True, False]}
    assert predicted(row, {"saws_by_trial": [True, True]}) == {
        "line_ratio": 0.66, "effort_vs_voluntary": 0.5, "tracking_rmse_m": 0.004, "saw_correlation": 0.9,
        "saws": False}
