"""Per-input deadlines of `mpcshare run` on a fake clock: stale, then a latched protective stop."""

from __future__ import annotations

import math

import pytest

from mpcshare.runtime.watchdog import Deadline, Watchdog


def _dog(start=10.0):
    return Watchdog([Deadline("arm", 0.03, 0.1), Deadline("fork", 0.05, 0.5),
                     Deadline("wrench", 0.05, 0.5, optional=True)], start)


def test_fresh_inputs_are_neither_stale_nor_stopped():
    w = _dog()
    for t in (10.0, 10.01, 10.02):
        for n in ("arm", "fork", "wrench"):
            w.seen(n, t)
    s = w.check(10.04)
    assert s.stale == () and not s.stopped and s.ages["arm"] == pytest.approx(0.02)


def test_stale_after_the_deadline_then_a_latched_stop():
    w = _dog()
    w.seen("arm", 10.0)
    w.seen("fork", 10.0)
    assert w.check(10.03).stale == ()
    s = w.check(10.06)  # fork 0.06 s > 0.05; arm 0.06 > 0.03
    assert s.stale == ("arm", "fork") and not s.stopped
    w.seen("arm", 10.5)
    s = w.check(10.50)
    assert s.stale == ("fork",) and not s.stopped  # 0.50 s is not past 0.5
    s = w.check(10.51)
    assert s.stopped and s.stop_reason.startswith("fork: no message for 0.510 s, stop after 0.5 s")
    w.seen("fork", 10.52)
    assert w.check(10.53).stopped  # latched
    w.resume()  # the caller's decision: the stop ends, a new silence stops again
    w.seen("arm", 10.53)
    assert not w.check(10.54).stopped
    assert w.check(10.64).stop_reason.startswith("arm: no message for 0.110 s")


def test_before_the_first_message_ages_count_from_the_start_and_optional_inputs_never_stop():
    w = _dog(start=0.0)
    w.seen("fork", 0.0)
    s = w.check(0.2)
    assert s.stopped and "arm: no message for 0.200 s (none yet)" in s.stop_reason
    assert math.isnan(s.ages["wrench"]) and "wrench" not in s.stale
    w2 = _dog(start=0.0)
    w2.seen("wrench", 0.0)
    for t in (0.0, 0.02, 0.04, 0.06, 0.08):
        w2.seen("arm", t)
        w2.seen("fork", t)
    s = w2.check(0.09)
    assert s.stale == ("wrench",) and not s.stopped  # optional: stale, but no stop even past 0.5 s
    w2.seen("arm", 0.95)
    w2.seen("fork", 0.95)
    assert not w2.check(0.96).stopped


def test_bad_deadlines_and_names_are_refused():
    with pytest.raises(ValueError, match="deadline_s < stop_after_s"):
        Deadline("arm", 0.2, 0.1)
    with pytest.raises(ValueError, match="repeat"):
        Watchdog([Deadline("a", 0.1, 0.2), Deadline("a", 0.1, 0.2)], 0.0)
    with pytest.raises(KeyError, match="no input 'b'"):
        _dog().seen("b", 0.0)
