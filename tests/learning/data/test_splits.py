"""Train/test splits by trial and by subject (learning.data.splits)."""

from __future__ import annotations

import pytest

from learning.data import split_by_subject, split_by_trial
from tests.learning.preprocessing.test_preprocess import make_demos


def test_split_by_trial() -> None:
    d = make_demos(lengths=(50,) * 8)
    train, test = split_by_trial(d, 0.25, seed=3)
    assert len(test) == 2 and len(train) == 6
    assert sorted(train.trial_ids + test.trial_ids) == list(range(8))
    assert train.trial_ids == sorted(train.trial_ids)
    again = split_by_trial(d, 0.25, seed=3)
    assert again[1].trial_ids == test.trial_ids
    assert any(split_by_trial(d, 0.25, seed=s)[1].trial_ids != test.trial_ids for s in range(4, 10))
    tiny_train, tiny_test = split_by_trial(make_demos(lengths=(50, 50)), 0.01)
    assert len(tiny_train) == 1 and len(tiny_test) == 1
    with pytest.raises(ValueError, match="at least 2 trials"):
        split_by_trial(make_demos(lengths=(50,)))
    with pytest.raises(ValueError, match="test_fraction"):
        split_by_trial(d, 1.0)


def test_split_by_subject() -> None:
    d = make_demos(lengths=(50,) * 6, subjects=[0, 1, 2, 0, 1, 2])
    train, test = split_by_subject(d, 2)
    assert test.trial_ids == [2, 5] and train.trial_ids == [0, 1, 3, 4]
    train, test = split_by_subject(d, [0, 1])
    assert test.subjects == [0, 1] and train.subjects == [2]
    with pytest.raises(ValueError, match="no trial of subject"):
        split_by_subject(d, 9)
    with pytest.raises(ValueError, match="training side would be empty"):
        split_by_subject(d, [0, 1, 2])
    with pytest.raises(ValueError, match="test side would be empty"):
        split_by_subject(d, [])
