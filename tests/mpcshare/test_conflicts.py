"""Conflict scenarios: each transform does what its name says, on the generator's data."""

from __future__ import annotations

import numpy as np
import pytest

from mpcshare.conflicts import SCENARIOS, SWEEP_SPEED, Scenario
from sim.task import EATING
from tests.mpcshare.control.controller_doubles import demos_and_bundle


@pytest.fixture(scope="module")
def data():
    return demos_and_bundle(0)


def _scenario(name, demos):
    return Scenario(name, demos.obs_names, demos.act_names)


def test_push_turns_the_intent_into_the_hand(data):
    demos, _ = data
    trial = demos.trials[0]
    sc = _scenario("push", demos)
    st = sc.apply(trial, duration_s=30.0)
    t = trial.t - trial.t[0]
    k = int(np.searchsorted(t, 0.2 * 30.0 + 3.0))  # the middle of the 6 s window
    hand = sc.hands(st.fork_truth[k:k + 1])[0]
    assert np.allclose(st.trial.act[k, sc.tip_cols], hand, atol=1e-12)
    assert np.array_equal(st.trial.act[:100], trial.act[:100])  # untouched before the window
    assert st.trial is not trial and np.array_equal(trial.act, demos.trials[0].act)


def test_sweep_brings_the_hand_to_the_knife_at_0_4_m_s(data):
    demos, _ = data
    trial = demos.trials[0]
    sc = _scenario("sweep", demos)
    st = sc.apply(trial, duration_s=30.0)
    hands = sc.hands(st.fork_truth)
    base = sc.hands(trial.obs[:, sc.fork_cols])
    speed = np.linalg.norm(np.diff(hands - base, axis=0), axis=1) / 0.01
    assert speed.max() <= SWEEP_SPEED + 1e-6 and speed.max() > 0.9 * SWEEP_SPEED
    gap = np.linalg.norm(hands - trial.act[:, sc.tip_cols], axis=1)
    assert gap.min() < EATING.body.hand_radius  # the sweep runs into where the knife should be
    assert np.array_equal(st.trial.obs[:, sc.fork_cols], st.fork_truth)  # the controller sees it


def test_the_hand_and_the_head_are_the_tasks(data):
    import dataclasses

    from sim.scene import SceneConfig

    demos, _ = data
    big = dataclasses.replace(EATING.body, hand_radius=0.1, head_center=(0.0, 0.1, 0.5))
    task = type("BigHands", (), {"body": big})()
    sc = Scenario("sweep", demos.obs_names, demos.act_names, task=task)
    assert sc.body is big and _scenario("sweep", demos).body is EATING.body
    assert np.allclose(sc.head_plate, np.asarray(big.head_center) - SceneConfig().plate_position)


def test_marker_lost_hides_the_fork_for_a_second(data):
    demos, _ = data
    sc = _scenario("marker_lost", demos)
    st = sc.apply(demos.trials[0], duration_s=30.0)
    lost = ~np.isfinite(st.trial.obs[:, sc.fork_cols]).all(axis=1)
    assert lost.sum() == 100 and np.isfinite(st.fork_truth).all()


def test_predictor_fault_points_into_the_hand_inside_its_window(data):
    demos, bundle = data
    sc = _scenario("predictor_fault", demos)
    st = sc.apply(demos.trials[0], duration_s=30.0)
    faulty = sc.wrap_bundle(bundle, st, demos.act_names)
    assert faulty is not bundle and bundle.predictor is not faulty.predictor
    stream, clean = faulty.predictor.make_stream(), bundle.predictor.make_stream()
    x = np.zeros(len(bundle.obs_names) + 3)
    pre = bundle.preprocessor.act
    for n in range(int(30 * bundle.model_hz)):
        u, u0 = stream.step(x), clean.step(x)
        t = n / bundle.model_hz
        if st.fault_window[0] <= t < st.fault_window[1]:
            tip = u[sc.tip_cols] * pre.scale_[sc.tip_cols] + pre.mean_[sc.tip_cols]
            hand = sc.hands(st.fork_truth[int(round(t * 100)):int(round(t * 100)) + 1])[0]
            assert np.allclose(tip, hand)
        else:
            assert np.allclose(u, u0)


def test_unknown_scenario_names_the_choices(data):
    demos, _ = data
    with pytest.raises(ValueError, match="valid choices"):
        _scenario("earthquake", demos)
    assert set(SCENARIOS) == {"push", "sweep", "face", "marker_lost", "predictor_fault"}
