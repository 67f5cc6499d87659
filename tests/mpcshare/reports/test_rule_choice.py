"""The closed-loop choice of the hand-over rule in words: the why from the reason record, the criterion, the
progress lines, the section of ``training.md``."""

from __future__ import annotations

import pytest

from mpcshare.calibration.choice_criterion import criterion, mix_winner
from mpcshare.reports.rule_choice import (
    CRITERION,
    candidate_line,
    criterion_why,
    criterion_words,
    pruned_line,
    pruned_why,
    ran_line,
    rule_markdown,
    skipped_markdown,
    why_words,
)
from sim.task import EATING
from tests.sim.task.test_protocol import Pouring


def _choice(**extra) -> dict:
    run = {"tracking_rmse_m": 0.010, "voluntary_effort": 0.08, "saw_correlation": 0.95}
    return {"duration_s": 60.0, "trials": [3], "seconds": 12.5, "wearer": "default", "wearer_modes": [1],
            "settings": {"wearer_modes": [1]}, "why": "the lowest line ratio", "criterion": "the criterion",
            "voluntary": run, "reactive": {**run, "tracking_rmse_m": 0.020, "voluntary_effort": 0.02,
                                           "saw_correlation": None},
            "candidates": [{"wearer_modes": [1], "timing": "early", "wearer_alpha": 0.25, "robot_alpha": 0.5,
                            "tracking_rmse_m": 0.012, "effort_vs_voluntary": 0.5, "line_ratio": 0.8,
                            "saw_correlation": 0.9}],
            "mode_costs": {"share": [0.6, 0.4], "rms_wearer_mm": [5.0, 6.0], "rms_robot_mm": [4.0, 30.0],
                           "effort_wearer_rad": [0.1, 0.2], "effort_robot_rad": [0.01, None],
                           "price_mm2_per_rad": [None, 4400.0]},
            "price_order": [1], "cutting_modes": [], **extra}


def test_the_section_states_the_choice_the_costs_and_every_candidate():
    md = rule_markdown(_choice())
    assert md.startswith("## Hand-over rule (closed-loop choice)\n\nChosen on held-out trials [3] (the first 60 s, "
                         "wearer default) in 12.5 s: the wearer leads modes [1], settings {'wearer_modes': [1]}.")
    assert "Why: the lowest line ratio. Criterion: the criterion." in md
    assert "| voluntary | | | | | 10.0 | 1.00 | 1 | 0.95 |" in md
    assert "| reactive | | | | | 20.0 | 0.25 | 1 | n/a |" in md
    assert "| gate | [1] | early | 0.25 | 0.5 | 12.0 | 0.50 | 0.800 | 0.90 |" in md
    assert "| 1 | 0.40 | 6.0 | 30.0 | 0.200 | n/a | 4400 |" in md and "modes that carry the cutting: none named." in md
    assert "Not simulated" not in md and "doing the task alone" not in md


def test_pruned_sets_and_the_cutting_modes_effort_are_said_when_present():
    md = rule_markdown(_choice(duration_s=None, pruned=[{"wearer_modes": [0], "why": "no better"}],
                               cutting_modes=[1], cutting_effort_vs_voluntary=0.8))
    assert "(whole trials, wearer default)" in md and "Not simulated, from the per-mode costs: [0] (no better)." in md
    assert "modes that carry the cutting: [1]. Leading them, the robot leading the rest, costs the wearer 0.80x" in md


def test_a_skipped_choice_is_one_sentence_under_the_same_heading():
    assert skipped_markdown("closed-loop choice was skipped: no knife") == \
        "## Hand-over rule\n\nThe closed-loop choice was skipped: no knife.\n"


