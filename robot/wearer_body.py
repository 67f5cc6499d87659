"""The wearer's body as keep-out zones: the fork hand, the forearm, the head and the torso.

Frames as in :mod:`sim.scene`: the *torso* frame is the arm's model world frame (the
SuperLimb is worn on it), the *plate* frame is the data's frame; ``T_plate_torso`` (4×4,
``p_plate = R·p_torso + t``) is the controller's base pose. The fork pose is
(x, y, z [m], roll, pitch, yaw [rad]) of the fork tip in the plate frame (ZYX, URDF).

* **hand** — a sphere at the fork handle's upper end (the fist around the handle), fixed
  in the fork frame, moving with the fork;
* **forearm** — a capsule from the hand toward the elbow: the elbow is held at a fixed
  point of the torso frame (the upper arm hangs from the shoulder beside the trunk), the
  forearm runs ``forearm_length`` from the hand toward it;
* **head** (with the face) — a sphere fixed to the torso;
* **torso** — a capsule fixed to the torso.

The sizes, anchors and speed caps are the task's (:class:`WearerBody` has no defaults; the
task shipped gives them, ``sim.task.eating.BODY``). A lost fork marker gives the hand and forearm an
uncertainty of the hand's top speed times the marker's age (:class:`robot.keepout.Zone`).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any, Sequence

import numpy as np

from .keepout import Zone
from .superlimb import rpy_to_matrix

__all__ = ["BODY_PARTS", "WearerBody", "body_zone_axes", "body_zones", "hand_center", "zones_to_plate"]

BODY_PARTS: tuple[str, ...] = ("hand", "forearm", "head", "torso")

Vec3 = tuple[float, float, float]


@dataclass(frozen=True)
class WearerBody:
    """Sizes [m], anchors [m] and speed caps [m/s] of the body zones (module docstring).

    hand_offset: the hand's centre in the fork frame (the handle's upper end);
    elbow: the elbow in the torso frame; head_center, torso_a, torso_b: torso frame;
    hand_top_speed [m/s]: growth rate of the hand and forearm zones while the fork
    marker is lost.
    """

    hand_offset: Vec3
    hand_radius: float
    elbow: Vec3
    forearm_length: float
    forearm_radius: float
    head_center: Vec3
    head_radius: float
    torso_a: Vec3
    torso_b: Vec3
    torso_radius: float
    hand_speed_cap: float
    head_speed_cap: float
    hand_top_speed: float

    def __post_init__(self) -> None:
        for name in ("hand_radius", "forearm_length", "forearm_radius", "head_radius", "torso_radius",
                     "hand_speed_cap", "head_speed_cap", "hand_top_speed"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v >= 0):
                raise ValueError(f"WearerBody.{name} must be finite and >= 0, got {v!r}")

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


def hand_center(body: WearerBody, fork_pose: np.ndarray) -> np.ndarray:
    """The hand's centre [m] in the frame of ``fork_pose`` (6,) (x, y, z, roll, pitch, yaw)."""
    return fork_pose[:3] + rpy_to_matrix(fork_pose[3:6]) @ np.asarray(body.hand_offset)


def _hand_velocity(body: WearerBody, fork_pose: np.ndarray, fork_rate: np.ndarray, hand: np.ndarray) -> np.ndarray:
    """d/dt of :func:`hand_center` (= ``hand``) for the pose's time derivative ``fork_rate`` (6,):
    a forward difference over 1 ms (the rotation's curvature over it is far below the rate's noise)."""
    eps = 1e-3
    return (hand_center(body, fork_pose + eps * fork_rate) - hand) / eps


