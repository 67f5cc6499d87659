"""The held-out trials of the rule choice and of the evaluation (mpcshare.calibration.trials)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from mpcshare.calibration.trials import (
    bundle_evaluation_trials,
    choice_duration,
    choice_seconds,
    choice_trials,
    evaluation_trials,
    unseen_trials,
)


def test_the_choice_runs_on_the_last_held_out_trials_and_leaves_the_rest():
    assert choice_trials([2, 3]) == [3]  # half of them, 1 to 2
    assert choice_trials([2, 7, 9, 11]) == [9, 11]
    assert choice_trials([2, 7, 9, 11, 12, 13]) == [12, 13]
    assert choice_trials([5]) == [5]
    assert choice_trials([2, 7, 9], n_trials=1) == [9]
    assert choice_trials([2, 7, 9, 11], subjects={2: 0, 7: 0, 9: 0, 11: 0}) == [9, 11]  # one subject: the order


def test_the_choice_and_the_evaluation_draw_on_the_same_subjects():
    """The demo's split: held-out trials 2, 3 of subject 0 and 10, 11 of subject 2. The last two would give the
    choice subject 2 alone and the evaluation subject 0 alone; dealt round the subjects, each gets one of each."""
    subjects = {2: 0, 3: 0, 10: 2, 11: 2}
    chosen = choice_trials([2, 3, 10, 11], subjects=subjects)
    assert chosen == [3, 11] and evaluation_trials([2, 3, 10, 11], chosen) == [2, 10, 3, 11]
    assert {subjects[t] for t in chosen} == {subjects[t] for t in evaluation_trials([2, 3, 10, 11], chosen)[:2]}
    # uneven subjects: every subject's first trial, then the seconds; the choice takes the last of that order
    assert choice_trials([1, 2, 3, 8, 9], subjects={1: "a", 2: "a", 3: "a", 8: "b", 9: "c"}) == [2, 3]
    assert choice_trials([1, 8], subjects={1: "a", 8: "b"}) == [8]
    assert evaluation_trials([4, 5, 6], []) == [4, 5, 6] and evaluation_trials([4, 5, 6], [6, 4]) == [5, 4, 6]
    assert unseen_trials([4, 5, 6], [6, 4]) == [5] and unseen_trials([4, 5], [5, 4]) == []  # never the choice's own
    assert unseen_trials([4, 5, 6], [7]) == [4, 5, 6]
    rule = SimpleNamespace(choice={"trials": [3, 11]})
    assert bundle_evaluation_trials(SimpleNamespace(heldout_trials=[2, 3, 10, 11], rule=rule)) == [2, 10, 3, 11]
    assert bundle_evaluation_trials(SimpleNamespace(heldout_trials=[2, 3], rule=None)) == [2, 3]
    assert bundle_evaluation_trials(SimpleNamespace(heldout_trials=[2, 3])) == [2, 3]  # no rule at all


def _labelled(mode: list[tuple[int, float]], rate: float = 10.0) -> SimpleNamespace:
    """A trial whose mode labels are the (label, seconds) runs in ``mode``."""
    return SimpleNamespace(mode=np.concatenate([np.full(int(round(s * rate)), k) for k, s in mode]))


def test_the_choice_runs_until_every_trial_has_shown_the_stroke():
    early = _labelled([(1, 10.0), (0, 5.0), (1, 105.0)])  # the stroke (label 0) from 10 to 15 s
    late = _labelled([(1, 78.0), (0, 10.0), (1, 32.0)])  # from 78 to 88 s
    never = _labelled([(1, 120.0)])
    assert choice_duration([early, never], 60.0, 10.0, 0) == 60.0  # every trial that has a stroke shows it
    own = [SimpleNamespace(trial_id=i, mode=t.mode) for i, t in enumerate((early, late, never))]
    assert choice_seconds(own, 60.0, 10.0, 0) == {0: 60.0, 1: 81.0, 2: 60.0}  # only the late one runs longer
    assert choice_duration([early, late], 60.0, 10.0, 0) == 81.0  # 3 s of the late stroke: 78 to 81 s
    assert choice_duration([late], 60.0, 10.0, 0, stroke_seen_s=10.0) == 88.0
    short = _labelled([(1, 70.0), (0, 1.0), (1, 9.0)])  # one second of stroke in all: all of it
    assert choice_duration([short], 60.0, 10.0, 0) == 71.0
    brief = _labelled([(0, 1.0), (1, 59.0), (0, 5.0)])  # 1 s of it at the start, more after the window
    assert choice_duration([brief], 60.0, 10.0, 0) == 62.0  # 2 s more of it: 60 to 62 s
    assert choice_duration([late], 50.0, 10.0, 0, stretch=1.5) == 75.0  # at most 1.5 x 50 s
    assert choice_duration([late], 2.0, 10.0, 0) == 4.0  # a short choice stays short
    assert choice_duration([late], None, 10.0, 0) is None  # whole trials already
    assert choice_duration([late], 60.0, 10.0, None) == 60.0  # no stroke mode: the task has none
    assert choice_duration([SimpleNamespace(mode=None)], 60.0, 10.0, 0) == 60.0  # no labels
    for bad in (0.0, -1.0):
        with pytest.raises(ValueError, match="duration_s"):
            choice_duration([late], bad, 10.0, 0)
    with pytest.raises(ValueError, match="stretch"):
        choice_duration([late], 60.0, 10.0, 0, stretch=0.5)
    with pytest.raises(ValueError, match="rate_hz"):
        choice_duration([late], 60.0, float("nan"), 0)
