"""The tip reference's bounds: the nearest point of the workspace box ∩ the reach shell."""

from __future__ import annotations

import numpy as np
import pytest

from mpcshare.control.workspace import WorkspaceBox, project_box_shell

LO, HI = np.array(WorkspaceBox().lower), np.array(WorkspaceBox().upper)


def _inside(x, c, r_min, r_max, tol=1e-9):
    return bool((x >= LO - tol).all() and (x <= HI + tol).all() and r_min - tol <= np.linalg.norm(x - c) <= r_max + tol)


def test_clamping_then_projecting_leaves_the_box_the_joint_projection_does_not():
    """The old two-stage clamp (box, then radially onto the reach) can put the reference below the box's floor."""
    c, r_min, r_max = np.array([0.0, 0.0, -0.35]), 0.1, 0.36
    p = np.array([0.30, 0.0, 0.0])  # in the box, 0.46 m from the pivot: out of reach
    box = np.minimum(np.maximum(p, LO), HI)
    d = box - c
    old = c + d * (r_max / np.linalg.norm(d))
    assert old[2] < LO[2] - 0.04  # 4.7 cm under the box's floor
    x, met = project_box_shell(p, LO, HI, c, r_min, r_max)
    assert met and _inside(x, c, r_min, r_max)
    assert x[2] == pytest.approx(LO[2]) and np.linalg.norm(x - c) == pytest.approx(r_max)


@pytest.mark.parametrize("seed", range(3))
def test_nearest_point_of_both_against_sampling(seed):
    rng = np.random.default_rng(seed)
    grid = rng.uniform(LO, HI, (200_000, 3))
    for _ in range(20):
        c = rng.uniform(LO - 0.3, HI + 0.3)
        r_min = rng.uniform(0.02, 0.2)
        r_max = r_min + rng.uniform(0.05, 0.4)
        p = rng.uniform(LO - 0.3, HI + 0.3)
        x, met = project_box_shell(p, LO, HI, c, r_min, r_max)
        r = np.linalg.norm(grid - c, axis=1)
        ok = grid[(r >= r_min) & (r <= r_max)]
        if not met:
            assert ok.size == 0 or np.allclose(x, np.minimum(np.maximum(p, LO), HI))
            assert ok.size == 0  # sampling finds no point of both either
            continue
        assert _inside(x, c, r_min, r_max)
        if ok.size:
            assert np.linalg.norm(x - p) <= np.linalg.norm(ok - p, axis=1).min() + 1e-9


def test_inside_is_unchanged_and_disjoint_sets_keep_the_box():
    c = np.array([0.1, 0.0, 0.1])
    p = np.array([0.1, 0.1, 0.1])
    x, met = project_box_shell(p, LO, HI, c, 0.05, 0.3)
    assert met and (x == p).all()
    x, met = project_box_shell(np.array([0.5, 0.0, -0.2]), LO, HI, np.array([2.0, 0.0, 0.0]), 0.1, 0.5)
    assert not met and np.allclose(x, [0.30, 0.0, -0.03])  # the box's point, floor first
    x, met = project_box_shell(c, LO, HI, c, 0.05, 0.3)  # at the pivot itself: out through the inner sphere
    assert met and np.linalg.norm(x - c) == pytest.approx(0.05)


def test_bound_reference_drops_the_outward_part_of_the_velocity_only():
    from mpcshare.control.workspace import bound_reference

    box = (np.array([-0.1, -0.1, 0.0]), np.array([0.1, 0.1, 0.2]))
    pivot, r_min, r_max = np.array([0.0, 0.0, 0.5]), 0.0, 10.0  # the reach contains the box
    u, a = np.array([0.3, 0.0, -0.5]), np.array([0.0, 1.0, -2.0])
    p, u2, a2, fault = bound_reference(np.array([0.05, 0.0, -0.01]), u, a, box, pivot, r_min, r_max)
    np.testing.assert_allclose(p, [0.05, 0.0, 0.0])  # onto the floor
    np.testing.assert_allclose(u2, [0.3, 0.0, 0.0])  # the downward part dropped, the sideways kept
    np.testing.assert_allclose(a2, [0.0, 1.0, 0.0])
    assert "projected" in fault
    p, u3, a3, fault = bound_reference(np.array([0.0, 0.0, 0.1]), u, a, box, pivot, r_min, r_max)
    assert fault is None and (u3 == u).all() and (a3 == a).all() and (p == [0.0, 0.0, 0.1]).all()
