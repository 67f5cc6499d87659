"""Closed-form position kinematics of the SuperLimb's knife tip (its fast path).

The arm is a yaw joint followed by a planar shoulder–elbow pair whose plane
contains the yaw axis (see :mod:`robot.superlimb.params`).  In the turret frame, with
angles positive *down* (rotation about +y), the tip is

    r = s_x + L1·cos q1 + L2·cos(q1 + q2 + φ)      (horizontal, along the turret x axis)
    z = s_z − L1·sin q1 − L2·sin(q1 + q2 + φ)      (up)

where the forearm (length L_f) and the knife (length L_k, pitched κ down) fold
into one link L2·e^{iφ} = L_f + L_k·e^{iκ}.  The inverse is the textbook
two-link solution (two elbow branches), plus the yaw q0 = atan2(y, x) (and the
back-reaching branch q0 + π, r < 0).  Used to check that demonstrations are
reachable (:func:`reachable`) and to find the episode's start pose; tested
against Pinocchio's forward kinematics.  Any other arm uses the numerical
inverse of :mod:`robot.ik` (Pinocchio); this closed form is ≈ 100× faster and exact.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .params import SuperLimbParams, rpy_to_matrix

__all__ = ["ArmGeometry", "forward_tip", "inverse_tip", "nearest_reachable_q", "reachable"]


@dataclass(frozen=True)
class ArmGeometry:
    """The numbers the closed form needs, read from :class:`SuperLimbParams`.

    mount_R (3, 3), mount_p (3,) [m]: base_link in the torso (model world) frame;
    yaw_z [m]: yaw joint above the base; s_x, s_z [m]: shoulder axis in the turret
    frame; L1 [m]: shoulder → elbow; L2 [m], phi [rad]: the folded forearm + knife
    link; lower, upper (3,) [rad]: joint limits.
    """

    mount_R: np.ndarray
    mount_p: np.ndarray
    yaw_z: float
    s_x: float
    s_z: float
    L1: float
    L2: float
    phi: float
    lower: np.ndarray
    upper: np.ndarray

    @classmethod
    def from_params(cls, params: SuperLimbParams | None = None) -> ArmGeometry:
        """Geometry of ``params``; raises ValueError for a layout the closed form does not cover."""
        p = params or SuperLimbParams()
        j0, j1, j2 = p.joints
        axes_ok = (tuple(j0.axis) == (0.0, 0.0, 1.0) and tuple(j1.axis) == (0.0, 1.0, 0.0)
                   and tuple(j2.axis) == (0.0, 1.0, 0.0))
        planar = (j0.origin_xyz[0] == 0.0 and j0.origin_xyz[1] == 0.0 and j1.origin_xyz[1] == 0.0
                  and j2.origin_xyz[1] == 0.0 and j2.origin_xyz[2] == 0.0
                  and all(a == 0.0 for j in p.joints for a in j.origin_rpy))
        if not (axes_ok and planar):
            raise ValueError("closed-form kinematics needs the SuperLimb layout: yaw about z, shoulder and elbow "
                             "about y, no lateral offsets and zero joint origin rotations")
        link2 = p.forearm_length + p.knife_length * complex(math.cos(p.knife_pitch), math.sin(p.knife_pitch))
        return cls(rpy_to_matrix(p.mount_rpy), np.array(p.mount_xyz, dtype=float), float(j0.origin_xyz[2]),
                   float(j1.origin_xyz[0]), float(j1.origin_xyz[2]), float(j2.origin_xyz[0]),
                   abs(link2), math.atan2(link2.imag, link2.real), p.lower.copy(), p.upper.copy())


def forward_tip(geom: ArmGeometry, q: np.ndarray) -> np.ndarray:
    """Knife tip [m] in the torso frame for joint angles ``q`` (..., 3) [rad] (module equation)."""
    q = np.asarray(q, dtype=float)
    q0, q1, q2 = q[..., 0], q[..., 1], q[..., 2]
    r = geom.s_x + geom.L1 * np.cos(q1) + geom.L2 * np.cos(q1 + q2 + geom.phi)
    z = geom.yaw_z + geom.s_z - geom.L1 * np.sin(q1) - geom.L2 * np.sin(q1 + q2 + geom.phi)
    local = np.stack([r * np.cos(q0), r * np.sin(q0), z], axis=-1)
    return local @ geom.mount_R.T + geom.mount_p


def _wrap_into(angle: np.ndarray, lo: float, hi: float) -> np.ndarray:
    """Shift angles by multiples of 2π into [lo, hi] where possible (else leave them outside)."""
    a = np.where(angle < lo, angle + 2 * np.pi, angle)
    return np.where(a > hi, a - 2 * np.pi, a)


def inverse_tip(geom: ArmGeometry, tip: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """All closed-form solutions for tips (N, 3) [m] in the torso frame.

    Returns ``(q, ok)``: q (N, 4, 3) [rad] for the four branches (yaw front/back ×
    elbow sign) and ok (N, 4) True where that branch exists (the tip is within
    the annulus of the two links) and lies within the joint limits.
    """
    tip = np.atleast_2d(np.asarray(tip, dtype=float))
    d = (tip - geom.mount_p) @ geom.mount_R  # into the base frame
    rho = np.hypot(d[:, 0], d[:, 1])
    yaw = np.arctan2(d[:, 1], d[:, 0])
    zrel = d[:, 2] - geom.yaw_z - geom.s_z
    out = np.full((tip.shape[0], 4, 3), np.nan)
    ok = np.zeros((tip.shape[0], 4), dtype=bool)
    k = 0
    for r_sign, yaw_b in ((1.0, yaw), (-1.0, yaw + np.pi)):
        X = r_sign * rho - geom.s_x
        Y = -zrel  # down positive, like the pitch angles
        c = (X * X + Y * Y - geom.L1**2 - geom.L2**2) / (2.0 * geom.L1 * geom.L2)
        exists = np.abs(c) <= 1.0
        beta0 = np.arccos(np.clip(c, -1.0, 1.0))
        for sign in (1.0, -1.0):
            beta = sign * beta0
            q1 = np.arctan2(Y, X) - np.arctan2(geom.L2 * np.sin(beta), geom.L1 + geom.L2 * np.cos(beta))
            q = np.stack([yaw_b, q1, beta - geom.phi], axis=-1)
            for j in range(3):
                q[:, j] = _wrap_into(q[:, j], geom.lower[j], geom.upper[j])
            within = np.all((q >= geom.lower) & (q <= geom.upper), axis=1)
            out[:, k] = q
            ok[:, k] = exists & within
            k += 1
    return out, ok


def reachable(geom: ArmGeometry, tip: np.ndarray) -> np.ndarray:
    """(N,) bool: some joint configuration within the limits puts the knife tip at ``tip`` (N, 3) [m]."""
    return inverse_tip(geom, tip)[1].any(axis=1)


def nearest_reachable_q(geom: ArmGeometry, tip: np.ndarray, q_prefer: np.ndarray | None = None) -> np.ndarray:
    """A joint configuration (3,) [rad] for one tip (3,) [m] in the torso frame.

    The exact solution nearest to ``q_prefer`` (default: mid-range) when the tip is
    reachable; otherwise the in-limit configuration whose tip is nearest (bounded
    least squares, scipy), so that an episode can always start.
    """
    q_all, ok = inverse_tip(geom, np.asarray(tip, dtype=float)[None])
    pref = 0.5 * (geom.lower + geom.upper) if q_prefer is None else np.asarray(q_prefer, dtype=float)
    if ok[0].any():
        cands = q_all[0][ok[0]]
        return cands[np.argmin(np.linalg.norm(cands - pref, axis=1))].copy()
    from scipy.optimize import least_squares

    res = least_squares(lambda q: forward_tip(geom, q) - tip, np.clip(pref, geom.lower, geom.upper),
                        bounds=(geom.lower, geom.upper))
    return np.clip(res.x, geom.lower, geom.upper)
