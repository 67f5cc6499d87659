"""The closed-loop choice of the gate's wearer modes: candidates, the line ratio, the criterion."""

from __future__ import annotations

import numpy as np
import pytest

from mpcshare.calibration import rule_choice
from mpcshare.calibration.rule_choice import candidate_sets, choose_rule, line_ratio
from mpcshare.control.strategies.gate import GateSettings, wearer_indicator
from mpcshare.reports.rule_choice import rule_markdown, span_words


def test_candidates_are_price_prefixes_with_and_without_the_cutting_modes():
    assert candidate_sets([2, 0, 1], [], 4) == [[2], [0, 2], [0, 1, 2], []]  # last: the robot leads every mode
    assert candidate_sets([2, 0, 1], [3], 4) == [[2], [2, 3], [0, 2], [0, 2, 3], [0, 1, 2], [3], []]
    assert candidate_sets([1, 0], [], 2) == [[1], []]  # never every mode: that is `voluntary`
    assert candidate_sets([], [0], 3) == [[0], []]  # nothing worth its price: the cutting alone, or the robot
    for modes in candidate_sets([2, 0, 1], [3], 4):  # each is a valid gate setting
        GateSettings(wearer_modes=tuple(modes), **rule_choice.HANDOVER_SETTINGS)
        assert wearer_indicator(modes, 4).sum() == len(modes)


def test_line_ratio_against_the_straight_line():
    vol = {"tracking_rmse_m": 0.010, "voluntary_effort": 0.08}
    rea = {"tracking_rmse_m": 0.020, "voluntary_effort": 0.02}
    assert line_ratio(0.010, 0.08, vol, rea) == pytest.approx(1.0)
    assert line_ratio(0.015, 0.05, vol, rea) == pytest.approx(1.0)  # the midpoint lies on the line
    assert line_ratio(0.012, 0.05, vol, rea) == pytest.approx(0.8)
    # equal efforts: the line is the better party (mpcshare.line_ratio, the one definition)
    assert line_ratio(0.012, 0.05, vol, dict(vol)) == pytest.approx(1.2)
    assert line_ratio(0.030, 0.10, vol, rea) == pytest.approx(3.0)  # beyond both efforts: the better party


class _Episode:
    """The fields mode_costs reads: per control step the mode estimate, tip, intent, shoulder angles."""

    def __init__(self, mode, err_m, effort_rad):
        n = len(mode)
        self.mode = np.asarray(mode)
        self.tip_intent = np.zeros((n, 3))
        self.tip = np.zeros((n, 3))
        self.tip[:, 0] = err_m
        self.voluntary = np.zeros((n, 3))
        self.voluntary[:, 1] = effort_rad


class _Bundle:
    model_hz = 10.0

    class modes:
        transmat_ = np.full((3, 3), 1 / 3)


def _fake_runs(figures, by_modes, calls):
    """pooled_runs replaced: the parties' figures and episodes (mode 1 costs the robot most per effort), and
    per gate candidate (its wearer modes, or (modes, timing), (modes, robot share while the wearer leads) or
    (modes, ("robot", share while the robot leads)) where that differs) given (RMS, effort, stroke
    correlation)."""
    mode = np.repeat([0, 1, 2], 100)

    def fake(bundle, demos, trials, strategy, options, duration_s, wearer, seed, mode_names=None):
        calls.append((strategy, None if options is None else tuple(options["wearer_modes"])))
        if strategy == "gate":
            modes, a_w = tuple(options["wearer_modes"]), options.get("wearer_alpha", 0.0)
            timing = "early" if options["share_on"] == rule_choice.EARLY_HANDOVER_SETTINGS["share_on"] else "prompt"
            a_r = options["robot_alphas"][0]
            rms, eff, saw = by_modes.get((modes, ("robot", a_r)), by_modes.get(
                (modes, timing), by_modes.get((modes, a_w), by_modes[modes])))
            return {"tracking_rmse_m": rms, "voluntary_effort": eff, "limit_violations": 0, "saw_correlation": saw,
                    "saw_amplitude_ratio": 0.9}, []
        if strategy.startswith("mix"):  # the constant mixtures: given, else at the wearer's effort and 5x the error
            rms, eff, saw = figures.get(strategy, (5 * figures["voluntary"][0], figures["voluntary"][1], None))
            return {"tracking_rmse_m": rms, "voluntary_effort": eff, "limit_violations": 0, "saw_correlation": saw,
                    "saw_amplitude_ratio": 0.9}, []
        rms, eff, saw = figures[strategy]
        err = {"voluntary": [0.005, 0.005, 0.005], "reactive": [0.006, 0.030, 0.012]}[strategy]
        effort = {"voluntary": [0.05, 0.05, 0.10], "reactive": [0.01, 0.01, 0.01]}[strategy]
        ep = _Episode(mode, np.repeat(err, 100), np.repeat(effort, 100))
        return {"tracking_rmse_m": rms, "voluntary_effort": eff, "limit_violations": 0, "saw_correlation": saw,
                "saw_amplitude_ratio": 0.9}, [ep]

    def fake_many(bundle, demos, trials, specs, duration_s, wearer, seed, mode_names=None, pool=None, **_):
        return [fake(bundle, demos, trials, s, o, duration_s, wearer, seed, mode_names) for s, o in specs]
    return fake_many


