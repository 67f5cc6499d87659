"""The SuperLimb's closed-form knife-tip kinematics (robot.superlimb.kinematics) against Pinocchio."""

import numpy as np
import pinocchio as pin
import pytest

from robot.kinematics import ArmGeometry, forward_tip, inverse_tip, nearest_reachable_q, reachable
from robot.model_files import build_pinocchio_model
from robot.superlimb import SuperLimbParams


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
