"""Holding: the brake toward the smoothed reference, and the last-resort commands."""

from __future__ import annotations

import numpy as np

from mpcshare.control.controller import SharedController
from mpcshare.control.holding import brake, fallback_joint_state, rest_command
from robot.superlimb import SuperLimbParams
from tests.mpcshare.control.controller_doubles import demos_and_bundle

P = SuperLimbParams()
Q0 = 0.5 * (P.lower + P.upper)


def test_the_brake_aims_at_the_measured_tip_before_any_reference_and_stops_there():
    _, bundle = demos_and_bundle(0)
    ctl = SharedController(bundle)
    faults: list = []
    res = brake(ctl.qp, ctl.keepout, ctl.state.smoother, ctl.tip, Q0, np.zeros(3), faults)
    assert faults == [] and np.allclose(res.v_next, 0.0, atol=1e-6)  # at rest at the tip: stays
    moving = brake(ctl.qp, ctl.keepout, ctl.state.smoother, ctl.tip, Q0, np.full(3, 0.5), faults)
    assert np.linalg.norm(moving.v_next) < np.linalg.norm(np.full(3, 0.5))  # slows down


def test_the_last_resort_state_and_command():
    qa, va = fallback_joint_state([0.1, 0.2], None, 3)
    assert np.isnan(qa).all() and np.isnan(va).all()
    qa, va = fallback_joint_state([0.1, 0.2, 0.3], [0, 0, 0], 3)
    assert qa.tolist() == [0.1, 0.2, 0.3] and va.tolist() == [0.0, 0.0, 0.0]
    c = rest_command(3, None, np.array([0.5, 0.5]), 1.0, "boom", 0.0)
    assert c.status == "internal_error" and c.reasons == ("boom",) and (c.tau == 0).all() and (c.q_cmd == 0).all()
