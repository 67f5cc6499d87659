"""The keep-out's zones given back from a recording: the same zones, faults and state, else run live."""

from __future__ import annotations

import numpy as np

from mpcshare.control.keepout import KeepOut, KeepOutSettings
from mpcshare.evaluation.keepout_replay import RecordedKeepOut
from robot.keepout import KeepOutLimit
from robot.superlimb import superlimb_description
from sim.demonstrator import OBS_NAMES
from sim.task import EATING


def _keepout() -> KeepOut:
    arm, settings = superlimb_description(), KeepOutSettings(body=EATING.body)
    ko = KeepOut(settings, KeepOutLimit(arm.model, arm.tip_frame, settings.heel_offset, settings.limit))
    ko.bind(OBS_NAMES)
    return ko


def _calls(n: int, base_shift: float = 0.0) -> list[tuple]:
    """``update`` arguments of n steps: a moving fork, lost (NaN) on steps 4–7 and repeated on step 9."""
    rng = np.random.default_rng(0)
    out = []
    for k in range(n):
        obs = np.zeros(len(OBS_NAMES))
        obs[:3] = (0.05 + 0.002 * k, -0.1, 0.08)
        if 4 <= k <= 7:
            obs[:] = np.nan
        base = np.eye(4)
        base[:3, 3] = (-0.4, 0.1, -0.2 + base_shift)
        out.append((0.01 * k, obs, rng.normal(size=len(OBS_NAMES)) * 0.1, k == 9, base))
    return out


def _run(ko, calls) -> list[tuple]:
    ko.reset()
    seen = []
    for t, obs, vel, repeated, base in calls:
        faults: list = []
        ko.update(t, obs, vel, repeated, base, faults)
        z = ko.limit.zones
        seen.append(([(x.name, x.a.tobytes(), x.b.tobytes(), x.velocity.tobytes(), x.uncertainty,
                       x.uncertainty_rate) for x in z], faults, ko.age_s, ko._t_seen,
                     None if ko._pose is None else ko._pose.tobytes()))
    return seen


def test_the_zones_given_back_are_the_live_ones_and_other_inputs_run_live(monkeypatch):
    calls, live_calls = _calls(12), []
    live = _run(_keepout(), calls)
    assert any(f for _, f, *_ in live), "the lost marker gives stale-zone faults"
    log: list = []
    recorded = _run(RecordedKeepOut(_keepout(), log, replaying=False), calls)
    assert recorded == live and len(log) == 12
    real = KeepOut.update
    monkeypatch.setattr(KeepOut, "update", lambda self, *a: (live_calls.append(1), real(self, *a))[1])
    replay = RecordedKeepOut(_keepout(), log, replaying=True)
    assert _run(replay, calls) == live and not live_calls  # all given back
    moved = _calls(12, base_shift=1e-3)  # another base pose (another seed's sway): every call runs live
    assert _run(replay, moved) == _run(_keepout(), moved) and len(live_calls) == 24
    assert _run(replay, calls) == live and len(live_calls) == 24  # reset: from the log's start again
