"""Any arm's kinematics and rigid-body dynamics as CasADi functions, generated from its Pinocchio model.

The pip wheel of Pinocchio has no ``pinocchio.casadi``, so :class:`SymbolicArm` builds the model
from the numbers of a :class:`robot.description.RobotDescription` (joint placements, types and
axes, body inertias, armature, gravity, the tool frame). q [rad], v [rad/s], a [rad/s²]; positions
in the model's world frame. Recursive Newton–Euler (Featherstone 2008, Table 5.1) in each joint
frame, spatial vectors as (linear, angular) pairs; joint i with parent λ, placement (R, p) (child →
parent) times the joint motion, motion subspace S_i = (0, s) (revolute) or (s, 0) (prismatic):

    ω_i = Rᵀω_λ (+ s·v_i revolute),   ν_i = Rᵀ(ν_λ + ω_λ × p) (+ s·v_i prismatic)
    a_i = ᵢX_λ·a_λ + S_i·a_i + v_i ×ₘ S_i·v_i,   a_0 = (−g, 0)   (gravity as a base acceleration)
    f_i = I_i·a_i + v_i ×* I_i·v_i,   τ_i = S_iᵀ·f_i + I_a,i·a_i,   f_λ += (R·f, R·n + p × R·f)

(×ₘ, ×*: motion and force cross products; I_i from mass, centre of mass and inertia in the joint frame).

So ``inverse_dynamics(q, v, a) = M(q)·a + h(q, v)``; M = ∂τ/∂a (exact, τ is linear in a),
h = τ(q, v, 0) (Pinocchio's ``nonLinearEffects``), ``forward_dynamics`` = M⁻¹(τ − h) (ABA); the tip
Jacobian ∂p/∂q is world-aligned (``LOCAL_WORLD_ALIGNED``, translational rows). Equal to Pinocchio's
RNEA, CRBA and ABA to 1e-9 (``tests/robot/mpc/test_symbolic.py``). A ``robot`` that is neither a
description, a ``SuperLimbParams`` nor None raises ``TypeError``.
"""

from __future__ import annotations

from typing import Any

import casadi as ca
import numpy as np

from robot.default_arm import as_description
from robot.description import RobotDescription
from robot.mjcf import joint_axis

__all__ = ["SymbolicArm"]


def _axis_rotation(axis: np.ndarray, angle: ca.SX) -> ca.SX:
    """Rodrigues: R = I + sin θ·K + (1 − cos θ)·K², K = [axis]× (axis a unit vector)."""
    K = ca.skew(ca.DM(axis))
    return ca.DM.eye(3) + ca.sin(angle) * K + (1.0 - ca.cos(angle)) * (K @ K)


