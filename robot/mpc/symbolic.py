"""SuperLimb kinematics and rigid-body dynamics as CasADi functions.

Pinocchio's CasADi bindings are not in the pip wheel, so the model the MPC
needs is generated here from the same :class:`robot.superlimb.SuperLimbParams`
that the URDF, the MJCF and the Pinocchio model are written from (joint
origins and axes, link inertias, armature, gravity, mount, knife pitch and
length).  Every quantity is in the Pinocchio model's ``world`` frame (the
wearer's torso frame); q [rad], v [rad/s], a [rad/s²].

Derivation: **recursive Newton–Euler** (Luh, Walker & Paul 1980) written with
world-frame vectors.  Forward pass, body i with joint axis z_i (world), joint
origin o_i and rotation R_i (world):

    ω_i = ω_{i−1} + z_i·v_i
    ω̇_i = ω̇_{i−1} + z_i·a_i + ω_{i−1} × z_i·v_i
    ö_i = ö_{i−1} + ω̇_{i−1} × r_i + ω_{i−1} × (ω_{i−1} × r_i),   r_i = o_i − o_{i−1},  ö_0 = −g
    c̈_i = ö_i + ω̇_i × ρ_i + ω_i × (ω_i × ρ_i),                  ρ_i = R_i·com_i

Backward pass (forces f and moments n about o_i, children j of i):

    f_i = m_i·c̈_i + Σ_j f_j
    n_i = I_i·ω̇_i + ω_i × I_i·ω_i + ρ_i × m_i·c̈_i + Σ_j (n_j + (o_j − o_i) × f_j),   I_i = R_i·I_c,i·R_iᵀ
    τ_i = z_iᵀ·n_i + I_a,i·a_i                                        (I_a: armature)

so that ``inverse_dynamics(q, v, a) = M(q)·a + h(q, v)``; M is its Jacobian
with respect to a (exact, τ is linear in a) and h = τ(q, v, 0) (Pinocchio's
``nonLinearEffects``).  The knife is rigidly fixed to the forearm and is
lumped into the forearm body; ``base_link`` is fixed to the world and has no
effect on the dynamics.  The tip Jacobian is ∂p/∂q (world-aligned, the
translational rows of Pinocchio's ``LOCAL_WORLD_ALIGNED`` frame Jacobian).
Checked against Pinocchio in ``tests/robot/mpc/test_symbolic.py`` (1e-9).
"""

from __future__ import annotations

from dataclasses import dataclass

import casadi as ca
import numpy as np

from robot.superlimb import Inertial, SuperLimbParams, rpy_to_matrix

_BODY_LINKS = ("turret_link", "upper_arm_link", "forearm_link")


def _inertia_matrix(inertia: tuple[float, ...]) -> np.ndarray:
    """(ixx, iyy, izz, ixy, ixz, iyz) → symmetric 3×3 [kg·m²]."""
    ixx, iyy, izz, ixy, ixz, iyz = inertia
    return np.array([[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]])


@dataclass(frozen=True)
class _Body:
    """Mass [kg], centre of mass [m] and inertia about it [kg·m²], in the joint (link) frame."""

    mass: float
    com: np.ndarray
    inertia: np.ndarray


def _combine(parts: list[tuple[Inertial, np.ndarray, np.ndarray]]) -> _Body:
    """Lump rigidly attached inertials, each placed by (R, t) in the body frame (parallel-axis theorem)."""
    mass = sum(i.mass for i, _, _ in parts)
    com = sum(i.mass * (t + R @ np.asarray(i.com)) for i, R, t in parts) / mass
    inertia = np.zeros((3, 3))
    for i, R, t in parts:
        c = t + R @ np.asarray(i.com) - com
        inertia += R @ _inertia_matrix(i.inertia) @ R.T + i.mass * (float(c @ c) * np.eye(3) - np.outer(c, c))
    return _Body(float(mass), com, inertia)


def _axis_rotation(axis: np.ndarray, angle: ca.SX) -> ca.SX:
    """Rodrigues: R = I + sin θ·K + (1 − cos θ)·K², K = [axis]× (axis a unit vector)."""
    K = ca.skew(ca.DM(axis))
    return ca.DM.eye(3) + ca.sin(angle) * K + (1.0 - ca.cos(angle)) * (K @ K)