def test_the_criterion_prefers_the_best_line_within_the_effort_cap(monkeypatch):
    """With simulated figures (the loop replaced): the candidates follow the measured prices; the lowest
    line ratio among efforts <= 0.75x wins; when none is below the cap, or the robot alone costs the
    wearer as much, the lowest RMS."""
    figures = {"voluntary": (0.010, 0.08, None), "reactive": (0.020, 0.02, None)}
    by_modes = {(1,): (0.014, 0.04, None), (1, 2): (0.0105, 0.07, None), (): (0.021, 0.075, None)}
    calls: list = []
    monkeypatch.setattr(rule_choice, "pooled_runs", _fake_runs(figures, by_modes, calls))
    choice = choose_rule(_Bundle(), None, [3], robot_alphas=(1.0,))
    assert choice["price_order"] == [1, 2, 0]  # mode 1: 0.0009 - 0.000025 m² saved for 0.04 rad
    # each non-empty set with the prompt and the early hand-over; the empty set (no hand-over) once
    assert [c[1] for c in calls if c[0] == "gate"] == [(1,), (1,), (1, 2), (1, 2), ()]
    assert [c["timing"] for c in choice["candidates"]] == ["prompt", "early"] * 2 + ["prompt"]
    assert choice["wearer_modes"] == [1] and "lowest line ratio" in choice["why"]  # 0.82 at 0.5x
    assert choice["settings"]["wearer_modes"] == [1]
    assert choice["mode_costs"]["rms_robot_mm"] == pytest.approx([6.0, 30.0, 12.0])
    by_modes[(1,)] = (0.014, 0.07, None)
    choice = choose_rule(_Bundle(), None, [3])
    assert choice["wearer_modes"] == [1, 2] and "no candidate" in choice["why"]  # the lowest line (0.90)
    # none within the cap: the lowest line ratio without it, not the lowest RMS (which would hand the wearer
    # nearly everything): [1] at 0.775x tracks at 0.885 of the line, [1, 2] at 0.99x at 1.03
    both = {(1,): (0.0115, 0.062, None), (1, 2): (0.0105, 0.079, None), (): (0.021, 0.075, None)}
    monkeypatch.setattr(rule_choice, "pooled_runs", _fake_runs(figures, both, []))
    relaxed = choose_rule(_Bundle(), None, [3])
    assert relaxed["wearer_modes"] == [1] and "no candidate" in relaxed["why"] and "line ratio" in relaxed["why"]
    monkeypatch.setattr(rule_choice, "pooled_runs", _fake_runs(figures, by_modes, calls))
    md = rule_markdown(choice)
    assert "| gate | [1, 2] |" in md and "| 1 | 0.33 | 5.0 | 30.0 |" in md
    by_modes.update({(1,): (0.0105, 0.04, None), (1, 2): (0.0104, 0.05, None)})
    figures["reactive"] = (0.020, 0.065, None)  # the robot alone costs 0.81x: the line is ill-posed
    choice = choose_rule(_Bundle(), None, [3])  # the lowest RMS within the cap; (): 0.075 is above it
    assert choice["wearer_modes"] == [1, 2] and "reactive alone costs 0.81x" in choice["why"]
    by_modes[()] = (0.009, 0.058, None)  # the robot leading every mode tracks best: the choice keeps it leading
    assert choose_rule(_Bundle(), None, [3])["wearer_modes"] == []
    by_modes[()] = (0.009, 0.066, None)  # ... but not above the effort cap
    assert choose_rule(_Bundle(), None, [3])["wearer_modes"] == [1, 2]
    with pytest.raises(ValueError, match="at least one held-out trial"):
        choose_rule(_Bundle(), None, [])


