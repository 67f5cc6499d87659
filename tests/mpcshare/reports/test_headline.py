"""The four answers a person reads first: the task, sharing (against each party and the line), effort, keep-out."""

from __future__ import annotations

from types import MappingProxyType

import pytest

import mpcshare.control.strategies as strategies
from mpcshare.control.strategies import REGISTRY, StrategySpec
from mpcshare.reports.headline import MIX_RUNS, headline_lines, headlines, lag_words, line_ratio, shared_strategy
from sim.task.eating import SAWING_MIN_AMPLITUDE, SAWING_MIN_CORRELATION


def _m(rms_mm: float, effort: float, **extra) -> dict:
    return {"tracking_rmse_m": rms_mm / 1e3, "voluntary_effort": effort, "lag_s": 0.12,
            "saw_amplitude_ratio": 0.9, "saw_correlation": 0.85, **extra}


def _runs(gate_mm: float, gate_effort: float = 0.03, **gate_extra) -> dict:
    return {"voluntary": _m(6.7, 0.06), "reactive": _m(18.4, 0.0), "gate": _m(gate_mm, gate_effort, **gate_extra)}


def test_line_ratio_is_the_rms_over_the_straight_line_at_the_same_effort():
    s = _runs(10.0, gate_effort=0.03)  # half way in effort: the line is at (6.7 + 18.4) / 2 = 12.55 mm
    assert line_ratio(s, "gate") == pytest.approx(10.0 / 12.55)
    s["gate"]["line_ratio"] = 0.5  # the comparison's own figure wins where it has one
    assert line_ratio(s, "gate") == 0.5
    del s["reactive"]
    assert line_ratio({"gate": _m(10.0, 0.03)}, "gate") is None


def test_sharing_says_when_it_loses_to_the_wearer_alone():
    h = {x.topic: x for x in headlines(_runs(15.7, gate_effort=0.048))}
    assert h["Sharing"].verdict.startswith("NO, it loses to the wearer alone")
    assert "15.7 mm" in h["Sharing"].text and "6.7 mm" in h["Sharing"].text and "18.4 mm" in h["Sharing"].text
    good = {x.topic: x for x in headlines(_runs(5.0))}
    assert good["Sharing"].verdict == "yes, it beats the wearer alone, the robot alone, mixing them (the line)"


def test_effort_task_and_keepout_each_have_a_figure_and_a_verdict():
    h = {x.topic: x for x in headlines(_runs(5.0, gate_effort=0.012))}
    assert h["Effort"].verdict == "80% saved" and "20%" in h["Effort"].text
    assert h["The task"].verdict == "yes, it sawed" and "0.85" in h["The task"].text
    assert h["Keep-out"].verdict == "not measured"  # no clearance figures in these runs
    weak = {x.topic: x for x in headlines(_runs(5.0, gate_effort=0.05, saw_correlation=0.2))}
    assert weak["Effort"].verdict == "only 17% saved" and weak["The task"].verdict.startswith("NO")
    zones = {x.topic: x for x in headlines(_runs(5.0, min_clearance_m=0.031, steps_driven_in=0))}
    assert zones["Keep-out"].verdict == "yes, it kept out" and "31 mm" in zones["Keep-out"].text
    bad = {x.topic: x for x in headlines(_runs(5.0, steps_driven_in=3))}
    assert bad["Keep-out"].verdict == "NO" and "3 control step" in bad["Keep-out"].text


def test_the_task_line_counts_the_cutting_episodes_and_names_the_worst():
    ep = [{"start_s": 1.0, "cutting_s": 4.0, "saw_correlation": 0.95, "saw_amplitude_ratio": 0.9},
          {"start_s": 30.0, "cutting_s": 3.0, "saw_correlation": 0.41, "saw_amplitude_ratio": 0.7},
          {"start_s": 50.0, "cutting_s": 2.0, "saw_correlation": 0.8, "saw_amplitude_ratio": 0.5}]
    h = {x.topic: x for x in headlines(_runs(5.0, saw_by_episode=ep))}
    assert "It sawed in 1 of 3 cutting episodes (each at least 1 s)" in h["The task"].text
    assert "the worst correlates 0.41 at 0.70 of the amplitude" in h["The task"].text
    assert "episodes" not in {x.topic: x for x in headlines(_runs(5.0))}["The task"].text  # none recorded


def test_the_four_lines_come_in_order_and_nothing_without_a_shared_run():
    lines = headline_lines(_runs(15.7), markdown=False)
    assert [ln.split(":")[0] for ln in lines] == ["The task", "Sharing", "Effort", "Keep-out"]
    assert headline_lines({"voluntary": _m(6.7, 0.06)}) == []


@pytest.mark.parametrize("order,first", [(3.5, "newshare"), (7.0, "gate")])
def test_a_strategy_registered_as_shared_reaches_the_headline_in_registry_order(monkeypatch, order, first):
    spec = StrategySpec("newshare", "A test strategy.", tunable=False, color="#000000",
                        factory=REGISTRY["gate"].factory, order=order, role="shared")
    specs = sorted([*REGISTRY.values(), spec], key=lambda s: (s.order, s.name))
    monkeypatch.setattr(strategies, "REGISTRY", MappingProxyType({s.name: s for s in specs}))
    runs = {**_runs(15.7), "newshare": _m(9.0, 0.03), "blend": _m(8.0, 0.03)}
    assert shared_strategy(runs) == first
    assert f"`{first}`" in headline_lines(runs)[1]
    assert shared_strategy({"voluntary": _m(6.7, 0.06), "newshare": _m(9.0, 0.03)}) == "newshare"


