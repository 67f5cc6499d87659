"""The sensing stage: the front end is an injection point (a recorded one replays the same step), and a
learned part that raises drops its output with a fault instead of stopping the loop."""

from __future__ import annotations

import numpy as np
import pytest

from mpcshare.control.controller import SharedController
from mpcshare.control.records import Sensed
from mpcshare.control.sensing import sense
from robot.superlimb import SuperLimbParams
from tests.mpcshare.control.controller_doubles import MOUNT, demos_and_bundle

P = SuperLimbParams()


class RecordingFrontEnd:
    """Steps the real front end and records its outputs (``replay``: gives them back instead)."""

    def __init__(self, inner) -> None:
        self.inner, self.outputs, self.replay = inner, [], False
        self._k = 0

    def reset(self) -> None:
        self.inner.reset()
        self._k = 0

    def step(self, t, obs):
        if self.replay:
            self._k += 1
            return self.outputs[self._k - 1]
        out = self.inner.step(t, obs)
        self.outputs.append(out)
        return out


def _run(ctl, trial, n):
    q, v = 0.5 * (P.lower + P.upper), np.zeros(3)
    cmds = []
    for k in range(n):
        c = ctl.step(trial.t[k], trial.obs[k], trial.voluntary[k], q, v)
        q, v = c.q_cmd, c.v_cmd
        cmds.append(c)
    return cmds


def test_a_recorded_front_end_replays_the_same_steps():
    demos, bundle = demos_and_bundle(0)
    trial = demos.trials[1]
    plain = _run(SharedController(bundle, strategy="gate", base_pose=MOUNT), trial, 150)
    recorder = RecordingFrontEnd(SharedController(bundle, base_pose=MOUNT).frontend)
    ctl = SharedController(bundle, strategy="gate", frontend=recorder, base_pose=MOUNT)  # any step(t, obs) / reset()
    recorded = _run(ctl, trial, 150)
    recorder.replay = True
    ctl.reset()
    replayed = _run(ctl, trial, 150)
    for a, b, c in zip(plain, recorded, replayed):
        np.testing.assert_array_equal(a.tau, b.tau)
        np.testing.assert_array_equal(a.tau, c.tau)
        assert a.status == c.status and a.alpha == c.alpha
    assert sum(c.status == "ok" for c in plain) > 100  # tracking, not holding
    with pytest.raises(TypeError, match="frontend must have step"):
        SharedController(bundle, frontend=object())


def test_sense_reports_a_bad_sample_and_holds_before_any_measurement():
    demos, bundle = demos_and_bundle(0)
    ctl = SharedController(bundle, base_pose=MOUNT)
    faults: list = []
    assert sense(0.0, None, faults, frontend=ctl.frontend, d_o=ctl.layout.d_o, stale_after_s=0.5) is None
    assert [f[0] for f in faults] == ["missing_observation", "no_observation"]
    faults.clear()
    fe = sense(0.01, demos.trials[0].obs[0][:2], faults, frontend=ctl.frontend, d_o=ctl.layout.d_o,
               stale_after_s=0.5)
    assert fe is None and faults[0][0] == "invalid_observation_shape"


def test_the_sensed_record_carries_the_forecast_the_arbitration_reads():
    demos, bundle = demos_and_bundle(0)
    ctl, trial = SharedController(bundle, strategy="reactive", base_pose=MOUNT), demos.trials[1]
    _run(ctl, trial, 60)
    q = 0.5 * (P.lower + P.upper)
    sensed = ctl._sense(float(trial.t[60]), 0.01, q, np.zeros(3), trial.obs[60], [], {})
    assert isinstance(sensed, Sensed) and sensed.t_aim == float(trial.t[60]) + ctl.lead_s
    assert sensed.forecast_ok and np.allclose(sensed.p_hat, ctl.forecast.at(sensed.t_aim)[0])
    assert sensed.tick is ctl.state.tick and sensed.pose is ctl.state.pose