def test_where_the_wearer_saws_the_choice_saws(monkeypatch):
    """The task first: a candidate that does not saw loses to one that does, even at a better line."""
    figures = {"voluntary": (0.010, 0.08, 0.95), "reactive": (0.020, 0.02, 0.1)}
    by_modes = {(1,): (0.012, 0.04, 0.65), (1, 2): (0.0125, 0.05, 0.9), (): (0.02, 0.02, 0.1)}  # 0.65: not sawing
    monkeypatch.setattr(rule_choice, "pooled_runs", _fake_runs(figures, by_modes, []))
    choice = choose_rule(_Bundle(), None, [3])
    assert choice["wearer_modes"] == [1, 2] and "that saw" in choice["why"]
    by_modes[(1, 2)] = (0.0125, 0.07, 0.9)  # the sawing candidate costs too much: the best line among the rest
    assert choose_rule(_Bundle(), None, [3])["wearer_modes"] == [1]


def test_where_sawing_and_the_effort_cap_exclude_each_other_the_choice_says_so(monkeypatch):
    """Leading the cutting modes [1, 2] costs the wearer (0.01 + 0.05 + 0.10) / (0.05 + 0.05 + 0.10) = 0.80x
    the effort alone (the fake per-mode efforts): no rule that leaves them to the wearer stays within 0.75x, and the why
    says so; with the cutting in mode 2 alone (0.60x) it does not."""
    figures = {"voluntary": (0.010, 0.08, 0.95), "reactive": (0.020, 0.02, 0.1)}
    by_modes = {(1,): (0.012, 0.04, 0.65), (1, 2): (0.0125, 0.07, 0.9), (): (0.02, 0.02, 0.1),
                (2,): (0.013, 0.07, 0.9)}
    monkeypatch.setattr(rule_choice, "pooled_runs", _fake_runs(figures, by_modes, []))
    monkeypatch.setattr(rule_choice, "_cutting", lambda *a: [1, 2])
    choice = choose_rule(_Bundle(), None, [3])
    assert choice["cutting_effort_vs_voluntary"] == pytest.approx(0.8)
    assert "costs the wearer 0.80x the effort of doing the task alone" in choice["why"]
    assert "costs the wearer 0.80x" in rule_markdown(choice)
    monkeypatch.setattr(rule_choice, "_cutting", lambda *a: [2])
    choice = choose_rule(_Bundle(), None, [3])
    assert choice["cutting_effort_vs_voluntary"] == pytest.approx(0.6)
    assert "effort of doing the task alone" not in choice["why"]


