"""The rule choice's criterion: sawing per cutting episode, and the prediction of the chosen row."""

from __future__ import annotations

import pytest

from mpcshare.calibration.choice_criterion import (
    criterion,
    cross_validated,
    predicted,
    saws_where_the_wearer_saws,
    wearer_saws,
)
from sim.task import EATING
from tests.sim.task.test_protocol import Pouring


def test_a_row_must_saw_in_each_episode_where_the_wearer_alone_saws():
    alone = {"saws_by_trial": [True, False, None]}
    assert saws_where_the_wearer_saws({"saws_by_trial": [True, False, None]}, alone)  # the 2nd does not count
    assert not saws_where_the_wearer_saws({"saws_by_trial": [False, True, None]}, alone)
    pooled = {"saw_correlation": 0.9, "saw_amplitude_ratio": 0.9}  # no per-trial figures: the pooled ones
    assert saws_where_the_wearer_saws(pooled, alone) and not saws_where_the_wearer_saws({}, alone)
    assert wearer_saws(alone) and not wearer_saws({"saws_by_trial": [False, None]})
    assert not wearer_saws({"saw_correlation": None, "saw_amplitude_ratio": None})


def test_the_episodes_within_a_trial_are_judged_one_by_one():
    """Trial 0 has two cutting episodes, trial 1 one. A row that saws in trial 0's pooled figures but not in its
    second episode, where the wearer alone saws, fails; one that fails only where the wearer alone does not saw
    passes. Episodes that do not line up with the wearer's fall back to the trials' figures."""
    alone = {"saws_by_trial": [True, True], "saws_by_episode": [[True, True], [False]]}
    pooled_only = {"saws_by_trial": [True, True]}
    assert saws_where_the_wearer_saws(pooled_only, alone)
    assert not saws_where_the_wearer_saws({**pooled_only, "saws_by_episode": [[True, False], [True]]}, alone)
    assert saws_where_the_wearer_saws({**pooled_only, "saws_by_episode": [[True, True], [False]]}, alone)
    assert saws_where_the_wearer_saws({**pooled_only, "saws_by_episode": [[True], [False]]}, alone)  # by trial
    assert wearer_saws({"saws_by_trial": [True], "saws_by_episode": [[False, False]]}) is False
    assert wearer_saws({"saws_by_trial": [True], "saws_by_episode": [[]]})  # no episode long enough: the trial


def test_where_no_candidate_saws_in_every_episode_the_trials_as_a_whole_decide():
    """No candidate saws in all four episodes where the wearer alone saws: the criterion falls back to the trials'
    cutting as a whole (``task_filter`` "trial"), so the candidate that saws there wins over a lower line ratio
    that does not saw at all; with one that saws in every episode, that one wins ("episode")."""
    vol = {"saws_by_trial": [True, True], "saws_by_episode": [[True, True], [True, True]],
           "voluntary_effort": 0.1, "tracking_rmse_m": 0.01}
    rea = {"voluntary_effort": 0.02, "tracking_rmse_m": 0.02}

    def row(name, line, by_trial, by_episode):
        return {"name": name, "effort_vs_voluntary": 0.5, "line_ratio": line, "tracking_rmse_m": 0.01,
                "saws_by_trial": by_trial, "saws_by_episode": by_episode}

    mostly = row("mostly", 0.95, [True, True], [[True, False], [True, True]])
    never = row("never", 0.80, [False, False], [[False, False], [False, False]])
    best, reason = criterion([mostly, never], vol, rea, 0.75)
    assert best["name"] == "mostly" and reason["task_filter"] == "trial"
    every = row("every", 0.99, [True, True], [[True, True], [True, True]])
    best, reason = criterion([mostly, never, every], vol, rea, 0.75)
    assert best["name"] == "every" and reason["task_filter"] == "episode"
    best, reason = criterion([never], vol, rea, 0.75)
    assert best["name"] == "never" and reason["task_filter"] is False  # nothing saws: the line ratio alone


