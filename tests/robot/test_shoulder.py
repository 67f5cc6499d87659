import numpy as np
import pytest

from robot.shoulder import ShoulderMap

#: a task's layout (the eating task's): rows plate x, y, z; columns the roles
ROLES = ("shoulder_elevation", "shoulder_protraction", "shoulder_abduction")
LAYOUT = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])


def for_channels(names, **kwargs):
    return ShoulderMap.for_channels(names, ROLES, LAYOUT, **kwargs)


def test_deadband_and_inverse_round_trip():
    m = ShoulderMap(LAYOUT, gain=0.4, deadband_rad=0.02)
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
        ShoulderMap(LAYOUT, gain=0.0)
    with pytest.raises(ValueError, match="deadband"):
        ShoulderMap(LAYOUT, deadband_rad=-1.0)
    with pytest.raises(ValueError, match="matrix"):
        ShoulderMap(matrix=np.zeros((3, 3)))
    with pytest.raises(ValueError, match="shape"):
        ShoulderMap(LAYOUT).tip_velocity(np.zeros(2))


def test_for_channels_reads_any_number_of_angles_by_role_or_position():
    three = for_channels(["vol_0", "vol_1", "vol_2"], gain=0.4)
    np.testing.assert_array_equal(three.matrix, LAYOUT)  # by position: the default map
    np.testing.assert_array_equal(for_channels([]).matrix, LAYOUT)
    two = for_channels(["shoulder_abduction", "imu_temp", "shoulder_elevation"], deadband_rad=0.0)
    assert two.n_channels == 3
    # abduction → y, the unnamed channel commands nothing, elevation → z
    np.testing.assert_allclose(two.tip_velocity(np.array([0.2, 5.0, -0.1])), [0.0, 0.1, -0.05])
    # fewer angles than axes: the command nearest to the wish (least squares), x out of reach
    np.testing.assert_allclose(two.tip_velocity(two.angles_for(np.array([0.3, 0.1, -0.05]))), [0.0, 0.1, -0.05])
    one = for_channels(["angle"])  # one channel: elevation → z
    np.testing.assert_allclose(one.tip_velocity(np.array([0.11])), [0.0, 0.0, 0.05])
    with pytest.raises(ValueError, match="shape \\(1,\\)"):
        one.tip_velocity(np.zeros(3))
    with pytest.raises(ValueError, match="none named by its role"):
        for_channels(["a", "b", "c", "d"])
    with pytest.raises(ValueError, match="repeat"):
        for_channels(["a", "a"])
    with pytest.raises(ValueError, match="linearly independent"):
        ShoulderMap(matrix=np.array([[1.0, 2.0], [0.0, 0.0], [0.0, 0.0]]))
    with pytest.raises(ValueError, match="layout has shape"):
        ShoulderMap.for_channels([], ROLES[:2], LAYOUT)