def test_a_robot_share_while_the_wearer_leads_is_chosen_where_it_measures_better(monkeypatch):
    """The mixture within the wearer's modes (wearer_alpha 0.25) wins only where its closed loop is better,
    and is then in the settings the saved gate reads."""
    figures = {"voluntary": (0.010, 0.08, None), "reactive": (0.020, 0.02, None)}
    by_modes = {(1,): (0.014, 0.04, None), (1, 2): (0.0105, 0.07, None), (): (0.021, 0.075, None)}
    calls: list = []
    monkeypatch.setattr(rule_choice, "pooled_runs", _fake_runs(figures, by_modes, calls))
    choice = choose_rule(_Bundle(), None, [3], wearer_alphas=(0.0, 0.25), timings=("prompt",), robot_alphas=(1.0,))
    # each non-empty set alone and with the robot's share 0.25 while the wearer leads; the empty set once
    assert [c[1] for c in calls if c[0] == "gate"] == [(1,), (1,), (1, 2), (1, 2), ()]
    assert choice["settings"]["wearer_alpha"] == 0.0  # a tie: the wearer alone (tried first)
    # every candidate writes its share out (its settings replace a bundle's earlier rule as a whole)
    assert all(set(c["settings"]) >= {"wearer_modes", "wearer_alpha"} for c in choice["candidates"])
    by_modes[((1,), 0.25)] = (0.012, 0.042, None)  # 0.012 at 0.525x: line 0.74, better than 0.82
    assert choose_rule(_Bundle(), None, [3])["settings"]["wearer_alpha"] == 0.0  # not tried by default
    choice = choose_rule(_Bundle(), None, [3], wearer_alphas=(0.0, 0.25), timings=("prompt",))
    assert choice["wearer_modes"] == [1] and choice["settings"]["wearer_alpha"] == 0.25
    assert GateSettings(**choice["settings"]).wearer_alpha == 0.25
    assert "| gate | [1] | prompt | 0.25 |" in rule_markdown(choice)
    # 2 sets x 2 timings + the empty set at the robot's full share while it leads; then the best two of
    # those ([1] early and prompt: a tie, 0.82) and the empty set at the robot's share 0.5
    rows = choose_rule(_Bundle(), None, [3])["candidates"]
    assert [(r["wearer_modes"], r["timing"], r["robot_alpha"]) for r in rows] == [
        ([1], "prompt", 1.0), ([1], "early", 1.0), ([1, 2], "prompt", 1.0), ([1, 2], "early", 1.0),
        ([], "prompt", 1.0), ([1], "prompt", 0.5), ([1], "early", 0.5), ([], "prompt", 0.5)]


def test_the_early_hand_over_is_chosen_where_it_measures_better(monkeypatch):
    """The early timing (the wearer leads once a wearer mode is possible within 1.5 s, 1 s longer) wins only
    where its closed loop is better, and its settings are then what the saved gate reads."""
    figures = {"voluntary": (0.010, 0.08, None), "reactive": (0.020, 0.02, None)}
    by_modes = {(1,): (0.014, 0.04, None), (1, 2): (0.0105, 0.07, None), (): (0.021, 0.075, None)}
    monkeypatch.setattr(rule_choice, "pooled_runs", _fake_runs(figures, by_modes, []))
    assert choose_rule(_Bundle(), None, [3])["settings"]["share_on"] == 0.5  # a tie: the prompt one
    by_modes[((1,), "early")] = (0.012, 0.05, None)  # 0.012 at 0.625x: line 0.73, better than 0.82
    choice = choose_rule(_Bundle(), None, [3])
    assert choice["wearer_modes"] == [1] and choice["settings"] == {
        "wearer_modes": [1], **rule_choice.EARLY_HANDOVER_SETTINGS, "wearer_alpha": 0.0, "robot_alphas": [1.0] * 3}
    assert GateSettings(**choice["settings"]).lead_s == 1.5
    assert "| gate | [1] | early | 0 |" in rule_markdown(choice)
    with pytest.raises(ValueError, match="unknown hand-over timing.*valid: prompt, early"):
        choose_rule(_Bundle(), None, [3], timings=("late",))


def test_a_robot_share_below_one_while_the_robot_leads_is_chosen_where_it_measures_better(monkeypatch):
    """The robot's share 0.5 while it leads (the mixture ``mix50`` in the robot's modes) wins only where its
    closed loop is better; it is written out per mode, for the saved gate; a share below 0.5 is refused."""
    figures = {"voluntary": (0.010, 0.08, None), "reactive": (0.020, 0.02, None)}
    by_modes = {(1,): (0.014, 0.04, None), (1, 2): (0.0105, 0.07, None), (): (0.021, 0.075, None)}
    monkeypatch.setattr(rule_choice, "pooled_runs", _fake_runs(figures, by_modes, []))
    assert choose_rule(_Bundle(), None, [3])["settings"]["robot_alphas"] == [1.0] * 3  # a tie: the robot's full share
    by_modes[((), ("robot", 0.5))] = (0.0115, 0.03, None)  # 0.0115 at 0.375x: line 0.70, better than 0.82
    choice = choose_rule(_Bundle(), None, [3])
    assert choice["wearer_modes"] == [] and choice["settings"]["robot_alphas"] == [0.5] * 3
    assert "| gate | [] | prompt | 0 | 0.5 |" in rule_markdown(choice)
    # the second stage tries the share only on the first stage's best two and the empty set: [1, 2] (above the
    # effort cap at full share) is not tried at 0.5, however well it would do there
    del by_modes[((), ("robot", 0.5))]
    by_modes[((1, 2), ("robot", 0.5))] = (0.009, 0.03, None)
    choice = choose_rule(_Bundle(), None, [3])
    assert choice["wearer_modes"] == [1] and not any(r["wearer_modes"] == [1, 2] and r["robot_alpha"] == 0.5
                                                     for r in choice["candidates"])
    with pytest.raises(ValueError, match=r"robot_alphas must be shares in \[0.5, 1\]"):
        choose_rule(_Bundle(), None, [3], robot_alphas=(0.25,))


