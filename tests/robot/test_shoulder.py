import numpy as np
import pytest

from robot.shoulder import ShoulderMap


def test_deadband_and_inverse_round_trip():
    m = ShoulderMap(gain=0.4, deadband_rad=0.02)
    np.testing.assert_array_equal(m.tip_velocity(np.array([0.015, -0.01, 0.0])), 0.0)
    # elevation → z, protraction → x, abduction → y
    np.testing.assert_allclose(m.tip_velocity(np.array([0.12, 0.0, 0.0])), [0, 0, 0.4 * 0.1])
    np.testing.assert_allclose(m.tip_velocity(np.array([0.0, -0.07, 0.0])), [-0.4 * 0.05, 0, 0])
    rng = np.random.default_rng(0)
    for _ in range(20):
        u = rng.normal(0, 0.05, 3)
        np.testing.assert_allclose(m.tip_velocity(m.angles_for(u)), u, atol=1e-12)


def test_invalid_settings_raise():
    with pytest.raises(ValueError, match="gain"):
        ShoulderMap(gain=0.0)
    with pytest.raises(ValueError, match="deadband"):
        ShoulderMap(deadband_rad=-1.0)
    with pytest.raises(ValueError, match="matrix"):
        ShoulderMap(matrix=np.zeros((3, 3)))
    with pytest.raises(ValueError, match="shape"):
        ShoulderMap().tip_velocity(np.zeros(2))
