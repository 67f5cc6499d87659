"""Speed and acceleration caps whose braking is torque-feasible, on sampled states of a workspace.

The viable position limits rely on braking at ``a_brake`` from any speed |v| ≤ ``v_max``; at a
configuration q the torque it takes is

    τ(q, v, a) = M(q)·a + c(q, v) + g(q)            [N·m]

(c: Coriolis and centrifugal, quadratic in v; g: gravity). Over the box |a_j| ≤ a_brake,j the
largest |τ_i| is exactly |c_i + g_i| + Σ_j |M_ij|·a_brake,j; over v, corners ±v_max are drawn
(:data:`V_CORNERS` sign patterns per state). The **braking torque ratio** is the largest need_i / τ_max,i over
the states: ≤ 1 means braking is feasible there.

Caps from references (v_ref [rad/s], a_ref [rad/s²] of braking) scaled by one factor s ∈ (0, 1]:

    need_i(s) = |g_i + s²·c_i(v_ref)| + s·Σ_j |M_ij|·a_ref,j

:func:`braking_caps` picks the largest s on a geometric grid (ratio 0.98 per step, down to
``s_min``) at which need(s) ≤ ``headroom``·τ_max on every state, at that s and every smaller one
on the grid (so any slower cap is feasible too); a speed or acceleration given by the caller is
kept and only the other one scales. Gravity alone over τ_max (s → 0) has no caps: a clear error.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

import numpy as np
import pinocchio as pin

from robot.errors import ControllerConfigError

__all__ = ["BrakingCaps", "braking_caps", "braking_torque_ratio", "tip_box_states"]

GRID_STEP = 0.98  # ratio of two successive scales tried
V_CORNERS = 8  # sign patterns of v drawn per state
HEADROOM = 0.9  # fraction of τ_max the sampled states may need (the rest: states between the samples)


@dataclass(frozen=True)
class BrakingCaps:
    """Chosen caps: ``velocity`` [rad/s] and ``acceleration`` [rad/s²] (braking at half of it) per
    joint, the ``scale`` s applied to the references, and the braking torque ratio they reach."""

    velocity: np.ndarray
    acceleration: np.ndarray
    scale: float
    ratio: float

    def summary(self) -> str:
        """One line: the caps' ranges over the joints and their braking torque ratio."""
        def span(x: np.ndarray) -> str:
            lo, hi = float(np.min(x)), float(np.max(x))
            return f"{lo:.2g}" if np.isclose(lo, hi) else f"{lo:.2g}–{hi:.2g}"
        return (f"velocity ≤ {span(self.velocity)} rad/s, acceleration ≤ {span(self.acceleration)} rad/s² "
                f"(braking at half: {self.ratio:.2f}× the torque limit at worst)")


def tip_box_states(model, tip_frame_id: int, q_min: np.ndarray, q_max: np.ndarray, lower: Sequence[float],
                   upper: Sequence[float], n: int = 1000, seed: int = 0, max_draws: int = 60000) -> np.ndarray:
    """Up to ``n`` configurations (k, nv), uniform within [q_min, q_max], whose tip frame lies in the
    axis-aligned box [lower, upper] [m] of the model's world frame (rejection sampling, at most
    ``max_draws`` draws). Raises ControllerConfigError when no draw puts the tip in the box."""
    rng = np.random.default_rng(seed)
    data = model.createData()
    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    kept: list[np.ndarray] = []
    for _ in range(max_draws):
        q = rng.uniform(q_min, q_max)
        pin.forwardKinematics(model, data, q)
        p = pin.updateFramePlacement(model, data, tip_frame_id).translation
        if np.all(p >= lo) and np.all(p <= hi):
            kept.append(q)
            if len(kept) == n:
                break
    if not kept:
        raise ControllerConfigError(f"no configuration within the joint limits puts the tip in the box "
                                    f"{lo.round(3).tolist()}–{hi.round(3).tolist()} m ({max_draws} draws): "
                                    "the arm is mounted out of reach")
    return np.array(kept)