def test_a_bundle_without_a_mode_model_is_refused():
    class NoModes:
        modes = None

    with pytest.raises(ValueError, match="no mode model"):
        choose_rule(NoModes(), None, [3])


def test_sawing_needs_both_the_correlation_and_the_amplitude():
    assert rule_choice.saws({"saw_correlation": 0.7, "saw_amplitude_ratio": 0.6})
    assert not rule_choice.saws({"saw_correlation": 0.95, "saw_amplitude_ratio": 0.5})  # too small a stroke
    assert not rule_choice.saws({"saw_correlation": None, "saw_amplitude_ratio": None})  # no cutting seen


def _with_episodes(fake_many, by_trial):
    """pooled_runs whose rows also carry per-trial sawing (``by_trial``: a strategy or a gate candidate's wearer
    modes → the ``saws_by_trial`` list)."""
    def many(bundle, demos, trials, specs, *args, **kwargs):
        rows = fake_many(bundle, demos, trials, specs, *args, **kwargs)
        for (strategy, options), (row, _) in zip(specs, rows):
            key = tuple(options["wearer_modes"]) if strategy == "gate" else strategy
            row["saws_by_trial"] = by_trial.get(key, [False] * len(trials))
        return rows
    return many


def test_a_candidate_must_saw_in_every_cutting_episode_where_the_wearer_saws(monkeypatch):
    """Pooled, both sets saw; per trial, [1] misses the second trial's cutting, so the choice takes [1, 2] at a
    worse line. A trial where the wearer alone does not saw does not count against a candidate."""
    figures = {"voluntary": (0.010, 0.08, 0.95), "reactive": (0.020, 0.02, 0.1)}
    by_modes = {(1,): (0.012, 0.04, 0.8), (1, 2): (0.0125, 0.05, 0.9), (): (0.02, 0.02, 0.1)}
    by_trial = {"voluntary": [True, True, None], "reactive": [False, False, None], (1,): [True, False, None],
                (1, 2): [True, True, None], (): [False, False, None]}
    fake = _fake_runs(figures, by_modes, [])
    monkeypatch.setattr(rule_choice, "pooled_runs", _with_episodes(fake, by_trial))
    choice = choose_rule(_Bundle(), None, [3, 4, 5], robot_alphas=(1.0,))
    assert choice["wearer_modes"] == [1, 2] and "every cutting episode" in choice["why"]
    assert choice["predicted"]["saws"] and choice["predicted"]["line_ratio"] == pytest.approx(
        choice["candidates"][2]["line_ratio"])
    by_trial["voluntary"] = [True, False, None]  # the wearer alone misses the second: [1] counts as sawing
    choice = choose_rule(_Bundle(), None, [3, 4, 5], robot_alphas=(1.0,))
    assert choice["wearer_modes"] == [1]
    assert choice["predicted"] == {"line_ratio": pytest.approx(choice["candidates"][0]["line_ratio"]),
                                   "effort_vs_voluntary": pytest.approx(0.5), "tracking_rmse_m": 0.012,
                                   "saw_correlation": 0.8, "saws": True}
    assert rule_choice.saws_where_the_wearer_saws({"saw_correlation": 0.1, "saw_amplitude_ratio": 0.1},
                                                  {"saws_by_trial": [True]}) is False  # no per-trial: pooled