def test_the_prediction_is_stated_when_recorded():
    predicted = {"line_ratio": 0.663, "effort_vs_voluntary": 0.5, "tracking_rmse_m": 0.012, "saw_correlation": 0.9,
                 "saws": True}
    md = rule_markdown(_choice(predicted=predicted))
    assert ("Predicted on these trials (an evaluation sets it beside what it realises): line ratio 0.663, effort "
            "0.50x voluntary, RMS 12.0 mm, stroke corr. 0.90, saws in every cutting episode") in md
    assert "Predicted" not in rule_markdown(_choice()) and "Left one trial out" not in md
    cv = {"line_ratio": 0.81, "effort_vs_voluntary": 0.55, "tracking_rmse_m": 0.013, "chosen": [0, 1]}
    assert ("Left one trial out (the rule chosen on the others, scored on it): line ratio 0.810, effort 0.55x "
            "voluntary.") in rule_markdown(_choice(predicted=predicted, cross_validated=cv))


# the choice's rows: a within the cap and sawing, b over the cap, c without a line ratio
_VOL = {"saws_by_trial": [True], "voluntary_effort": 0.1, "tracking_rmse_m": 0.01}
_REA = {"voluntary_effort": 0.02, "tracking_rmse_m": 0.02}
_A = {"strategy": "a", "effort_vs_voluntary": 0.5, "line_ratio": 0.7123, "tracking_rmse_m": 0.0061,
      "saws_by_trial": [True]}
_B = {"effort_vs_voluntary": 0.9, "line_ratio": 0.6, "tracking_rmse_m": 0.0042, "saws_by_trial": [False]}
_C = {"effort_vs_voluntary": 0.6, "line_ratio": None, "tracking_rmse_m": 0.0052, "saws_by_trial": [False]}
_CASES = [  # (rows, voluntary, reactive, task) -> the words the calibration said before the reason became a record
    ([_A, _B, _C], _VOL, _REA, EATING,
     "lowest line ratio (0.712) among the 2 of 3 candidates with effort <= 0.75x voluntary, of those that saw in "
     "every cutting episode where the wearer alone saws"),
    ([_A, _B], {**_VOL, "saws_by_trial": [False]}, _REA, EATING,
     "lowest line ratio (0.712) among the 1 of 2 candidates with effort <= 0.75x voluntary"),
    ([_A, _C], _VOL, {"voluntary_effort": 0.081, "tracking_rmse_m": 0.02}, EATING,
     "reactive alone costs 0.81x the voluntary effort, so the line is ill-posed; the lowest tracking RMS (6.1 mm) "
     "among the 2 of 2 candidates with effort <= 0.75x voluntary, of those that saw in every cutting episode where "
     "the wearer alone saws"),
    ([_C], _VOL, _REA, EATING,
     "no line ratio is defined; the lowest tracking RMS (5.2 mm) among the 1 of 1 candidates with effort <= 0.75x "
     "voluntary"),
    ([_B], _VOL, _REA, EATING, "no candidate has effort <= 0.75x voluntary; the lowest line ratio (0.600)"),
    ([{**_B, "line_ratio": None}], _VOL, _REA, EATING,
     "no candidate has effort <= 0.75x voluntary and none a line ratio; the lowest tracking RMS (4.2 mm)"),
    ([{**_B, "saws_by_trial": [True]}], _VOL, _REA, EATING,
     "no candidate has effort <= 0.75x voluntary; the lowest line ratio (0.600) of those that saw in every cutting "
     "episode where the wearer alone saws"),
    ([_A, _B], _VOL, _REA, Pouring(),
     "lowest line ratio (0.712) among the 1 of 2 candidates with effort <= 0.75x voluntary, of those that meet the "
     "task's criterion in every episode where the wearer alone meets it"),
]


@pytest.mark.parametrize("rows, vol, rea, task, words", _CASES)
def test_the_why_of_each_clause_of_the_criterion_reads_as_before(rows, vol, rea, task, words):
    _, reason = criterion(rows, vol, rea, 0.75, task)
    assert why_words({"criterion": reason, "mixture": None, "task_effort": None}) == words


