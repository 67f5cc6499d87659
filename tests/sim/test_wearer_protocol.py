"""A new wearer behaviour is one class: the closed loop runs any object of the wearer protocol."""

import numpy as np
import pytest

from sim.closed_loop import run_episode
from sim.demonstrator import generate_demonstrations
from sim.errors import SimError, WearerError
from sim.metrics import episode_metrics
from sim.task import EATING
from sim.wearer_presets import DEFAULT_WEARER, wearer_preset
from sim.wearer_protocol import Wearer
from tests.sim.controllers import IdleController, VoluntaryController


class ExactWearer:
    """No delay, no noise, no dead band: commands the intent's velocity plus a P correction of the tip error.

    θ_k = angles_for(ṗ*_k + K·(p*_k − p_k)) through the shoulder map (its dead zone inverted).
    """

    def __init__(self, intent: np.ndarray, rate_hz: float, *, seed: int, gain_per_s: float = 5.0) -> None:
        self.intent = np.asarray(intent, dtype=float)
        self.velocity = np.gradient(self.intent, 1.0 / rate_hz, axis=0)
        self.gain, self.map = gain_per_s, EATING.shoulder_map()
        self.resets = self.steps = 0

    def reset(self) -> None:
        self.resets += 1
        self.steps = 0

    def step(self, k: int, tip: np.ndarray, alpha_cue: float | None = None) -> np.ndarray:
        self.steps += 1
        return self.map.angles_for(self.velocity[k] + self.gain * (self.intent[k] - tip))

    def info(self) -> dict:
        return {"shoulder_gain": self.map.gain, "shoulder_deadband_rad": self.map.deadband_rad, "wearer": "exact"}


@pytest.fixture(scope="module")
def trial():
    return generate_demonstrations(n_subjects=1, minutes=0.5, seed=11).trials[0]


def test_a_wearer_class_is_its_own_factory_and_drives_the_loop(trial):
    ep = run_episode(VoluntaryController(), trial, duration_s=3.0, seed=1, wearer=ExactWearer)
    assert ep.info["wearer"] == "exact" and ep.info["limit_violations"] == 0
    np.testing.assert_allclose(ep.tip_intent, trial.act[:300, :3])  # its own intent: the raw knife, not smoothed
    rms = episode_metrics(ep)["tracking_rmse_m"]
    print(f"voluntary tracking RMS beside the exact wearer: {rms * 1e3:.1f} mm")
    assert rms < 0.005  # no delay, no dead band: the shoulder's command reaches the knife
    # the loop gave the controller exactly what the class returned (its behaviour, not the default wearer's)
    u = np.array([EATING.shoulder_map().tip_velocity(th) for th in ep.voluntary[1:]])
    np.testing.assert_allclose(np.diff(ep.tip_reference, axis=0), u * 0.01, atol=1e-12)


def test_a_wearer_instance_is_used_as_it_is_and_reset_once(trial):
    person = ExactWearer(trial.act[:, :3], 100.0, seed=0)
    assert isinstance(person, Wearer)
    ep = run_episode(IdleController(), trial, duration_s=0.5, wearer=person)
    assert person.resets == 1 and person.steps == 50
    np.testing.assert_allclose(ep.voluntary[0], person.map.angles_for(person.velocity[0] + 5.0 * (
        person.intent[0] - ep.tip[0])))


def test_configs_and_presets_are_factories_of_the_simulated_wearer(trial):
    a = run_episode(IdleController(), trial, duration_s=0.5, seed=2)
    b = run_episode(IdleController(), trial, duration_s=0.5, seed=2, wearer=DEFAULT_WEARER)
    np.testing.assert_array_equal(a.voluntary, b.voluntary)
    assert a.info["wearer_preset"] == "hemiparetic_mild"
    c = run_episode(IdleController(), trial, duration_s=0.5, seed=2, wearer=wearer_preset("unimpaired"))
    assert c.info["wearer_preset"] == "unimpaired" and not np.array_equal(a.voluntary, c.voluntary)


class _NoInfo:
    intent = np.zeros((10, 3))

    def reset(self) -> None: ...

    def step(self, k, tip, alpha_cue=None):
        return np.zeros(3)

    def info(self):
        return {"wearer": "lacks the shoulder map"}


def test_a_wearer_that_breaks_the_protocol_is_refused_with_the_reason(trial):
    with pytest.raises(WearerError, match="factory"):
        run_episode(IdleController(), trial, duration_s=0.1, wearer=object())
    with pytest.raises(WearerError, match="shoulder_gain"):
        run_episode(IdleController(), trial, duration_s=0.05, wearer=_NoInfo())
    with pytest.raises(WearerError, match=r"\(≥ 20, 3\)"):
        run_episode(IdleController(), trial, duration_s=0.2, wearer=_NoInfo())
    with pytest.raises(WearerError, match="lacks"):
        run_episode(IdleController(), trial, duration_s=0.1, wearer=lambda intent, rate_hz, seed: "not a wearer")
    assert issubclass(WearerError, SimError) and issubclass(WearerError, TypeError)
