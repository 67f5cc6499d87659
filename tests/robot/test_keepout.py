"""Keep-out rows: segment distances against brute force, the blade's kinematics, zones held in a QP loop."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from robot.constraints import TorqueLimit
from robot.keepout import (
    KeepOutConfig,
    KeepOutLimit,
    Zone,
    closest_segment_points,
    retreat,
    segment_zone_clearance,
    segment_zone_clearances,
)
from robot.limits import JointLimits
from robot.model_files import build_pinocchio_model
from robot.qp import QPController
from robot.superlimb import TOOL_FRAME, SuperLimbParams

P = SuperLimbParams()
HEEL = (-0.09, 0.0, 0.0)


def _brute(p0, p1, q0, q1, n=400):
    s = np.linspace(0.0, 1.0, n)
    a = p0 + s[:, None] * (p1 - p0)
    b = q0 + s[:, None] * (q1 - q0)
    return float(np.sqrt(((a[:, None, :] - b[None, :, :]) ** 2).sum(-1)).min())


def test_batched_clearances_are_the_scalar_ones_row_by_row():
    rng = np.random.default_rng(1)
    tip, heel, a, b = rng.normal(size=(4, 60, 3))
    heel[:10] = tip[:10]  # a point blade
    b[5:20] = a[5:20]  # a sphere (both degenerate on rows 5-9)
    heel[20:25] = tip[20:25] + 0.1 * (b[20:25] - a[20:25])  # parallel segments
    a[25], b[25] = tip[25], heel[25]  # the blade on the zone's axis: the fallback normal
    tip[30] = np.nan  # a lost sample stays NaN
    dist, s, normal = segment_zone_clearances(tip, heel, a, b, 0.05)
    assert np.isnan(dist[30]) and np.isnan(normal[30]).all()
    for k in (k for k in range(60) if k != 30):
        one = segment_zone_clearance(tip[k], heel[k], Zone("z", a[k], b[k], 0.05, np.zeros(3), 0.1))
        assert dist[k] == one.distance and s[k] == one.s and np.array_equal(normal[k], one.normal), k


def test_the_closest_points_are_numpys_interpolation_to_the_last_bit():
    rng = np.random.default_rng(2)
    for tip, heel, a, b in rng.normal(size=(200, 4, 3)) * rng.uniform(0.01, 10.0, (200, 1, 1)):
        c = segment_zone_clearance(tip, heel, Zone("z", a, b, 0.05, np.zeros(3), 0.1))
        s, t = closest_segment_points(tip, heel, a, b)
        pb, pz = tip + s * (heel - tip), a + t * (b - a)
        assert np.array_equal(c.blade_point, pb) and np.array_equal(c.zone_point, pz)
        dist = float(np.sqrt(_dot3(pb - pz)))
        assert c.distance == dist - 0.05 and np.array_equal(c.normal, (pb - pz) / dist)


def _dot3(x):
    return x[0] * x[0] + x[1] * x[1] + x[2] * x[2]


def test_segment_distance_matches_brute_force():
    rng = np.random.default_rng(0)
    for _ in range(40):
        p0, p1, q0, q1 = rng.normal(size=(4, 3))
        if rng.random() < 0.2:
            q1 = q0.copy()  # a sphere
        s, t = closest_segment_points(p0, p1, q0, q1)
        exact = float(np.linalg.norm(p0 + s * (p1 - p0) - q0 - t * (q1 - q0)))
        brute = _brute(p0, p1, q0, q1)
        assert exact <= brute + 1e-12
        assert brute - exact < 1e-2 * max(np.linalg.norm(p1 - p0), np.linalg.norm(q1 - q0), 1e-3)


def test_clearance_of_a_sphere_is_the_point_distance_minus_radius():
    z = Zone("ball", np.array([0.0, 0.0, 0.0]), np.array([0.0, 0.0, 0.0]), 0.05, np.zeros(3), 0.15)
    c = segment_zone_clearance(np.array([0.2, 0.0, 0.0]), np.array([0.2, 0.0, 0.3]), z)
    assert c.distance == pytest.approx(0.15)
    assert c.s == pytest.approx(0.0) and np.allclose(c.normal, [1.0, 0.0, 0.0])


def _superlimb():
    model = build_pinocchio_model(P).model
    lim = JointLimits.from_superlimb(P)
    return model, lim


def test_heel_frame_and_blade_jacobian_are_those_of_the_rigid_knife():
    model, _ = _superlimb()
    limit = KeepOutLimit(model, TOOL_FRAME, HEEL)
    rng = np.random.default_rng(1)
    q = 0.5 * (P.lower + P.upper) + 0.3 * rng.normal(size=3)
    v = rng.normal(size=3)
    tip, heel = limit.knife(q, v)
    data = model.createData()
    pin.framesForwardKinematics(model, data, q)
    M = data.oMf[model.getFrameId(TOOL_FRAME)]
    assert np.allclose(heel.p, M.translation + M.rotation @ np.array(HEEL), atol=1e-12)
    eps = 1e-7  # finite differences of the heel's position along v
    plus = limit.knife(q + eps * v)[1]
    minus = limit.knife(q - eps * v)[1]
    assert np.allclose(heel.J @ v, (plus.p - minus.p) / (2 * eps), atol=1e-6)
    assert np.allclose(heel.v, heel.J @ v, atol=1e-12)


def test_a_blade_shared_with_the_floor_gives_the_rows_of_separate_blades():
    from robot.floor import FloorLimit
    from robot.state import StateEvaluator

    model, _ = _superlimb()
    floor = FloorLimit(model, TOOL_FRAME, HEEL)
    floor.set_plane((0.0, 0.0, 1.0), -0.3)
    shared, alone = KeepOutLimit(model, TOOL_FRAME, HEEL, blade=floor.blade), KeepOutLimit(model, TOOL_FRAME, HEEL)
    evaluate = StateEvaluator(model, model.getFrameId(TOOL_FRAME))
    rng = np.random.default_rng(2)
    for k in range(6):
        q = 0.5 * (P.lower + P.upper) + 0.3 * rng.normal(size=3)
        state = evaluate(q, rng.normal(size=3) if k % 3 else np.zeros(3), 0.01)
        zone = Zone("hand", state.p + 0.05, state.p + 0.05, 0.04, np.zeros(3), 0.15)
        shared.set_zones([zone])
        alone.set_zones([zone])
        for _ in range(2):  # the second call of a state reuses its kinematics
            rows = [floor.compute_qp_inequalities(state), shared.compute_qp_inequalities(state)]
            assert np.array_equal(rows[1].G, alone.compute_qp_inequalities(state).G)
            assert np.array_equal(rows[1].h, alone.rows.h)
            assert shared.knife(state.q, state.v)[0] is floor.blade.knife(state.q, state.v)[0]


def _loop(zone_at, target, steps, cfg=None):
    """QP with the keep-out rows tracking ``target`` while the zone follows ``zone_at(k)``: clearances."""
    model, lim = _superlimb()
    limit = KeepOutLimit(model, TOOL_FRAME, HEEL, cfg)
    qp = QPController(model, TOOL_FRAME, lim, constraints=[TorqueLimit(lim), limit])
    q, v = 0.5 * (P.lower + P.upper), np.zeros(3)
    tip0 = qp.tip_position(q)
    out = []
    for k in range(steps):
        limit.set_zones([zone_at(k, tip0)])
        r = qp.step(q, v, target(tip0))
        if limit.rows is not None and not (limit.rows.G @ r.a <= limit.rows.h + 1e-6).all():
            act = retreat(qp, limit, q, v)
            assert act is not None
            r.a, r.q_next, r.v_next = act.a, q + (v + 0.5 * 0.01 * act.a) * 0.01, v + act.a * 0.01
        q, v = r.q_next, r.v_next
        tip, heel = limit.knife(q)
        out.append(segment_zone_clearance(tip.p, heel.p, zone_at(k + 1, tip0)).distance)
    return np.array(out)


def test_a_reference_inside_the_zone_never_brings_the_knife_inside_its_margin():
    def zone(k, tip0):
        c = tip0 + np.array([0.0, 0.08, 0.0])
        return Zone("hand", c, c, 0.045, np.zeros(3), 0.15)

    d = _loop(zone, lambda tip0: tip0 + np.array([0.0, 0.1, 0.0]), 150)
    print(f"least clearance {d.min() * 1e3:.2f} mm (margin 20 mm)")
    assert d.min() >= 0.02 - 1e-4


def test_a_hand_sweeping_at_0_4_m_s_is_kept_out_and_the_knife_yields():
    def zone(k, tip0):
        c = tip0 + np.array([0.0, 0.2 - min(0.004 * k, 0.2), 0.05])  # 0.4 m/s toward and past the knife
        vel = np.array([0.0, -0.4, 0.0]) if 0.004 * k < 0.2 else np.zeros(3)
        return Zone("hand", c, c, 0.045, vel, 0.15)

    d = _loop(zone, lambda tip0: tip0, 80)
    print(f"least clearance to a sweeping hand {d.min() * 1e3:.2f} mm")
    assert d.min() > 0.0


def test_keepout_rows_on_another_arm():
    erd = pytest.importorskip("example_robot_data")
    model = erd.load("ur5").model
    limit = KeepOutLimit(model, "tool0", (0.0, 0.0, -0.08), KeepOutConfig(max_zones=2))
    lim = JointLimits.from_model(model, a_max=8.0, a_brake=3.0)
    qp = QPController(model, "tool0", lim, constraints=[TorqueLimit(lim), limit])
    q, v = np.array([0.0, -1.2, 1.5, -1.9, -1.57, 0.0]), np.zeros(6)
    tip0 = qp.tip_position(q)
    c = tip0 + np.array([0.0, 0.0, -0.12])
    limit.set_zones([Zone("hand", c, c, 0.04, np.zeros(3), 0.15)])
    for _ in range(200):
        r = qp.step(q, v, c)
        q, v = r.q_next, r.v_next
    tip, heel = limit.knife(q)
    d = segment_zone_clearance(tip.p, heel.p, limit.zones[0]).distance
    assert limit.rows.G.shape == (4, 6)
    assert d >= 0.02 - 1e-4


def test_bad_settings_are_refused():
    model, _ = _superlimb()
    with pytest.raises(ValueError, match="margin"):
        KeepOutConfig(margin=-1.0)
    with pytest.raises(Exception, match="heel_offset"):
        KeepOutLimit(model, TOOL_FRAME, (0.0, 0.0, 0.0))
    limit = KeepOutLimit(model, TOOL_FRAME, HEEL, KeepOutConfig(max_zones=1))
    z = Zone("a", np.zeros(3), np.zeros(3), 0.1, np.zeros(3), 0.1)
    with pytest.raises(Exception, match="max_zones"):
        limit.set_zones([z, z])