class SymbolicArm:
    """CasADi functions of the SuperLimb built from ``params`` (default parameters if None).

    Attributes (``casadi.Function``, SX inside, callable on numbers, SX or MX):

    - ``tip_position(q) -> p (3,)`` [m], the ``knife_tip`` frame origin in the world frame;
    - ``tip_jacobian(q) -> J (3, 3)`` [m/rad], J = ∂p/∂q (world-aligned);
    - ``mass_matrix(q) -> M (3, 3)`` [kg·m²], armature on the diagonal;
    - ``nonlinear_effects(q, v) -> h (3,)`` [N·m], C(q, v)·v + g(q);
    - ``inverse_dynamics(q, v, a) -> τ (3,)`` [N·m], M(q)·a + h(q, v).
    """

    def __init__(self, params: SuperLimbParams | None = None) -> None:
        self.params = params or SuperLimbParams()
        q, v, a = ca.SX.sym("q", 3), ca.SX.sym("v", 3), ca.SX.sym("a", 3)
        tip, tau = self._rnea(q, v, a)
        M = ca.jacobian(tau, a)
        h = ca.substitute(tau, a, ca.SX.zeros(3))
        self.tip_position = ca.Function("tip_position", [q], [tip], ["q"], ["p"])
        self.tip_jacobian = ca.Function("tip_jacobian", [q], [ca.jacobian(tip, q)], ["q"], ["J"])
        self.mass_matrix = ca.Function("mass_matrix", [q], [M], ["q"], ["M"])
        self.nonlinear_effects = ca.Function("nonlinear_effects", [q, v], [h], ["q", "v"], ["h"])
        self.inverse_dynamics = ca.Function("inverse_dynamics", [q, v, a], [tau], ["q", "v", "a"], ["tau"])

    # ------------------------------------------------------------------
    def _bodies(self) -> list[_Body]:
        p = self.params
        links = {link.name: link for link in p.links}
        eye, zero = np.eye(3), np.zeros(3)
        bodies = [_combine([(links[name].inertial, eye, zero)]) for name in _BODY_LINKS[:2]]
        knife_R = rpy_to_matrix((0.0, p.knife_pitch, 0.0))
        knife_t = np.array([p.forearm_length, 0.0, 0.0])
        bodies.append(_combine([(links["forearm_link"].inertial, eye, zero),
                                (links["knife_link"].inertial, knife_R, knife_t)]))
        return bodies

    def _rnea(self, q: ca.SX, v: ca.SX, a: ca.SX) -> tuple[ca.SX, ca.SX]:
        """Tip position and τ = M(q)·a + h(q, v) by world-frame recursive Newton–Euler (module docstring)."""
        p = self.params
        R = ca.DM(rpy_to_matrix(p.mount_rpy))
        o = ca.DM(p.mount_xyz)
        omega, omega_dot = ca.SX.zeros(3), ca.SX.zeros(3)
        acc_o = ca.SX(ca.DM([0.0, 0.0, p.gravity]))  # ö_0 = −g: gravity as an upward base acceleration
        frames = []  # per body: (R, o, z, ω, ω̇, c̈)
        bodies = self._bodies()
        for i, (joint, body) in enumerate(zip(p.joints, bodies)):
            axis = np.asarray(joint.axis, dtype=float)
            norm = float(np.linalg.norm(axis))
            if norm == 0.0:
                raise ValueError(f"joint {joint.name}: axis must be non-zero, got {joint.axis}")
            axis = axis / norm
            r = R @ ca.DM(joint.origin_xyz)
            acc_o = acc_o + ca.cross(omega_dot, r) + ca.cross(omega, ca.cross(omega, r))
            o = o + r
            R = R @ ca.DM(rpy_to_matrix(joint.origin_rpy))
            z = R @ ca.DM(axis)
            R = R @ _axis_rotation(axis, q[i])
            omega_dot = omega_dot + z * a[i] + ca.cross(omega, z * v[i])
            omega = omega + z * v[i]
            rho = R @ ca.DM(body.com)
            acc_c = acc_o + ca.cross(omega_dot, rho) + ca.cross(omega, ca.cross(omega, rho))
            frames.append((R, o, z, omega, omega_dot, rho, acc_c))
        tip = frames[-1][1] + frames[-1][0] @ ca.DM([p.forearm_length, 0.0, 0.0])
        tip = tip + frames[-1][0] @ ca.DM(rpy_to_matrix((0.0, p.knife_pitch, 0.0))) @ ca.DM([p.knife_length, 0.0, 0.0])

        tau = [None, None, None]
        f_child, n_child, o_child = ca.SX.zeros(3), ca.SX.zeros(3), None
        for i in (2, 1, 0):
            R_i, o_i, z, omega, omega_dot, rho, acc_c = frames[i]
            body = bodies[i]
            inertia = R_i @ ca.DM(body.inertia) @ R_i.T
            f = body.mass * acc_c + f_child
            n = inertia @ omega_dot + ca.cross(omega, inertia @ omega) + ca.cross(rho, body.mass * acc_c)
            if o_child is not None:
                n = n + n_child + ca.cross(o_child - o_i, f_child)
            tau[i] = ca.dot(z, n) + p.joints[i].armature * a[i]
            f_child, n_child, o_child = f, n, o_i
        return tip, ca.vertcat(*tau)