def test_constant_mixtures_are_reported_and_the_why_says_when_one_would_win(monkeypatch):
    """The mixtures run beside the parties; they never become the gate's rule, but the why names one that wins the
    criterion. ``mixes=()`` runs none."""
    figures = {"voluntary": (0.010, 0.08, None), "reactive": (0.020, 0.02, None)}
    by_modes = {(1,): (0.014, 0.04, None), (1, 2): (0.0105, 0.07, None), (): (0.021, 0.075, None)}
    calls: list = []
    monkeypatch.setattr(rule_choice, "pooled_runs", _fake_runs(figures, by_modes, calls))
    choice = choose_rule(_Bundle(), None, [3])
    assert [m["strategy"] for m in choice["mixes"]] == ["mix25", "mix50", "mix75"]
    assert "constant mixture" not in choice["why"] and choice["wearer_modes"] == [1]
    figures["mix75"] = (0.012, 0.03, None)  # line ratio 0.012 / 0.01833 = 0.655 at 0.375x, below [1]'s 0.84
    choice = choose_rule(_Bundle(), None, [3])
    assert choice["wearer_modes"] == [1] and choice["settings"]["wearer_modes"] == [1]
    assert "the constant mixture mix75 would win the criterion (line ratio 0.655 at 0.38x voluntary)" in choice["why"]
    assert "| mix75 | | | | | 12.0 | 0.38 | 0.655 | n/a |" in rule_markdown(choice)
    calls.clear()
    assert choose_rule(_Bundle(), None, [3], mixes=())["mixes"] == [] and not any(c[0].startswith("mix") for c in calls)
    with pytest.raises(ValueError, match="not constant mixtures"):
        choose_rule(_Bundle(), None, [3], mixes=("gate",))


def test_the_choice_runs_long_enough_for_every_trial_to_show_the_stroke(monkeypatch):
    """A choice trial whose first seconds hold no cutting cannot tell a sawing candidate from one that does not:
    choose_for_bundle runs such a trial until it has shown 3 s of it (here trial 5's starts at 78 s), the others
    for the seconds given, logs it, and records the seconds each ran; ``stroke_seen_s=None`` keeps the seconds it
    was given."""
    from types import SimpleNamespace

    from mpcshare.calibration.rule_choice import choose_for_bundle

    figures = {"voluntary": (0.010, 0.08, 0.95), "reactive": (0.020, 0.02, 0.1)}
    by_modes = {(1,): (0.012, 0.04, 0.8), (1, 2): (0.0125, 0.05, 0.9), (): (0.02, 0.02, 0.1)}
    fake, durations = _fake_runs(figures, by_modes, []), []

    def spy(bundle, demos, trials, specs, duration_s, *args, **kwargs):
        durations.append(duration_s)
        return fake(bundle, demos, trials, specs, duration_s, *args, **kwargs)

    monkeypatch.setattr(rule_choice, "pooled_runs", spy)
    labels = {4: np.r_[np.ones(100), np.zeros(50), np.ones(1050)], 5: np.r_[np.ones(780), np.zeros(100), np.ones(320)]}
    demos = SimpleNamespace(rate_hz=10.0, trials=[SimpleNamespace(trial_id=t, subject=0, mode=m.astype(int))
                                                  for t, m in labels.items()])
    bundle, said = _Bundle(), []
    bundle.heldout_trials = [4, 5]
    choice = choose_for_bundle(bundle, demos, n_trials=2, duration_s=60.0, mode_names=("cutting", "other"),
                               log=said.append, workers=1, robot_alphas=(1.0,))
    assert durations and all(d == {4: 60.0, 5: 81.0} for d in durations) and choice["trials"] == [4, 5]
    assert choice["duration_s"] == 81.0 and choice["duration_by_trial"] == [[4, 60.0], [5, 81.0]]
    assert any("81 s of trial 5 (the others 60 s)" in line for line in said)  # only the trial that lacks it
    assert span_words(choice) == "first 60 s of trial 4 and 81 s of trial 5"
    durations.clear()
    choice = choose_for_bundle(bundle, demos, n_trials=2, duration_s=60.0, mode_names=("cutting", "other"), log=None,
                               workers=1, robot_alphas=(1.0,), stroke_seen_s=None)
    assert choice["duration_s"] == 60.0 and set(durations) == {60.0} and "duration_by_trial" not in choice
    assert span_words(choice) == "first 60 s"
