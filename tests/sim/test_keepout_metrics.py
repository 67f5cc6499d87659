"""Keep-out figures on episodes with known answers; the scene draws the zones the controller keeps out."""

from __future__ import annotations

import mujoco
import numpy as np
import pytest

from robot.superlimb import rpy_to_matrix
from robot.wearer_body import BODY_PARTS, body_zone_axes, body_zones, hand_center, zones_to_plate
from sim.episode import Episode
from sim.keepout_metrics import episode_keepout_metrics
from sim.scene import EatingScene
from sim.task import EATING

FORK = np.array([0.0, 0.05, 0.02, 0.1, -0.4, 0.2])
HAND = hand_center(EATING.body, FORK)
R = EATING.body.hand_radius
U = np.array([-1.0, 0.0, 1.0]) / np.sqrt(2.0)  # the blade's direction, tip to heel: the tip leads toward the hand


def _episode(tip: np.ndarray, fork: np.ndarray) -> Episode:
    n = len(tip)
    heel = tip + 0.09 * U  # a 9 cm blade pitched 45° back up
    return Episode(np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3)), np.arange(n) * 0.01,
                   np.zeros(n), np.ones(n), np.zeros(n, int), tip, tip.copy(), tip.copy(), np.zeros((n, 3)),
                   np.array(["ok"] * n), np.full(n, 1e-3), np.tile(np.eye(4), (n, 1, 1)), np.full(n, np.nan),
                   {"control_period_s": 0.01}, fork_pose=fork, knife_heel=heel)


def test_a_knife_driven_into_the_hand_is_counted():
    n = 45  # the tip runs at 0.2 m/s from 6 cm outside the hand's surface to 2.8 cm in
    tip = HAND[None, :] + U[None, :] * (R + 0.06 - 0.002 * np.arange(n))[:, None]
    m = episode_keepout_metrics(_episode(tip, np.tile(FORK, (n, 1))))
    inside = int(np.sum(0.06 - 0.002 * np.arange(n) < 0))
    hand = m["keepout_min_clearance_by_zone_m"]["hand"]
    assert hand == pytest.approx(0.06 - 0.002 * (n - 1), abs=1e-9)
    assert m["keepout_min_clearance_m"] <= hand  # the forearm starts at the hand
    assert m["keepout_max_depth_m"] == pytest.approx(-m["keepout_min_clearance_m"])
    assert m["keepout_time_inside_s"] >= inside * 0.01 - 1e-12
    assert m["keepout_steps_driven_in"] * 0.01 == pytest.approx(m["keepout_time_inside_s"])
    assert m["keepout_inside_zone_moving_s"] == 0.0
    assert m["keepout_near_speed_mps"] == pytest.approx(0.2, rel=1e-6)
    lowest = min(tip[:, 2].min(), (tip + 0.09 * U)[:, 2].min())
    assert m["knife_min_height_m"] == pytest.approx(lowest)  # the blade's lowest point above the plate


def test_a_hand_moving_onto_a_still_knife_is_not_driven_in():
    n = 30  # the hand's centre stops 1.5 cm short of the tip
    tip = np.tile(HAND + U * (R + 0.03), (n, 1))
    fork = np.tile(FORK, (n, 1))
    fork[:, :3] += 0.002 * np.arange(n)[:, None] * U[None, :]  # the hand comes at 0.2 m/s
    m = episode_keepout_metrics(_episode(tip, fork))
    assert m["keepout_time_inside_s"] > 0.1
    assert m["keepout_steps_driven_in"] == 0
    assert m["keepout_inside_zone_moving_s"] >= 0.1
    assert m["keepout_near_speed_mps"] == pytest.approx(0.0, abs=1e-12)