def test_the_prediction_is_the_chosen_rows_figures():
    row = {"line_ratio": 0.66, "effort_vs_voluntary": 0.5, "tracking_rmse_m": 0.004, "saw_correlation": 0.9,
           "saw_amplitude_ratio": 0.9, "saws_by_trial": [True, False]}
    assert predicted(row, {"saws_by_trial": [True, True]}) == {
        "line_ratio": 0.66, "effort_vs_voluntary": 0.5, "tracking_rmse_m": 0.004, "saw_correlation": 0.9,
        "saws": False}


def _row(name, per_trial):
    """A row with per-trial (RMS [m], effort) on 2 trials of 100 steps each, pooled."""
    by = [{"tracking_rmse_m": r, "voluntary_effort": e, "steps": 100} for r, e in per_trial]
    rms = ((per_trial[0][0] ** 2 + per_trial[1][0] ** 2) / 2) ** 0.5
    return {"name": name, "by_trial": by, "tracking_rmse_m": rms,
            "voluntary_effort": (per_trial[0][1] + per_trial[1][1]) / 2}


def test_left_one_trial_out_each_trial_is_scored_by_the_rule_the_other_trial_chose():
    """A tracks best on trial 0 and B on trial 1: leaving trial 0 out chooses B and scores it there, and the
    other way round, so the cross-validated RMS is both rows' worse trial, above either in-sample figure."""
    vol = _row("voluntary", [(0.010, 0.08), (0.010, 0.08)])
    rea = _row("reactive", [(0.020, 0.02), (0.020, 0.02)])
    a, b = _row("A", [(0.005, 0.04), (0.015, 0.04)]), _row("B", [(0.015, 0.04), (0.005, 0.04)])
    rows = [{**r, "line_ratio": None, "effort_vs_voluntary": 0.5} for r in (a, b)]
    cv = cross_validated(rows, vol, rea, 0.75)
    assert cv["chosen"] == [1, 0] and cv["tracking_rmse_m"] == pytest.approx(0.015)
    assert cv["effort_vs_voluntary"] == pytest.approx(0.5)
    assert cv["line_ratio"] == pytest.approx(0.015 / (0.020 - (0.04 - 0.02) / 0.06 * 0.010))
    assert cross_validated(rows, {**vol, "by_trial": vol["by_trial"][:1]}, rea, 0.75) is None  # one trial


def test_the_criterion_is_the_tasks_own():
    """Under a task judged by its lag (``Pouring``: within 0.2 s), the candidate with the lower line ratio that is
    late loses to the one on time where the wearer alone is on time; under eating, neither saws: the lower ratio."""
    vol = {"saws_by_trial": [True], "voluntary_effort": 0.1, "tracking_rmse_m": 0.01, "lag_s": 0.1}
    rea = {"voluntary_effort": 0.02, "tracking_rmse_m": 0.02}
    late = {"name": "late", "effort_vs_voluntary": 0.5, "line_ratio": 0.7, "tracking_rmse_m": 0.006,
            "saws_by_trial": [False], "lag_s": 0.5}
    on_time = {**late, "name": "on time", "line_ratio": 0.9, "saws_by_trial": [True], "lag_s": 0.05}
    best, reason = criterion([late, on_time], vol, rea, 0.75, Pouring())
    assert best["name"] == "on time" and reason["task_filter"] and reason["stroke_mode"] is None
    assert reason["by"] == "line_ratio" and reason["line_ratio"] == 0.9 and reason["n_within"] == 2
    no_per_trial = [{k: v for k, v in r.items() if k != "saws_by_trial"} for r in (late, on_time)]
    assert criterion(no_per_trial, vol, rea, 0.75, Pouring())[0]["name"] == "on time"  # pooled: task.done
    assert criterion(no_per_trial, vol, rea, 0.75, EATING)[0]["name"] == "late"  # no sawing figures: the ratio