class SymbolicArm:
    """CasADi functions of an arm (module docstring); ``robot`` a :class:`RobotDescription`
    (None or a ``SuperLimbParams``: the SuperLimb).

    Attributes (``casadi.Function``, SX inside, callable on numbers, SX or MX), n joints:

    - ``tip_position(q) -> p (3,)`` [m], the tool frame's origin in the world frame;
    - ``tip_jacobian(q) -> J (3, n)`` [m/rad], J = ∂p/∂q (world-aligned);
    - ``mass_matrix(q) -> M (n, n)`` [kg·m²], armature on the diagonal;
    - ``nonlinear_effects(q, v) -> h (n,)`` [N·m], C(q, v)·v + g(q);
    - ``inverse_dynamics(q, v, a) -> τ (n,)`` [N·m], M(q)·a + h(q, v);
    - ``forward_dynamics(q, v, τ) -> a (n,)`` [rad/s²], M(q)⁻¹·(τ − h(q, v)).
    """

    def __init__(self, robot: RobotDescription | Any = None) -> None:
        self.robot = as_description(robot)
        self.n = n = self.robot.n
        q, v, a, tau_in = ca.SX.sym("q", n), ca.SX.sym("v", n), ca.SX.sym("a", n), ca.SX.sym("tau", n)
        tip, tau = self._rnea(q, v, a)
        M = ca.jacobian(tau, a)
        h = ca.substitute(tau, a, ca.SX.zeros(n))
        self.tip_position = ca.Function("tip_position", [q], [tip], ["q"], ["p"])
        self.tip_jacobian = ca.Function("tip_jacobian", [q], [ca.jacobian(tip, q)], ["q"], ["J"])
        self.mass_matrix = ca.Function("mass_matrix", [q], [M], ["q"], ["M"])
        self.nonlinear_effects = ca.Function("nonlinear_effects", [q, v], [h], ["q", "v"], ["h"])
        self.inverse_dynamics = ca.Function("inverse_dynamics", [q, v, a], [tau], ["q", "v", "a"], ["tau"])
        self.forward_dynamics = ca.Function("forward_dynamics", [q, v, tau_in], [ca.solve(M, tau_in - h)],
                                            ["q", "v", "tau"], ["a"])

    # ------------------------------------------------------------------
    def _rnea(self, q: ca.SX, v: ca.SX, a: ca.SX) -> tuple[ca.SX, ca.SX]:
        """Tip position and τ = M(q)·a + h(q, v) by recursive Newton–Euler (module docstring)."""
        model = self.robot.model
        g = np.asarray(model.gravity.linear, dtype=float)
        zero = ca.SX.zeros(3)
        # per joint: R, p (in the parent), world pose (R_o, p_o), velocity (ν, ω), acceleration (α_lin, α_ang)
        R_of, p_of = {0: ca.SX(ca.DM.eye(3))}, {0: ca.SX.zeros(3)}
        vel, acc = {0: (zero, zero)}, {0: (ca.SX(ca.DM(-g)), zero)}
        local, forces, motion = {}, {}, {}
        for j in range(1, model.njoints):
            jm = model.joints[j]
            kind, s = joint_axis(jm)
            iv, lam = jm.idx_v, model.parents[j]
            place = model.jointPlacements[j]
            R, p = ca.DM(place.rotation), ca.DM(place.translation)
            if kind == "hinge":
                R = R @ _axis_rotation(s, q[iv])
                S_lin, S_ang = ca.DM.zeros(3), ca.DM(s)
            else:
                p = p + R @ ca.DM(s) * q[iv]
                S_lin, S_ang = ca.DM(s), ca.DM.zeros(3)
            local[j], motion[j] = (R, p), (S_lin, S_ang)
            R_of[j], p_of[j] = R_of[lam] @ R, p_of[lam] + R_of[lam] @ p
            nu_l, om_l = vel[lam]
            al_l, aa_l = acc[lam]
            Rt = R.T
            om = Rt @ om_l + S_ang * v[iv]
            nu = Rt @ (nu_l + ca.cross(om_l, p)) + S_lin * v[iv]
            sv_lin, sv_ang = S_lin * v[iv], S_ang * v[iv]
            aa = Rt @ aa_l + S_ang * a[iv] + ca.cross(om, sv_ang)
            al = Rt @ (al_l + ca.cross(aa_l, p)) + S_lin * a[iv] + ca.cross(om, sv_lin) + ca.cross(nu, sv_ang)
            vel[j], acc[j] = (nu, om), (al, aa)
            inertia = model.inertias[j]
            m, c, Ic = float(inertia.mass), ca.DM(inertia.lever), ca.DM(inertia.inertia)
            f_a = m * (al + ca.cross(aa, c))
            n_a = Ic @ aa + ca.cross(c, f_a)
            f_v = m * (nu + ca.cross(om, c))
            n_v = Ic @ om + ca.cross(c, f_v)
            forces[j] = [f_a + ca.cross(om, f_v), n_a + ca.cross(om, n_v) + ca.cross(nu, f_v)]
        tau: list[ca.SX] = [None] * self.n  # type: ignore[list-item]
        for j in range(model.njoints - 1, 0, -1):
            f, n_ = forces[j]
            S_lin, S_ang = motion[j]
            iv = model.joints[j].idx_v
            tau[iv] = ca.dot(S_lin, f) + ca.dot(S_ang, n_) + float(model.armature[iv]) * a[iv]
            lam = model.parents[j]
            if lam > 0:
                R, p = local[j]
                Rf = R @ f
                forces[lam][0] = forces[lam][0] + Rf
                forces[lam][1] = forces[lam][1] + R @ n_ + ca.cross(p, Rf)
        frame = model.frames[self.robot.tip_frame_id]
        jt = frame.parentJoint
        tip = p_of[jt] + R_of[jt] @ ca.DM(frame.placement.translation)
        return tip, ca.vertcat(*tau)