def test_the_zones_of_every_step_at_once_are_those_of_each_step():
    rng = np.random.default_rng(0)
    n = 20
    fork = FORK + 0.05 * rng.normal(size=(n, 6))
    fork[3, 4] = np.nan  # a lost marker: no hand or forearm on that step
    base = np.tile(np.eye(4), (n, 1, 1))
    base[:, :3, 3] = 0.01 * rng.normal(size=(n, 3))
    base[:, :3, :3] = [rpy_to_matrix(r) for r in 0.3 * rng.normal(size=(n, 3))]
    axes = body_zone_axes(EATING.body, fork, base)
    for k in range(n):
        zones = {z.name: z for z in zones_to_plate(body_zones(EATING.body, fork[k], base[k]), base[k])}
        for name in BODY_PARTS:
            a, b, radius = axes[name]
            if name not in zones:
                assert k == 3 and np.isnan(a[k]).all() and np.isnan(b[k]).all()
                continue
            assert radius == zones[name].radius
            np.testing.assert_allclose(a[k], zones[name].a, rtol=0, atol=1e-15)
            np.testing.assert_allclose(b[k], zones[name].b, rtol=0, atol=1e-15)


def test_lost_samples_leave_their_steps_out_and_the_next_speed_waits_for_a_whole_step():
    n = 30
    tip = np.tile(HAND + U * (R + 0.03), (n, 1))
    tip[10:] -= 0.001 * np.arange(n - 10)[:, None] * U[None, :]  # then the knife comes at 0.1 m/s
    fork = np.tile(FORK, (n, 1))
    tip[15] = np.nan  # a lost tip: step 15 has no figures and step 16 no speeds
    fork[20, 0] = np.nan  # a lost fork: no hand or forearm on step 20
    m = episode_keepout_metrics(_episode(tip, fork))
    assert m["keepout_near_speed_mps"] == pytest.approx(0.1, rel=1e-6)
    assert m["keepout_min_clearance_by_zone_m"]["hand"] == pytest.approx(0.03 - 0.001 * (n - 11), abs=1e-9)


def test_an_old_run_file_without_the_fork_pose_has_no_figures(tmp_path):
    ep = _episode(np.zeros((5, 3)), np.tile(FORK, (5, 1)))
    ep.fork_pose = None
    assert all(v is None for v in episode_keepout_metrics(ep).values())
    ep = _episode(np.zeros((5, 3)), np.tile(FORK, (5, 1)))
    back = Episode.load(ep.save(tmp_path / "run.npz"))
    assert np.array_equal(back.fork_pose, ep.fork_pose) and np.array_equal(back.knife_heel, ep.knife_heel)


def test_the_scene_draws_the_zones_where_the_controller_keeps_them():
    scene = EatingScene(seed=1)
    t = 0.7
    scene.set_state(0.5 * (scene.config.params.lower + scene.config.params.upper), np.zeros(3), t)
    scene.set_fork(FORK, t)
    mujoco.mj_forward(scene.model, scene.data)
    base = scene.base_pose(t)
    zones = {z.name: z for z in zones_to_plate(body_zones(EATING.body, FORK, base), base)}
    geom = {name: mujoco.mj_name2id(scene.model, mujoco.mjtObj.mjOBJ_GEOM, name)
            for name in ("hand", "forearm", "head", "trunk")}
    plate = scene.plate_p
    assert np.allclose(scene.data.geom_xpos[geom["hand"]] - plate, zones["hand"].a, atol=1e-9)
    assert np.allclose(scene.data.geom_xpos[geom["head"]] - plate, zones["head"].a, atol=1e-9)
    mid = 0.5 * (zones["forearm"].a + zones["forearm"].b)
    assert np.allclose(scene.data.geom_xpos[geom["forearm"]] - plate, mid, atol=1e-9)
    assert scene.model.geom_size[geom["hand"]][0] == pytest.approx(EATING.body.hand_radius)
    heel = scene.knife_heel_in_plate()
    assert np.linalg.norm(heel - scene.tip_in_plate()) == pytest.approx(scene.config.blade_length)