def _terms(model, states: np.ndarray, v_ref: np.ndarray, a_ref: np.ndarray, seed: int):
    """Rows (state × v corner): g, c at the corner of v_ref, Σ_j |M_ij| a_ref,j, each (k·V_CORNERS, n)."""
    data = model.createData()
    rng = np.random.default_rng(seed)
    k, n = states.shape
    g, c, m = (np.empty((k, V_CORNERS, n)) for _ in range(3))
    zero = np.zeros(n)
    for i, q in enumerate(states):
        g[i] = pin.rnea(model, data, q, zero, zero)
        M = pin.crba(model, data, q)
        m[i] = np.abs(np.triu(M) + np.triu(M, 1).T) @ a_ref
        for j in range(V_CORNERS):
            c[i, j] = pin.rnea(model, data, q, rng.choice([-1.0, 1.0], n) * v_ref, zero) - g[i, 0]
    return g.reshape(-1, n), c.reshape(-1, n), m.reshape(-1, n)


def _ratio(g, c, m, tau_max, s_v: float, s_a: float) -> float:
    return float(np.max((np.abs(g + s_v ** 2 * c) + s_a * m) / tau_max))


def braking_torque_ratio(robot: Any, n_samples: int = 2000, seed: int = 0, *,
                         states: np.ndarray | None = None) -> float:
    """The braking torque ratio (module docstring) of ``robot`` (a RobotDescription) on ``states``
    (k, n) [rad], default ``n_samples`` configurations uniform within its position limits."""
    lim = robot.limits
    if states is None:
        states = np.random.default_rng(seed).uniform(lim.q_min, lim.q_max, (n_samples, robot.n))
    g, c, m = _terms(robot.model, np.asarray(states, dtype=float), lim.v_max, lim.a_brake, seed)
    return _ratio(g, c, m, lim.tau_max, 1.0, 1.0)


def braking_caps(model, states: np.ndarray, v_ref: np.ndarray, a_ref: np.ndarray, tau_max: np.ndarray, *,
                 scale_velocity: bool = True, scale_acceleration: bool = True, headroom: float = HEADROOM,
                 s_min: float = 0.02, seed: int = 0) -> BrakingCaps:
    """The largest caps ``s·v_ref``, ``s·a_ref`` (acceleration; braking at half) feasible on ``states``
    (module docstring); ``scale_velocity``/``scale_acceleration`` False keep that reference as given.
    Raises ControllerConfigError naming the worst ratio when no scale down to ``s_min`` is feasible."""
    states = np.asarray(states, dtype=float)
    if states.ndim != 2 or states.shape[0] == 0:
        raise ControllerConfigError(f"braking_caps needs states (k, n) with k ≥ 1, got shape {states.shape}")
    v_ref, a_ref, tau_max = (np.asarray(x, dtype=float) for x in (v_ref, a_ref, tau_max))
    g, c, m = _terms(model, states, v_ref, a_ref / 2.0, seed)
    n_grid = int(np.floor(np.log(s_min) / np.log(GRID_STEP))) + 1
    scales = GRID_STEP ** np.arange(n_grid)  # 1, 0.98, … ≥ s_min
    ok = np.array([_ratio(g, c, m, tau_max, s if scale_velocity else 1.0, s if scale_acceleration else 1.0)
                   <= headroom for s in scales])
    # the largest s with every smaller grid scale feasible too: the top of the feasible run at the bottom
    bad = np.flatnonzero(~ok)
    top = 0 if bad.size == 0 else int(bad.max()) + 1
    if top >= n_grid:
        worst = _ratio(g, c, m, tau_max, s_min if scale_velocity else 1.0, s_min if scale_acceleration else 1.0)
        gravity = _ratio(g, 0 * c, 0 * m, tau_max, 0.0, 0.0)
        raise ControllerConfigError(f"braking needs {worst:.2f}× the torque limit at some states even with the caps "
                                    f"scaled to {s_min:g}× (gravity alone: {gravity:.2f}×)")
    s = float(scales[top])
    s_v, s_a = (s if scale_velocity else 1.0), (s if scale_acceleration else 1.0)
    return BrakingCaps(s_v * v_ref, s_a * a_ref, s, _ratio(g, c, m, tau_max, s_v, s_a))
