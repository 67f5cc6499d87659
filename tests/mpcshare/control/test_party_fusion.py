"""Fusion inside the QP: the parties' own reference chains (one step, the anti-windup, the bound) and ``qp_blend``
in a short closed run."""

from __future__ import annotations

import numpy as np
import pytest

from mpcshare.control.controller import SharedController
from mpcshare.control.party_fusion import PartyState, advance
from mpcshare.control.types import ControllerConfig
from mpcshare.control.workspace import bound_reference
from tests.mpcshare.control.controller_doubles import MOUNT, demos_and_bundle
from tests.mpcshare.control.test_controller import _run, _safe

CFG = ControllerConfig()
BOX = (np.array([-0.2, -0.2, 0.0]), np.array([0.2, 0.2, 0.2]))


def _bound(p, u, acc):
    return bound_reference(p, u, acc, BOX, np.array([0.0, 0.0, -1.0]), 0.0, 10.0)


def _step(state, alpha, p_hat, u_v, ok=True, offset=0.02):
    return advance(state, alpha, np.array([0.0, 0.0, 0.05]), p_hat, np.zeros(3), np.zeros(3), ok, u_v, 0.01, CFG,
                   _bound, offset)


def test_each_chain_follows_its_party_and_the_wearer_is_held_near_a_leading_robot():
    state = PartyState.new(0.01, CFG)
    p_hat = np.array([0.01, 0.0, 0.05])
    refs, faults = _step(state, 0.0, p_hat, np.array([0.0, 0.1, 0.0]))
    assert faults == [] and not refs.limited
    np.testing.assert_allclose(refs.u_r, CFG.reactive_gain * (p_hat - [0, 0, 0.05]))  # û_r from the robot's own ref
    np.testing.assert_allclose(refs.p_v, [0.0, 0.001, 0.05])  # the wearer's chain integrates û_v
    for _ in range(300):  # the robot leads; the wearer pushes sideways: held within d / α of the robot's reference
        refs, _ = _step(state, 1.0, p_hat, np.array([0.0, 0.1, 0.0]))
    np.testing.assert_allclose(refs.p_r, p_hat, atol=1e-6)
    assert refs.limited and np.linalg.norm(refs.p_v - refs.p_r) == pytest.approx(0.02)
    for _ in range(100):  # the wearer leads: no bound on the gap
        refs, _ = _step(state, 0.0, p_hat, np.array([0.0, 0.1, 0.0]))
    assert not refs.limited and np.linalg.norm(refs.p_v - refs.p_r) > 0.05
    held = state.p_r.copy()
    refs, _ = _step(state, 0.5, p_hat + 0.05, np.zeros(3), ok=False)  # no forecast: the robot's chain holds
    np.testing.assert_array_equal(refs.p_r, held)
    refs, faults = _step(state, 0.0, p_hat, np.array([0.0, 0.0, -100.0]))  # below the floor: bound, said
    assert refs.p_v[2] == 0.0 and faults and faults[0].startswith("wearer's reference: tip reference projected")


def test_qp_blend_closed_run_commands_within_limits_and_reports_the_blend():
    demos, bundle = demos_and_bundle(0)
    ctl = SharedController.from_bundle(bundle, strategy="qp_blend", use_mpc=False, base_pose=MOUNT)
    cmds = _run(ctl, demos.trials[-1], 800)
    for c in cmds:
        _safe(c)
    assert [c.status for c in cmds if c.status != "ok"] == []
    alpha = np.array([c.alpha for c in cmds])
    assert alpha.min() == 0.0 and alpha.max() == 1.0
    np.testing.assert_array_equal([c.beta for c in cmds], 1.0 - alpha)
    s = ctl.state.parties
    np.testing.assert_allclose(cmds[-1].tip_reference, alpha[-1] * s.p_r + (1 - alpha[-1]) * s.p_v, atol=1e-12)
    assert ctl.qp.tip_task.second_weight == 0.0  # the second reference is set for the step only
    with pytest.raises(ValueError, match="fuses the parties in the QP"):
        SharedController.from_bundle(bundle, strategy="qp_blend", use_mpc=True, base_pose=MOUNT)
