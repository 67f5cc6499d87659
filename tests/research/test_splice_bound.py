"""The splice bound: its front and line ratio against brute force over every assignment."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from mpcshare.line_ratio import line_ratio
from research.splice_bound import best_line_ratio, group_sums, splice_front


def _runs(seed: int, runs: int = 3, steps: int = 40, groups: int = 5):
    rng = np.random.default_rng(seed)
    e2 = rng.gamma(2.0, 1e-5, (runs, steps)) * rng.uniform(0.3, 3.0, (runs, 1))
    effort = rng.gamma(2.0, 0.02, (runs, steps)) * rng.uniform(0.2, 2.0, (runs, 1))
    labels = np.sort(rng.integers(0, groups, steps))  # groups of uneven size, one label absent at times
    return e2, effort, labels


def _brute(e2, effort, labels, allowed=None):
    """Every assignment of a run per group: (mean effort, mean squared error, assignment)."""
    names, g_e2 = group_sums(e2, labels)
    _, g_ef = group_sums(effort, labels)
    n, out = labels.size, []
    options = [np.flatnonzero(allowed[:, g]) if allowed is not None else range(e2.shape[0])
               for g in range(names.size)]
    for a in itertools.product(*options):
        idx = (np.array(a), np.arange(names.size))
        out.append((g_ef[idx].sum() / n, g_e2[idx].sum() / n, np.array(a)))
    return out


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_front_is_the_lowest_error_at_each_effort_as_brute_force_finds(seed):
    """Every assignment lies on or above the front at its effort (up to one bin), and each front point is
    an assignment whose spliced error it reports exactly, at an effort it does not overstate."""
    e2, effort, labels = _runs(seed)
    front = splice_front(e2, effort, labels, bins=20000)
    brute = _brute(e2, effort, labels)
    width = max(e for e, _, _ in brute) / 20000
    for e, m, _ in brute:
        below = front.mse[front.effort <= e + 1e-12]
        assert below.min() <= m + 1e-15  # nothing beats the front at or below its effort
    for i in range(0, front.effort.size, max(1, front.effort.size // 25)):
        a = front.assignment(i)
        e, m = next((e, m) for e, m, b in brute if np.array_equal(b, a))
        assert front.mse[i] == pytest.approx(m, rel=1e-12)
        assert e - 2 * width * len(a) <= front.effort[i] <= e + 1e-12  # rounded down, never up


@pytest.mark.parametrize("seed", [3, 4])
def test_the_best_line_ratio_within_the_cap_matches_brute_force(seed):
    e2, effort, labels = _runs(seed, runs=4, groups=4)
    effort *= np.array([[3.0], [0.1], [1.0], [0.5]]) / effort.mean(axis=1, keepdims=True)  # the wearer most
    e2 *= np.array([[1.0], [3.0], [1.5], [2.0]]) / e2.mean(axis=1, keepdims=True)  # the robot least well
    vol = (float(effort[0].mean()), float(np.sqrt(e2[0].mean())))
    rea = (float(effort[1].mean()), float(np.sqrt(e2[1].mean())))
    front = splice_front(e2, effort, labels, bins=50000)
    for cap in (0.75, None):
        got, where = best_line_ratio(front, vol, rea, cap)
        limit = np.inf if cap is None else cap * vol[0]
        ratios = [line_ratio(float(np.sqrt(m)), e, vol, rea) for e, m, _ in _brute(e2, effort, labels) if e <= limit]
        want = min(r for r in ratios if r is not None)
        assert got == pytest.approx(want, rel=2e-3)  # the bins round efforts down: optimistic by at most a bin
        assert got <= want + 1e-12 and where is not None


def test_a_forced_group_takes_only_its_allowed_run():
    e2, effort, labels = _runs(5)
    allowed = np.ones((3, np.unique(labels).size), dtype=bool)
    allowed[1:, 0] = False  # group 0 must take run 0 (the wearer leads the cutting mode, say)
    front = splice_front(e2, effort, labels, allowed=allowed, bins=20000)
    assert all(front.assignment(i)[0] == 0 for i in range(front.effort.size))
    free = splice_front(e2, effort, labels, bins=20000)
    assert front.mse.min() >= free.mse.min() - 1e-15
    forced = _brute(e2, effort, labels, allowed)
    assert front.mse.min() == pytest.approx(min(m for _, m, _ in forced), rel=1e-12)


def test_bad_input_is_refused_with_what_is_wrong():
    e2, effort, labels = _runs(6)
    with pytest.raises(ValueError, match="one group per step"):
        splice_front(e2, effort[:, :-1], labels)
    with pytest.raises(ValueError, match="finite"):
        splice_front(np.where(e2 > 0, np.nan, e2), effort, labels)
    with pytest.raises(ValueError, match="a run allowed in every group"):
        splice_front(e2, effort, labels, allowed=np.zeros((3, np.unique(labels).size), dtype=bool))