def _mixes(**mixes: tuple[float, float]) -> dict:
    """voluntary, reactive and gate (9.0 mm at effort 0.037) beside the given mixes (name: (mm, effort))."""
    s = {"voluntary": _m(13.2, 0.080), "reactive": _m(10.5, 0.015), "gate": _m(9.0, 0.037)}
    return {**s, **{k: _m(mm, e) for k, (mm, e) in mixes.items()}}


def test_sharing_beats_mixing_only_when_no_constant_mix_tracks_better_at_equal_or_lower_effort():
    assert MIX_RUNS == ("mix25", "mix50", "mix75")
    # the report a user misread: mix25 tracks worse at twice the effort, mix50 and mix75 worse at less
    h = {x.topic: x for x in headlines(_mixes(mix25=(9.3, 0.076), mix50=(10.5, 0.014), mix75=(10.4, 0.014)))}
    assert h["Sharing"].verdict == "yes, it beats the wearer alone, the robot alone, mixing them"
    assert "No constant mix tracks better at equal or lower effort" in h["Sharing"].text
    # mix75 tracks better at less effort: the gate loses to it, and the line names it with its figures
    h = {x.topic: x for x in headlines(_mixes(mix25=(9.3, 0.076), mix75=(8.1, 0.030)))}
    assert h["Sharing"].verdict == "NO, it loses to mixing them (`mix75`)"
    assert "`mix75` 8.1 mm at effort 0.030" in h["Sharing"].text and "mix25" not in h["Sharing"].text
    # better tracking at MORE effort is no win for the mix
    h = {x.topic: x for x in headlines(_mixes(mix25=(8.0, 0.060)))}
    assert h["Sharing"].verdict.startswith("yes") and "mix25" not in h["Sharing"].verdict
    # a mix within the tie at lower effort: a tie, named
    h = {x.topic: x for x in headlines(_mixes(mix50=(9.05, 0.020)))}
    assert h["Sharing"].verdict == "partly: it ties with mixing them (`mix50`)"


def test_without_mixes_the_line_ratio_stands_in_for_mixing():
    h = {x.topic: x for x in headlines(_runs(5.0))}
    assert "Line ratio" in h["Sharing"].text and "mixing them (the line)" in h["Sharing"].verdict


def test_a_negative_lag_reads_ahead_never_minus_late():
    assert lag_words(-0.02) == "20 ms ahead" and lag_words(0.11) == "110 ms late" and lag_words(0.0002) == "on time"
    text = headlines(_runs(5.0, lag_s=-0.06))[0].text
    assert "60 ms ahead" in text and "-60" not in text and "ms late" not in text


def test_the_sawing_criterion_is_the_tasks_and_is_stated_once():
    at = {x.topic: x for x in headlines(_runs(5.0, saw_correlation=SAWING_MIN_CORRELATION,
                                               saw_amplitude_ratio=SAWING_MIN_AMPLITUDE))}
    assert at["The task"].verdict == "yes, it sawed"
    below = {x.topic: x for x in headlines(_runs(5.0, saw_correlation=0.69, saw_amplitude_ratio=0.9))}
    assert below["The task"].verdict == "NO, it did not saw"
    assert at["The task"].text.count(f"at least {SAWING_MIN_CORRELATION:g}") == 1


def _choice(corr: float, amp: float) -> dict:
    settings = {"wearer_modes": [0]}
    return {"settings": settings, "trials": [3], "duration_s": 20.0,
            "candidates": [{"settings": {"wearer_modes": []}, "saw_correlation": 0.1, "saw_amplitude_ratio": 0.1},
                           {"settings": settings, "saw_correlation": corr, "saw_amplitude_ratio": amp}]}


def test_the_task_line_says_why_training_and_the_evaluation_disagree_on_sawing():
    not_here = headlines(_runs(5.0, saw_correlation=0.3), rule_choice=_choice(0.91, 0.8),
                         trials="trial(s) 2 (first 10 s)")[0]
    assert not_here.verdict == "NO, it did not saw"
    assert "Training chose this hand-over rule as one that saws" in not_here.text
    assert "trial(s) 3 (first 20 s)" in not_here.text and "correlated 0.91" in not_here.text
    assert "trial(s) 2 (first 10 s)" in not_here.text
    agree = headlines(_runs(5.0), rule_choice=_choice(0.91, 0.8))[0]
    assert "Training" not in agree.text  # both saw: nothing to explain


def test_a_task_without_strokes_is_judged_by_its_own_criterion():
    from tests.sim.task.test_protocol import Pouring

    task = Pouring()  # done: the tip within 0.2 s of the intent
    late = headlines(_runs(5.0, lag_s=0.5), task=task)[0]
    assert late.verdict == "NO, not done" and "the task's criterion is NOT met (the tip within 0.2 s" in late.text
    assert "saw" not in late.text and "cutting" not in late.text
    choice = {"settings": {"wearer_modes": [0]}, "trials": [3], "duration_s": 20.0,
              "candidates": [{"settings": {"wearer_modes": [0]}, "saws_by_trial": [True]}]}
    noted = headlines(_runs(5.0, lag_s=0.5), rule_choice=choice, trials="trial(s) 2 (first 10 s)", task=task)[0]
    assert "Training chose this hand-over rule as one that meets the task's criterion on trial(s) 3" in noted.text
    on_time = headlines(_runs(5.0, lag_s=0.1), rule_choice=choice, task=task)[0]
    assert on_time.verdict == "yes, done" and "Training" not in on_time.text  # both met it
