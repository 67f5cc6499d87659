"""Frames and the workspace box of the knife tip (plate frame).

* The **base pose** ``T`` (4×4) is the arm's model world frame (the torso frame of
  ``robot.superlimb``) expressed in the plate frame: ``p_plate = R·p_model + t``, so
  ``p_model = Rᵀ·(p_plate − t)``. :data:`DEFAULT_BASE_POSE` is the fixed mount used when
  no torso motion is given: the plate's centre 0.22 m in front of the torso origin and
  0.12 m to the wearer's right (the arm's side), at the torso origin's height, axes
  aligned (plate x away from the wearer = torso x forward, z up). With it the knife
  positions of the demonstrations lie near the middle of the arm's joint ranges.
* The **workspace box** (plate frame) bounds the integrated tip reference:
  x ∈ [−0.10, 0.30], y ∈ [−0.25, 0.20], z ∈ [−0.03, 0.25] m by default — the plate
  (radius ≈ 0.12 m) with a margin, from 3 cm below its surface (a knife pressing into
  food) to 25 cm above it.

What the arm itself can reach (the reach shell, in the model frame) is the robot's
knowledge: :class:`robot.kinematics.ReachShell`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mpcshare.errors import ControllerSetupError

__all__ = ["DEFAULT_BASE_POSE", "DEFAULT_WORKSPACE", "WorkspaceBox", "check_base_pose"]

DEFAULT_BASE_POSE = np.eye(4)
DEFAULT_BASE_POSE[:3, 3] = (-0.22, 0.12, 0.0)
DEFAULT_BASE_POSE.setflags(write=False)


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


def check_base_pose(T: object) -> np.ndarray:
    """The (4, 4) float array of a valid homogeneous transform, else ValueError saying why."""
    a = np.asarray(T, dtype=float)
    if a.shape != (4, 4):
        raise ValueError(f"base_pose must be a (4, 4) homogeneous transform, got shape {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError("base_pose has non-finite entries")
    R = a[:3, :3]
    if np.abs(R.T @ R - np.eye(3)).max() > 1e-6 or abs(np.linalg.det(R) - 1.0) > 1e-6 \
            or np.abs(a[3] - (0.0, 0.0, 0.0, 1.0)).max() > 1e-12:
        raise ValueError("base_pose is not a rigid transform (rotation not orthonormal or last row not 0 0 0 1)")
    return a
