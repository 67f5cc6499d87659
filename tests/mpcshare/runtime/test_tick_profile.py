"""The ticks' profile of `mpcshare run`: long periods named by their cause; garbage collections recorded."""

from __future__ import annotations

import gc

import numpy as np

from mpcshare.runtime.tick_profile import TickProfile

T = 0.01


def _ticks(profile: TickProfile, n: int, step=None, arm_late=None, no_arm=None) -> None:
    """n ticks 10 ms apart with 1 ms steps; ``step``: {tick: extra step [s]}, ``arm_late``: {tick: how late its
    joint state was stamped [s]}, ``no_arm``: ticks without a new joint state (the window waited out)."""
    sent, arm = 100.0, 5000.0
    for i in range(n):
        extra = (step or {}).get(i, 0.0)
        late = (arm_late or {}).get(i, 0.0)
        waited = i in (no_arm or ())
        arm_i = arm if waited else arm + T + late
        sent += T + extra + late + (0.005 if waited else 0.0)
        profile.tick(arm_i + 2e-4 + (0.005 if waited else 0.0), arm_i, sent, (1e-4, 1e-3 + extra, 3e-4, 0.0),
                     late=extra > 0.015)
        arm = arm_i


def test_each_long_period_is_named_by_its_largest_excess():
    p = TickProfile(T)
    _ticks(p, 300, step={50: 0.006, 60: 0.02}, arm_late={100: 0.004}, no_arm={200})
    p.gc[0] = (2, p.sent[149] + 1e-4, 0.007)  # a full collection between ticks 149 and 150
    p.n_gc = 1
    p.sent[150:] += 0.007
    r = p.report()
    assert r["ticks"] == 300 and r["causes"] == {"step": 2, "input late": 2, "gc gen2": 1}, r["causes"]
    assert r["late_ticks"] == {"step": 1}
    assert r["period_ms"]["max"] > 30.0 and r["worst"][0]["tick"] == 60 and r["worst"][0]["cause"] == "step"
    assert r["gc"]["gen2"] == {"count": 1, "max_ms": 7.0}
    assert abs(r["phases_ms"]["step"]["median"] - 1.0) < 1e-9


def test_quiet_ticks_have_no_long_period_and_real_collections_are_recorded():
    p = TickProfile(T, capacity=50)
    _ticks(p, 60)
    p.install()
    try:
        gc.collect()
    finally:
        p.uninstall()
    r = p.report()
    assert r["causes"] == {} and r["dropped"] == 10 and r["ticks"] == 50
    assert r["gc"]["gen2"]["count"] >= 1 and r["jitter_p99_ms"] < 1e-6
    assert np.isfinite(p.gc[:p.n_gc, 2]).all()
