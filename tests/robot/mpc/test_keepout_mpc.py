"""The MPC holds a moving zone over its horizon (the hand's constant-velocity forecast)."""

from __future__ import annotations

import numpy as np
import pytest

from robot.keepout import Zone
from robot.mpc.keepout_mpc import KeepOutTipMPC
from robot.mpc.tip_mpc import TipMPC
from robot.qp import QPController
from robot.superlimb import SuperLimbParams

P = SuperLimbParams()


def _case():
    q, v = 0.5 * (P.lower + P.upper), np.zeros(3)
    tip = QPController.for_superlimb(P).tip_position(q)
    c, vz = tip + np.array([0.0, 0.08, 0.0]), np.array([0.0, -0.3, 0.0])
    return q, v, tip, Zone("hand", c, c, 0.045, vz, 0.15)


def test_the_plan_keeps_clear_of_where_the_hand_will_be():
    q, v, tip, zone = _case()
    mpc = KeepOutTipMPC(params=P, margin=0.02)
    mpc.set_zones([zone])
    ref = np.tile(tip, (mpc.horizon + 1, 1))  # hold still: the hand comes at 0.3 m/s
    for _ in range(5):
        r = mpc.solve(q, v, ref)
    centres = zone.a + np.arange(mpc.horizon + 1)[:, None] * mpc.dt * zone.velocity
    d = np.linalg.norm(r.tip_plan - centres, axis=1) - zone.radius
    plain = TipMPC(params=P).solve(q, v, ref)
    d_plain = np.linalg.norm(plain.tip_plan - centres, axis=1) - zone.radius
    print(f"end of horizon: {d[-1] * 1e3:.1f} mm with the zones, {d_plain[-1] * 1e3:.1f} mm without")
    assert r.ok
    assert d.min() >= 0.02 - 1e-3  # the linearisation's error is small at this curvature
    assert d_plain[-1] < 0.0  # without the zones the plan would stay in the hand's way


def test_zones_need_a_real_time_iteration_solver():
    with pytest.raises(ValueError, match="real-time iteration"):
        KeepOutTipMPC(params=P, solver="ipopt")
    mpc = KeepOutTipMPC(params=P, max_zones=1)
    _, _, _, zone = _case()
    with pytest.raises(ValueError, match="max_zones"):
        mpc.set_zones([zone, zone])