def body_zones(body: WearerBody, fork_pose: np.ndarray | None, base_pose: np.ndarray,
               fork_rate: np.ndarray | None = None, marker_age_s: float = 0.0,
               parts: Sequence[str] = BODY_PARTS) -> list[Zone]:
    """The zones of ``parts`` in the **torso** frame.

    ``fork_pose`` (6,) plate frame (None or non-finite: no hand or forearm zone);
    ``base_pose`` 4×4 T_plate_torso; ``fork_rate`` (6,) its time derivative [m/s, rad/s]
    (the hand's velocity; None: at rest); ``marker_age_s`` [s] since the fork was last
    measured: the hand and forearm get an uncertainty of ``hand_top_speed·marker_age_s`` growing at
    ``hand_top_speed`` (:class:`robot.keepout.Zone`).
    """
    R, t = base_pose[:3, :3], base_pose[:3, 3]
    zones: list[Zone] = []
    zero = np.zeros(3)
    hand_ok = fork_pose is not None and np.isfinite(fork_pose).all()
    age = max(0.0, float(marker_age_s))
    grow, rate = body.hand_top_speed * age, (body.hand_top_speed if age > 0.0 else 0.0)
    if hand_ok and ("hand" in parts or "forearm" in parts):
        hand_plate = hand_center(body, fork_pose)
        hand = R.T @ (hand_plate - t)
        rate_ok = fork_rate is not None and np.isfinite(fork_rate).all()
        vel = R.T @ _hand_velocity(body, fork_pose, fork_rate, hand_plate) if rate_ok else zero
        if "hand" in parts:
            zones.append(Zone("hand", hand, hand, body.hand_radius, vel, body.hand_speed_cap, grow, rate))
        if "forearm" in parts:
            to_elbow = np.asarray(body.elbow) - hand
            dist = float(np.linalg.norm(to_elbow))
            end = hand + to_elbow * (min(1.0, body.forearm_length / dist) if dist > 1e-9 else 0.0)
            zones.append(Zone("forearm", hand, end, body.forearm_radius, vel, body.hand_speed_cap, grow, rate))
    if "head" in parts:
        c = np.asarray(body.head_center, dtype=float)
        zones.append(Zone("head", c, c, body.head_radius, zero, body.head_speed_cap))
    if "torso" in parts:
        zones.append(Zone("torso", np.asarray(body.torso_a, dtype=float), np.asarray(body.torso_b, dtype=float),
                          body.torso_radius, zero, body.hand_speed_cap))
    return zones


def zones_to_plate(zones: Sequence[Zone], base_pose: np.ndarray) -> list[Zone]:
    """The same zones in the plate frame (``p_plate = R·p + t``, velocities rotated)."""
    R, t = base_pose[:3, :3], base_pose[:3, 3]
    return [z._replace(a=R @ z.a + t, b=R @ z.b + t, velocity=R @ z.velocity) for z in zones]


def body_zone_axes(body: WearerBody, fork_poses: np.ndarray, base_poses: np.ndarray
                   ) -> dict[str, tuple[np.ndarray, np.ndarray, float]]:
    """The zones of :func:`body_zones` (at rest, no uncertainty) placed by :func:`zones_to_plate`, for N
    steps at once: ``fork_poses`` (N, 6) plate frame, ``base_poses`` (N, 4, 4) T_plate_torso. Returns
    part → (a (N, 3), b (N, 3) [m] in the plate frame, radius [m]); the hand and forearm rows are NaN
    where the fork pose is not finite."""
    fork, base = np.asarray(fork_poses, dtype=float), np.asarray(base_poses, dtype=float)
    R, t = base[:, :3, :3], base[:, :3, 3]

    def to_plate(p: np.ndarray) -> np.ndarray:
        return np.einsum("kij,kj->ki", R, p) + t

    roll, pitch, yaw = (fork[:, i] for i in (3, 4, 5))
    cr, sr, cp, sp, cy, sy = np.cos(roll), np.sin(roll), np.cos(pitch), np.sin(pitch), np.cos(yaw), np.sin(yaw)
    Rf = np.stack([np.stack([cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr], axis=-1),
                   np.stack([sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr], axis=-1),
                   np.stack([-sp, cp * sr, cp * cr], axis=-1)], axis=1)  # rpy_to_matrix per row
    hand_plate = fork[:, :3] + np.einsum("kij,j->ki", Rf, np.asarray(body.hand_offset, dtype=float))
    hand = np.einsum("kji,kj->ki", R, hand_plate - t)  # torso frame: R.T·(p − t)
    hand[~np.isfinite(fork).all(axis=1)] = np.nan
    to_elbow = np.asarray(body.elbow, dtype=float) - hand
    dist = np.sqrt(np.sum(to_elbow * to_elbow, axis=1))
    with np.errstate(divide="ignore", invalid="ignore"):
        scale = np.where(dist > 1e-9, np.minimum(1.0, body.forearm_length / dist), 0.0)
    end = hand + to_elbow * scale[:, None]
    head = np.broadcast_to(np.asarray(body.head_center, dtype=float), hand.shape)
    torso_a = np.broadcast_to(np.asarray(body.torso_a, dtype=float), hand.shape)
    torso_b = np.broadcast_to(np.asarray(body.torso_b, dtype=float), hand.shape)
    hand_p, head_p = to_plate(hand), to_plate(head)
    return {"hand": (hand_p, hand_p, body.hand_radius), "forearm": (hand_p, to_plate(end), body.forearm_radius),
            "head": (head_p, head_p, body.head_radius), "torso": (to_plate(torso_a), to_plate(torso_b),
                                                                  body.torso_radius)}
