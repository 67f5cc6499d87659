"""Closed-form knife-tip kinematics against Pinocchio; reachability of the demonstrations in the scene."""

import numpy as np
import pinocchio as pin
import pytest

from robot.kinematics import (
    ArmGeometry,
    forward_tip,
    inverse_tip,
    nearest_reachable_q,
    reachable,
)
from robot.model_files import build_pinocchio_model
from robot.superlimb import SuperLimbParams
from sim.demonstrator import ACT_NAMES, GeneratorConfig, generate_demonstrations
from sim.scene import SceneConfig


def test_forward_equals_pinocchio_and_inverse_recovers_tips():
    params = SuperLimbParams(mount_rpy=(0.05, -0.1, 0.3))  # a tilted mount: the rotation is used too
    g = ArmGeometry.from_params(params)
    model, data, fid = build_pinocchio_model(params)
    rng = np.random.default_rng(0)
    Q = rng.uniform(g.lower, g.upper, (300, 3))
    for q in Q[:50]:
        pin.framesForwardKinematics(model, data, q)
        np.testing.assert_allclose(forward_tip(g, q), data.oMf[fid].translation, atol=1e-12)
    P = forward_tip(g, Q)
    q_all, ok = inverse_tip(g, P)
    assert ok.any(axis=1).all()  # every tip of an in-limit configuration is found
    for i in range(len(P)):
        for q in q_all[i][ok[i]]:
            np.testing.assert_allclose(forward_tip(g, q), P[i], atol=1e-10)
            assert np.all(q >= g.lower) and np.all(q <= g.upper)


def test_unreachable_tips_and_nearest_configuration():
    g = ArmGeometry.from_params()
    far = g.mount_p + np.array([2.0, 0.0, 0.0])
    assert not reachable(g, far[None])[0]
    q = nearest_reachable_q(g, far)
    assert np.all(q >= g.lower) and np.all(q <= g.upper)
    assert np.linalg.norm(forward_tip(g, q) - far) > 1.0  # best effort, still far
    tip = forward_tip(g, np.array([0.2, 0.6, 0.9]))
    np.testing.assert_allclose(forward_tip(g, nearest_reachable_q(g, tip)), tip, atol=1e-10)


def test_layout_outside_the_closed_form_is_refused():
    p = SuperLimbParams().with_joint("elbow", origin_xyz=(0.26, 0.02, 0.0))
    with pytest.raises(ValueError, match="closed-form"):
        ArmGeometry.from_params(p)


@pytest.mark.parametrize("seed,single", [(0, False), (7, False), (2, True)])
def test_demonstrated_knife_tips_reachable_and_on_or_above_the_plate(seed, single):
    demos = generate_demonstrations(n_subjects=2, minutes=3, seed=seed, config=GeneratorConfig(single_regime=single))
    cols = [ACT_NAMES.index(c) for c in ("knife_x", "knife_y", "knife_z")]
    tips = np.concatenate([tr.act[:, cols] for tr in demos])
    # Tolerance below the surface: the generator adds sensor noise of σ = 0.01·0.05 m = 0.5 mm
    # to the recorded knife (the physical tip rests on z = 0); 5σ = 2.5 mm is exceeded by
    # Gaussian noise with probability 3e-7 per sample, so a recorded z < −2.5 mm is a real fault.
    assert tips[:, 2].min() >= -2.5e-3
    sc = SceneConfig()
    g = ArmGeometry.from_params(sc.params)
    in_torso = tips[::5] + np.array(sc.plate_position)  # the plate frame at the torso's rest pose
    assert reachable(g, in_torso).mean() >= 0.99
    # and with the torso swayed by its largest excursion in any direction
    sway = np.abs(sc.breathing_amplitude_m) + np.abs(sc.posture_amplitude_m)
    for axis in range(3):
        for sign in (1.0, -1.0):
            shift = np.zeros(3)
            shift[axis] = sign * sway[axis]
            assert reachable(g, in_torso - shift).mean() >= 0.99
