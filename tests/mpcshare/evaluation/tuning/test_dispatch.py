"""The tune's dispatch (mpcshare.evaluation.tuning.dispatch): the estimate from measured recordings and replays."""

from __future__ import annotations

import pytest

from mpcshare.evaluation.tuning.episodes import plan_tasks


def test_the_estimate_counts_recordings_and_replays():
    from mpcshare.evaluation.tuning.dispatch import Costs

    costs = Costs()
    task = plan_tasks([90.0], [0.5], ["gate"], [3], [0], {90.0: "b"}, "d", 1.0, "w")[0]
    costs.add(task, 6.0, pid=1)  # the first of bundle b, trial 3 in process 1: a recording
    assert not costs.ready(workers=2)
    costs.add(task, 4.0, pid=1)
    costs.add(task, 2.0, pid=1)
    assert costs.recorded == [6.0] and costs.replayed == [4.0, 2.0] and costs.ready(workers=2)
    # 2 processes x 2 bundles and trials = 4 recordings, 1 done: 3 more at 6 s, the other 7 at 3 s, on 2 processes
    assert costs.estimate(10, wheres=2, workers=2) == pytest.approx((3 * 6.0 + 7 * 3.0) / 2)
