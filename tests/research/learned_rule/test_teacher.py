"""The teacher's ranking of replays and its labels read half a ramp ahead."""

from __future__ import annotations

import numpy as np
import pytest

from research.learned_rule.teacher import objective, teacher_labels


def test_objective_ranks_the_task_first():
    ok = {"line_ratio": 0.9, "effort_vs_voluntary": 0.5, "stroke_correlation": 0.7}
    assert objective(ok) == 0.9
    assert objective({**ok, "effort_vs_voluntary": 0.9}) == pytest.approx(10.2)
    assert objective({**ok, "stroke_correlation": None}) == pytest.approx(10.6)


def test_labels_read_the_schedule_half_a_ramp_ahead():
    times = np.arange(100) * 0.01
    alpha = np.where(times >= 0.5, 1.0, 0.0)
    ctx = {"n": [100], "times": [times]}
    y = teacher_labels(ctx, alpha, [times])
    assert np.flatnonzero(y)[0] == 25  # the default hand-over ramp is 0.5 s: read 0.25 s ahead
