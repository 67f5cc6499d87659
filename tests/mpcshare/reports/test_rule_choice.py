"""The closed-loop choice of the hand-over rule in words: the section of ``training.md``."""

from __future__ import annotations

from mpcshare.reports.rule_choice import rule_markdown, skipped_markdown


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
