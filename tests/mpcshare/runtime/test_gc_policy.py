"""The garbage collector while `mpcshare run` ticks: frozen after setup, collected in the slack."""

from __future__ import annotations

import gc

import pytest

from mpcshare.runtime.gc_policy import CollectorPolicy


def test_managed_freezes_then_collects_only_in_enough_slack():
    was = gc.isenabled()
    policy = CollectorPolicy("managed", min_slack_s=0.002)
    policy.start()
    try:
        assert not gc.isenabled() and gc.get_freeze_count() > 0
        junk = [[i] for i in range(5 * gc.get_threshold()[0])]  # the young generation over its threshold
        assert gc.get_count()[0] >= gc.get_threshold()[0]
        assert policy.idle(0.001) == -1  # too little slack: nothing collected
        assert policy.idle(0.005) >= 0 and sum(policy.collections) == 1
        del junk
    finally:
        policy.stop()
    assert gc.isenabled() == was and gc.get_freeze_count() == 0
    r = policy.report()
    assert r["policy"] == "managed" and r["full_ms"] > 0 and r["frozen_full_ms"] >= 0
    assert sum(r["slack_collections"]) == 1


def test_python_policy_leaves_the_collector_alone_and_a_bad_one_is_named():
    policy = CollectorPolicy("python")
    policy.start()
    assert gc.get_freeze_count() == 0 and policy.idle(1.0) == -1
    policy.stop()
    assert policy.report()["full_ms"] > 0 and policy.report()["frozen_full_ms"] is None
    with pytest.raises(ValueError, match="gc policy 'off': expected one of managed, python"):
        CollectorPolicy("off")
