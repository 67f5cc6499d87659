"""The simulated wearer: reaction delay, deadband, bandwidth, direction of the correction."""

import numpy as np
import pytest

from robot.shoulder import ShoulderMap
from sim.wearer import SimulatedWearer, WearerConfig

QUIET = {"noise_rad": 0.0, "noise_signal_dependent": 0.0, "feedforward": False}


def _still_intent(T=200):
    return np.zeros((T, 3))


def test_reaction_delay_then_correction_toward_the_intent():
    w = SimulatedWearer(_still_intent(), 100.0, WearerConfig(**QUIET))
    tip = np.array([0.0, 0.0, -0.05])  # 5 cm below the intent, appearing at step 10
    out = [w.step(k, np.zeros(3) if k < 10 else tip) for k in range(80)]
    out = np.array(out)
    assert np.all(out[:30] == 0.0)  # steps 10..29: the error is not perceived yet (0.2 s = 20 steps)
    assert np.any(out[31] != 0.0)
    u = ShoulderMap().tip_velocity(out[-1])
    assert u[2] > 0 and abs(u[0]) < 1e-12 and abs(u[1]) < 1e-12  # commands the tip up, toward the intent


def test_errors_inside_the_deadband_are_tolerated():
    w = SimulatedWearer(_still_intent(), 100.0, WearerConfig(**QUIET))
    out = np.array([w.step(k, np.array([0.006, -0.005, 0.0])) for k in range(100)])  # 7.8 mm < 10 mm
    assert np.all(out == 0.0)


def test_limited_bandwidth_smooths_a_step():
    cfg = WearerConfig(**QUIET, reaction_delay_s=0.0, bandwidth_hz=2.0)
    w = SimulatedWearer(_still_intent(), 100.0, cfg)
    out = np.array([w.step(k, np.array([0.0, 0.0, -0.05])) for k in range(100)])
    target = ShoulderMap().angles_for(np.array([0.0, 0.0, 0.1]))  # K·e = 2/s · 5 cm
    z = out[:, 0]  # elevation drives plate z
    assert np.all(np.diff(z) >= -1e-15)  # critically damped: no overshoot, monotone
    assert z[5] < 0.5 * target[0]  # slow start: a 2 Hz second-order stage
    assert abs(z[-1] - target[0]) < 0.01 * abs(target[0])


def test_noise_is_seeded_and_signal_dependent():
    cfg = WearerConfig(reaction_delay_s=0.0)
    a = SimulatedWearer(_still_intent(), 100.0, cfg, seed=3)
    b = SimulatedWearer(_still_intent(), 100.0, cfg, seed=3)
    xa = np.array([a.step(k, np.zeros(3)) for k in range(100)])
    xb = np.array([b.step(k, np.zeros(3)) for k in range(100)])
    np.testing.assert_array_equal(xa, xb)
    assert 0.0005 < xa.std() < 0.005  # tremor-level noise at rest, inside the shoulder map's dead zone
    assert np.all(ShoulderMap().tip_velocity(xa[50]) == 0.0) or np.abs(xa).max() > 0.01


def test_feedforward_follows_a_moving_intent_when_engaged():
    T = 300
    intent = np.zeros((T, 3))
    intent[:, 0] = 0.1 * np.arange(T) / 100.0  # 0.1 m/s along x
    w = SimulatedWearer(intent, 100.0, WearerConfig(noise_rad=0.0, noise_signal_dependent=0.0,
                                                    reaction_delay_s=0.0))
    tip = np.array([-0.05, 0.0, 0.0])  # 5 cm behind: fully engaged
    out = [w.step(k, tip) for k in range(31)]
    assert w.engagement == 1.0
    assert w.desired_velocity[0] == pytest.approx(0.1 + 2.0 * (intent[30, 0] + 0.05), rel=1e-3)  # ṗ* + K·e
    assert ShoulderMap().tip_velocity(out[-1])[0] > 0.05
    for k in range(31, 150):
        w.step(k, tip)
    assert np.linalg.norm(w.desired_velocity) == pytest.approx(0.3)  # capped at max_speed_mps


@pytest.mark.parametrize("bad", [{"reaction_delay_s": -0.1}, {"bandwidth_hz": 0.0}, {"deadband_m": float("nan")}])
def test_bad_settings_are_refused(bad):
    with pytest.raises(ValueError, match=next(iter(bad))):
        WearerConfig(**bad)


def test_bad_intent_is_refused():
    with pytest.raises(ValueError, match="non-finite"):
        SimulatedWearer(np.full((10, 3), np.nan), 100.0)
    with pytest.raises(ValueError, match=r"\(T, 3\)"):
        SimulatedWearer(np.zeros((10, 2)), 100.0)
