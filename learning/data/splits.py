"""Train/test splits of a data set by whole trials or by subject (never within a trial)."""

from __future__ import annotations

from collections.abc import Iterable

import numpy as np

from .model import Demonstrations

__all__ = ["split_by_subject", "split_by_trial"]


def split_by_trial(demos: Demonstrations, test_fraction: float = 0.25,
                   seed: int = 0) -> tuple[Demonstrations, Demonstrations]:
    """Random split of whole trials: ``round(n · test_fraction)`` test trials, at least 1
    and at most n−1; each side keeps the original trial order. Deterministic in ``seed``.

    Raises:
        ValueError: fewer than 2 trials, or ``test_fraction`` outside (0, 1).
    """
    n = len(demos)
    if not 0.0 < test_fraction < 1.0:
        raise ValueError(f"test_fraction must be in (0, 1), got {test_fraction!r}")
    if n < 2:
        raise ValueError(f"need at least 2 trials to split by trial, got {n}; one side would be empty")
    n_test = min(max(int(np.rint(n * test_fraction)), 1), n - 1)
    rng = np.random.default_rng(seed)
    test_pos = set(rng.permutation(n)[:n_test].tolist())
    ids = demos.trial_ids
    train = [ids[i] for i in range(n) if i not in test_pos]
    test = [ids[i] for i in range(n) if i in test_pos]
    return demos.select(train), demos.select(test)


def split_by_subject(demos: Demonstrations,
                     test_subjects: int | Iterable[int]) -> tuple[Demonstrations, Demonstrations]:
    """Train = trials of the other subjects, test = trials of ``test_subjects``.

    Raises:
        ValueError: a requested subject has no trial, or a side would be empty.
    """
    wanted = {int(test_subjects)} if isinstance(test_subjects, (int, np.integer)) else \
        {int(s) for s in test_subjects}
    have = set(demos.subjects)
    missing = sorted(wanted - have)
    if missing:
        raise ValueError(f"no trial of subject(s) {missing} (subjects: {sorted(have)})")
    if not wanted:
        raise ValueError("test_subjects is empty; the test side would be empty")
    if wanted >= have:
        raise ValueError(f"test_subjects {sorted(wanted)} cover every subject; the training side "
                         f"would be empty")
    train = [tr.trial_id for tr in demos.trials if tr.subject not in wanted]
    test = [tr.trial_id for tr in demos.trials if tr.subject in wanted]
    return demos.select(train), demos.select(test)
