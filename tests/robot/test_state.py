"""StateEvaluator: Jacobian, drift J̇·v, M and h against finite differences and plain Pinocchio calls."""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from robot.model_files import build_pinocchio_model
from robot.state import StateEvaluator


def test_state_quantities_match_finite_differences() -> None:
    model, data, fid = build_pinocchio_model()
    ev = StateEvaluator(model, fid)
    rng = np.random.default_rng(2)
    eps = 1e-7
    for _ in range(10):
        q, v, a = rng.uniform(-1, 1, 3), rng.uniform(-2, 2, 3), rng.uniform(-5, 5, 3)
        s = ev(q, v, 0.01)
        # tip position derivative along v equals J·v = ṗ
        p_plus = ev(q + eps * v, v, 0.01).p
        np.testing.assert_allclose((p_plus - s.p) / eps, s.J @ v, atol=1e-5)
        np.testing.assert_allclose(s.p_dot, s.J @ v, atol=1e-12)
        # tip acceleration p̈ = J·a + J̇·v: differentiate ṗ along (v, a)
        pd_plus = ev(q + eps * v, v + eps * a, 0.01).p_dot
        np.testing.assert_allclose((pd_plus - s.p_dot) / eps, s.J @ a + s.drift, atol=1e-5)
        # symmetric M with armature, h = rnea(q, v, 0)
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        np.testing.assert_allclose(s.M, M, atol=1e-12)
        np.testing.assert_allclose(s.h, pin.nonLinearEffects(model, data, q, v), atol=1e-12)
        np.testing.assert_allclose(s.M @ a + s.h, pin.rnea(model, data, q, v, a), atol=1e-10)
