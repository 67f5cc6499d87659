"""Floor rows: a reference below the plane never takes the blade through it; a blade below climbs back."""

from __future__ import annotations

import numpy as np
import pytest

from robot.constraints import TorqueLimit
from robot.errors import ControllerConfigError
from robot.floor import FloorConfig, FloorLimit
from robot.limits import JointLimits
from robot.model_files import build_pinocchio_model
from robot.qp import QPController, QPStatus
from robot.superlimb import TOOL_FRAME, SuperLimbParams

P = SuperLimbParams()
HEEL = (-0.09, 0.0, 0.0)
Q0 = 0.5 * (P.lower + P.upper)


def _qp(with_floor: bool):
    model = build_pinocchio_model(P).model
    lim = JointLimits.from_superlimb(P)
    floor = FloorLimit(model, TOOL_FRAME, HEEL)
    rows = [TorqueLimit(lim)] + ([floor] if with_floor else [])
    return QPController(model, TOOL_FRAME, lim, constraints=rows), floor


def _run(qp, floor, target, q, steps=300):
    """Track ``target`` from rest at q, the arm integrated from the commands; (tip heights, heel heights, results)."""
    v = np.zeros(3)
    tips, heels, results = [], [], []
    for _ in range(steps):
        r = qp.step(q, v, target, np.zeros(3), np.zeros(3))
        q, v = r.q_next, r.v_next
        tip, heel = floor.blade.knife(q)
        tips.append(float(floor.normal @ tip.p) - floor.offset)
        heels.append(float(floor.normal @ heel.p) - floor.offset)
        results.append(r)
    return np.array(tips), np.array(heels), results


@pytest.mark.parametrize("normal", [(0.0, 0.0, 1.0), (0.1, -0.05, 1.0)])
def test_a_reference_below_the_floor_stops_the_blade_on_it(normal):
    qp, floor = _qp(True)
    tip0 = floor.blade.knife(Q0)[0].p
    n = np.asarray(normal) / np.linalg.norm(normal)
    floor.set_plane(normal, float(n @ tip0) - 0.08)  # the floor 8 cm below the start
    target = tip0 - 0.25 * n + np.array([0.05, 0.0, 0.0])  # 17 cm below the floor
    tips, heels, results = _run(qp, floor, target, Q0.copy())
    assert tips.min() >= -1e-3 and heels.min() >= -1e-3  # to the rows' linearisation (sub-mm)
    assert tips[-1] < 0.005  # it went down to the floor
    assert all(r.status is QPStatus.OK for r in results)
    free, _ = _qp(False)
    low, _, _ = _run(free, floor, target, Q0.copy())
    assert low.min() < -0.03  # without the rows the same command goes through (to the joint limits)


def test_a_blade_below_the_floor_climbs_back_gently():
    qp, floor = _qp(True)
    tip0 = floor.blade.knife(Q0)[0].p
    floor.set_plane((0.0, 0.0, 1.0), tip0[2] + 0.02)  # the start is 2 cm below the floor
    tips, _, results = _run(qp, floor, tip0 - np.array([0.0, 0.0, 0.1]), Q0.copy(), steps=150)
    assert tips[-1] >= -1e-4
    rise = np.diff(tips) / qp.dt
    assert rise.min() >= -1e-6  # never further down
    assert rise.max() <= FloorConfig().recover_speed + FloorConfig().brake_acceleration * qp.dt + 1e-6
    assert all(r.status is QPStatus.OK for r in results)


def test_no_plane_no_rows_and_bad_planes_refused():
    qp, floor = _qp(True)
    G, h = floor.compute_qp_inequalities(qp.evaluate(Q0, np.zeros(3)))
    assert not G.any() and (h >= 1e5).all()
    for normal, offset in [((0.0, 0.0, 0.0), 0.0), ((0.0, 0.0), 0.0), ((0.0, 0.0, 1.0), float("nan"))]:
        with pytest.raises(ControllerConfigError, match="floor plane"):
            floor.set_plane(normal, offset)
    with pytest.raises(ControllerConfigError, match="brake_acceleration"):
        FloorConfig(brake_acceleration=0.0)
