"""The control-rate forecast in the loop: its online inputs equal the training's offline ones, the
MPC preview holds where the forecast has no skill, and the 10 Hz path is kept when asked for."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from learning.preprocessing.resample import causal_downsample
from mpcshare.control import ControllerConfig, SharedController
from mpcshare.control.preview import PreviewPlan
from mpcshare.training import train_bundle
from mpcshare.training.config import TrainConfig
from mpcshare.training.fast import TIP, trial_designs
from sim.demonstrator import GeneratorConfig, generate_demonstrations
from tests.mpcshare.control.controller_doubles import MOUNT

SMALL = TrainConfig(n_modes=3, hmm_restarts=1, max_epochs=3, patience=2, gate_max_samples=200, seed=0)


@pytest.fixture(scope="module")
def setup():
    demos = generate_demonstrations(2, 1.5, seed=3, config=GeneratorConfig(trial_minutes=0.5))
    return demos, train_bundle(demos, SMALL, progress=False)


def _online(bundle, trial, n: int, config: ControllerConfig | None = None):
    """(φ per step, forecasts per step, commands) of the controller streaming ``trial``."""
    ctl = SharedController.from_bundle(bundle, strategy="reactive", config=config, base_pose=MOUNT)
    phis, outs = [], []
    inputs_step, fast_step = ctl.fast.inputs.step, ctl.fast.step

    def probe_inputs(*a):
        phis.append(inputs_step(*a))
        return phis[-1]

    def probe_fast(*a):
        outs.append(fast_step(*a))
        return outs[-1]

    ctl.fast.inputs.step, ctl.fast.step = probe_inputs, probe_fast
    q, v = np.array([0.0, 0.5, 1.0]), np.zeros(3)
    cmds = [ctl.step(trial.t[k], trial.obs[k], trial.voluntary[k], q, v) for k in range(n)]
    return np.array(phis), outs, cmds


def test_online_inputs_equal_the_offline_rows(setup):
    demos, bundle = setup
    trial = demos.trials[bundle.heldout_trials[0]]
    one = demos.with_trials([trial])
    std = bundle.preprocessor.standardize(causal_downsample(one, bundle.model_hz, zero_phase_act=True))
    obs = std.trials[0].obs
    post = bundle.modes.filter_proba(obs, [len(obs)])
    tip = [list(bundle.act_names).index(c) for c in TIP]
    (phi, _, _), = trial_designs(one, [np.hstack([obs, post])], [post], bundle.predictor, bundle.preprocessor,
                                 tip, bundle.model_hz, tuple(bundle.fast.lags))
    n = 250
    online, outs, cmds = _online(bundle, trial, n)
    assert all(c.status == "ok" for c in cmds[1:]), {c.status for c in cmds}
    assert online.shape == (n, phi.shape[1])
    np.testing.assert_allclose(online, phi[:n], rtol=0, atol=1e-9)  # the LSTM: NumPy stream vs torch float64
    assert all(o is not None and np.all(np.isfinite(o)) for o in outs)


def test_the_preview_holds_where_the_forecast_has_no_skill(setup):
    demos, bundle = setup
    trial = demos.trials[bundle.heldout_trials[0]]
    ctl = SharedController.from_bundle(bundle, strategy="reactive", base_pose=MOUNT)
    q, v = np.array([0.0, 0.5, 1.0]), np.zeros(3)
    for k in range(120):
        ctl.step(trial.t[k], trial.obs[k], trial.voluntary[k], q, v)
    sm = type("S", (), {"position": np.zeros(3), "velocity": np.zeros(3)})()
    t = float(trial.t[119])  # the preview the MPC would get after the last step, the robot leading
    sensed = SimpleNamespace(t=t, pose=ctl.state.pose, tick=ctl.state.tick)
    arb = SimpleNamespace(plan=PreviewPlan(1.0, 0.5, np.zeros(3), t + ctl.lead_s))
    ctl.fast.skill = np.full_like(bundle.fast.preview_skill_, -0.1)
    held = ctl.mpc_preview(sm, 20, sensed, arb)
    assert np.allclose(held, held[0]), "no skill at any horizon: the preview is a hold"
    ctl.fast.skill = np.full_like(bundle.fast.preview_skill_, 0.2)
    moving = ctl.mpc_preview(sm, 20, sensed, arb)
    assert np.ptp(moving, axis=0).max() > 1e-5, "skill everywhere: the preview follows the forecast"
    assert ctl.fast.preview_until(1.0, np.array([1.0, 0.0, 0.0])) == pytest.approx(1.0 + 0.1 * (len(
        bundle.fast.preview_skill_[0]) - 1))


def test_the_10hz_path_is_kept_when_asked_or_for_an_old_bundle(setup):
    demos, bundle = setup
    assert SharedController.from_bundle(bundle, config=ControllerConfig(fast_forecast=False)).fast is None
    import dataclasses
    old = dataclasses.replace(bundle, fast=None, format_version=1)
    ctl = SharedController.from_bundle(old, base_pose=MOUNT)
    assert ctl.fast is None and ctl.lead_s == ControllerConfig().forecast_lead_s
    trial = demos.trials[0]
    cmd = ctl.step(trial.t[0], trial.obs[0], trial.voluntary[0], np.array([0.0, 0.5, 1.0]), np.zeros(3))
    assert "fast" not in cmd.timings


def test_a_fast_forecaster_that_does_not_fit_is_refused(setup):
    import copy
    _, bundle = setup
    bad = copy.copy(bundle)
    bad.fast = copy.deepcopy(bundle.fast)
    bad.fast.n_features_in_ += 1
    with pytest.raises(ValueError, match="does not fit"):
        SharedController.from_bundle(bad)
