"""Frames and the workspace box of the knife tip (plate frame).

* The **base pose** ``T`` (4×4) is the arm's model world frame (the torso frame of
  ``robot.superlimb``) expressed in the plate frame: ``p_plate = R·p_model + t``, so
  ``p_model = Rᵀ·(p_plate − t)``. The controller has no default: its caller gives it
  (``mpcshare.arms.rest_base_pose``, the torso at rest in the eating scene, or the measured pose).
* The **workspace box** (plate frame) bounds the integrated tip reference:
  x ∈ [−0.10, 0.30], y ∈ [−0.25, 0.20], z ∈ [−0.03, 0.25] m by default — the plate
  (radius ≈ 0.12 m) with a margin, from 3 cm below its surface to 25 cm above it; the
  controller raises its floor to ``ControllerConfig.floor_z`` (the plate's top, the knife's
  hard floor) when that is set.
* :func:`project_box_shell` puts a point into the box and the arm's reach shell *at once*
  (clamping to one and then projecting onto the other can leave the first).

What the arm itself can reach (the reach shell, in the model frame) is the robot's
knowledge: :class:`robot.kinematics.ReachShell`.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np

from mpcshare.errors import ControllerSetupError

__all__ = ["DEFAULT_WORKSPACE", "WorkspaceBox", "bound_reference", "check_base_pose",
           "project_box_shell"]

@dataclass(frozen=True)
class WorkspaceBox:
    """Axis-aligned box in the plate frame [m]; ``clamp`` returns (clamped point, was clamped)."""

    lower: tuple[float, float, float] = (-0.10, -0.25, -0.03)
    upper: tuple[float, float, float] = (0.30, 0.20, 0.25)

    def __post_init__(self) -> None:
        lo, hi = np.asarray(self.lower, dtype=float), np.asarray(self.upper, dtype=float)
        if lo.shape != (3,) or hi.shape != (3,) or not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
            raise ControllerSetupError("WorkspaceBox lower/upper must be finite (3,) [m]")
        if np.any(lo >= hi):
            raise ControllerSetupError(f"WorkspaceBox needs lower < upper on every axis, "
                                       f"got {self.lower}, {self.upper}")

    def clamp(self, p: np.ndarray) -> tuple[np.ndarray, bool]:
        c = np.minimum(np.maximum(p, self.lower), self.upper)
        return c, bool((c != p).any())


DEFAULT_WORKSPACE = WorkspaceBox()


#: Every face of a box: per axis 0 = free, 1 = at the lower bound, 2 = at the upper bound (27 faces).
_FACES = tuple(itertools.product((0, 1, 2), repeat=3))


def _sphere_on_face(p: np.ndarray, center: np.ndarray, r: float, face: tuple[int, int, int],
                    lower: np.ndarray, upper: np.ndarray) -> list[np.ndarray]:
    """The points of the sphere ‖x − c‖ = r on a face's affine subspace nearest to and farthest from p (on
    a line the sphere is these two points; ±axes when p is at the sub-sphere's centre); none where the
    subspace misses the sphere."""
    fixed = np.array(face) > 0
    x0 = np.where(np.array(face) == 1, lower, np.where(np.array(face) == 2, upper, p))
    rho2 = r * r - float(((x0 - center)[fixed] ** 2).sum())
    if rho2 < 0.0 or fixed.all():
        return [x0] if fixed.all() and abs(rho2) < 1e-12 else []
    d = np.where(fixed, 0.0, p - center)
    nd = float(np.linalg.norm(d))
    axes = [sign * np.eye(3)[i] for i in np.flatnonzero(~fixed) for sign in (1.0, -1.0)]
    dirs = [d / nd, -d / nd] if nd > 1e-12 else axes
    return [np.where(fixed, x0, center + math.sqrt(rho2) * u) for u in dirs]


def project_box_shell(p: np.ndarray, lower: np.ndarray, upper: np.ndarray, center: np.ndarray,
                      r_min: float, r_max: float, tol: float = 1e-9) -> tuple[np.ndarray, bool]:
    """The nearest point to ``p`` in box ∩ shell, B = [lower, upper], S = {r_min ≤ ‖x − c‖ ≤ r_max} [m].

    Returns (point, True), or (the box's clamp of p, False) when B and S do not meet. Exact: the
    nearest point has some set of active box faces and at most one active sphere; with none active
    it is clip(p), else it is a point of that sphere within that face's affine subspace nearest to
    p on it (or, on a line, the other of its two points). Every face (27) and both spheres are
    tried and the nearest candidate of B ∩ S kept (S is not convex: alternating projections need
    not find it).
    """
    b = np.minimum(np.maximum(p, lower), upper)
    d = b - center
    if r_min <= math.sqrt(float(d.dot(d))) <= r_max:  # ‖b − c‖ as np.linalg.norm sums it, one call
        return b, True
    best, best_d = b, math.inf
    for face in _FACES:
        for r in (r_min, r_max):
            for x in _sphere_on_face(p, center, r, face, lower, upper):
                rx = float(np.linalg.norm(x - center))
                dx = float(np.linalg.norm(x - p))
                if dx < best_d and (x >= lower - tol).all() and (x <= upper + tol).all() \
                        and r_min - tol <= rx <= r_max + tol:
                    best, best_d = np.minimum(np.maximum(x, lower), upper), dx
    return best, math.isfinite(best_d)


def bound_reference(p: np.ndarray, u: np.ndarray, acc: np.ndarray, box: tuple[np.ndarray, np.ndarray],
                    pivot: np.ndarray, r_min: float, r_max: float
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, str | None]:
    """(p', u', a', fault): the tip reference ``p`` [m] projected onto the box ∩ the reach shell
    (:func:`project_box_shell`), and the velocity ``u`` [m/s] and acceleration ``a`` less their
    part along the outward normal n = (p − p')/‖p − p'‖ where projected (u' = u − max(0, u·n)·n),
    so that a smoother aimed ahead along u is not aimed through the bound; ``fault`` says why the
    reference moved (None where it did not)."""
    p_new, met = project_box_shell(p, box[0], box[1], pivot, r_min, r_max)
    fault = None
    if not met:
        fault = "the workspace box and the arm's reach do not meet: the reference kept in the box"
    elif (p_new != p).any():
        fault = "tip reference projected onto the workspace box and the arm's reach"
    out = p - p_new
    norm = math.sqrt(float(out @ out))
    if norm > 1e-12:
        n = out / norm
        u = u - max(0.0, float(u @ n)) * n
        acc = acc - max(0.0, float(acc @ n)) * n
    return p_new, u, acc, fault


def check_base_pose(T: object) -> np.ndarray:
    """The (4, 4) float array of a valid homogeneous transform, else ValueError saying why."""
    a = np.asarray(T, dtype=float)
    if a.shape != (4, 4):
        raise ValueError(f"base_pose must be a (4, 4) homogeneous transform, got shape {a.shape}")
    flat = a.ravel().tolist()
    if not all(map(math.isfinite, flat)):
        raise ValueError("base_pose has non-finite entries")
    r00, r01, r02, _, r10, r11, r12, _, r20, r21, r22, _, l0, l1, l2, l3 = flat
    # RᵀR − I and det R in plain floats: it runs at every control step
    gram = max(abs(r00 * r00 + r10 * r10 + r20 * r20 - 1.0), abs(r01 * r01 + r11 * r11 + r21 * r21 - 1.0),
               abs(r02 * r02 + r12 * r12 + r22 * r22 - 1.0), abs(r00 * r01 + r10 * r11 + r20 * r21),
               abs(r00 * r02 + r10 * r12 + r20 * r22), abs(r01 * r02 + r11 * r12 + r21 * r22))
    det = r00 * (r11 * r22 - r12 * r21) - r01 * (r10 * r22 - r12 * r20) + r02 * (r10 * r21 - r11 * r20)
    if gram > 1e-6 or abs(det - 1.0) > 1e-6 or max(abs(l0), abs(l1), abs(l2), abs(l3 - 1.0)) > 1e-12:
        raise ValueError("base_pose is not a rigid transform (rotation not orthonormal or last row not 0 0 0 1)")
    return a