def test_the_mixture_and_the_cutting_effort_add_their_sentences():
    mix = {"strategy": "mix75", "effort_vs_voluntary": 0.38, "line_ratio": 0.655, "tracking_rmse_m": 0.004,
           "saws_by_trial": [True]}
    _, reason = criterion([_A], _VOL, _REA, 0.75)
    winner = mix_winner(_A, [mix], _VOL, _REA, 0.75)
    assert winner == {"strategy": "mix75", "line_ratio": 0.655, "effort_vs_voluntary": 0.38}
    over = {"cutting_modes": [1, 2], "effort_vs_voluntary": 0.8, "max_effort": 0.75}
    assert why_words({"criterion": reason, "mixture": winner, "task_effort": over}) == (
        "lowest line ratio (0.712) among the 1 of 1 candidates with effort <= 0.75x voluntary, of those that saw in "
        "every cutting episode where the wearer alone saws; the constant mixture mix75 would win the criterion "
        "(line ratio 0.655 at 0.38x voluntary), but the gate's rule cannot be a constant mixture; leading the "
        "cutting modes [1, 2] costs the wearer 0.80x the effort of doing the task alone (the robot leading the "
        "rest; from the per-mode costs), so no rule that leaves them to the wearer stays within 0.75x here")
    assert "line ratio n/a at" in why_words({"criterion": reason, "mixture": {**winner, "line_ratio": None}})
    assert mix_winner(mix, [_A], _VOL, _REA, 0.75) is None  # the candidate wins: no sentence


def test_the_criterion_and_the_progress_lines_read_as_before():
    assert CRITERION == criterion_words(EATING) == (
        "among the candidates with effort <= max_effort x voluntary, those that saw in every cutting episode where "
        "the wearer alone saws (where none does, in every trial's cutting episodes as a whole), the lowest line "
        "ratio (the lowest tracking RMS where reactive itself costs >= max_effort x voluntary); if none is within "
        "the cap, the same without the cap (the lowest line ratio of those that saw)")
    assert criterion_words(Pouring()) == (
        "among the candidates with effort <= max_effort x voluntary, those that meet the task's criterion in every "
        "episode (trial) where the wearer alone meets it, the lowest line ratio (the lowest tracking RMS where "
        "reactive itself costs >= max_effort x voluntary); if none is within the cap, the same without the cap (the "
        "lowest line ratio of those that meet it)")
    row = {"wearer_modes": [1, 2], "timing": "early", "wearer_alpha": 0.0, "robot_alpha": 0.5,
           "tracking_rmse_m": 0.00612, "effort_vs_voluntary": 0.456, "line_ratio": None}
    assert candidate_line(row) == ("  gate with wearer modes [1, 2] (early hand-over, robot share 0 while the wearer "
                                   "leads, 0.5 while it leads): RMS 6.1 mm, effort 0.46x voluntary, line ratio n/a")
    assert pruned_line({"wearer_modes": [3], "why": "x"}) == (
        "  gate with wearer modes [3]: not simulated (the per-mode costs: x)")
    assert pruned_why(1.0573, 0.02257) == ("1.06x the voluntary effort and 22.6 mm before the hand-overs' cost, no "
                                           "better than the wearer alone on either")
    assert ran_line(7, 12) == ("  7 of the 12 episodes simulated: the others decide as one of them at every step "
                               "(the same episode)")


def test_the_why_says_when_only_the_trials_as_a_whole_saw():
    reason = {"max_effort": 0.75, "tracking_rmse_m": 0.01, "task_filter": "trial", "stroke_mode": "cutting",
              "within_cap": True, "n_within": 3, "n_candidates": 5, "by": "line_ratio", "line_ratio": 0.9}
    assert criterion_why(reason) == (
        "lowest line ratio (0.900) among the 3 of 5 candidates with effort <= 0.75x voluntary, of those that saw in "
        "every trial's cutting episodes as a whole where the wearer alone saws (none saws in every cutting episode)")
