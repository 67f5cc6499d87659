"""How close the knife came to the wearer: keep-out figures of one episode (``comparison.json`` keys).

Per control step k the body zones (:func:`robot.wearer_body.body_zones`: hand, forearm, head, torso, without the
controller's margin) are placed with the fork pose the scene showed (``Episode.fork_pose``) and the base pose;
the knife is the segment from its tip to the blade's heel (``Episode.knife_heel``). With c_k,z the clearance
[m] (surface distance, negative inside) of the blade to zone z, n its normal (zone → knife) and ṗ_b the
knife's own velocity at the closest blade point (backward difference):

* ``keepout_min_clearance_m`` = min_k,z c_k,z;  ``keepout_max_depth_m`` = max(0, −that);
* ``keepout_time_inside_s`` = Δ·#{k: min_z c_k,z < 0};
* ``keepout_steps_driven_in`` = #{k: some zone with c < 0 and −n·ṗ_b > 0.05 m/s};
* ``keepout_inside_zone_moving_s`` = Δ·#{inside steps where the zone comes toward the knife faster than the
  knife toward the zone} (the person's own sweep outran the arm);
* ``keepout_near_speed_mps`` = max of the knife's own speed toward a zone over steps with c < ``near_m``
  (0.05 m); 0 when never near;
* ``keepout_min_clearance_by_zone_m``: zone → min_k c_k,z;
* ``knife_min_height_m`` = min_k min(tip_k,z, heel_k,z) above the plate's top (negative: into the plate, whose
  top the controller keeps as its floor, ``ControllerConfig.floor_z``).
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np

from robot.keepout import segment_zone_clearances
from robot.wearer_body import BODY_PARTS, WearerBody, body_zone_axes
from sim.episode import Episode
from sim.task import EATING

__all__ = ["KEEPOUT_KEYS", "episode_keepout_metrics"]

KEEPOUT_KEYS = ("keepout_min_clearance_m", "keepout_max_depth_m", "keepout_time_inside_s",
                "keepout_steps_driven_in", "keepout_inside_zone_moving_s", "keepout_near_speed_mps",
                "keepout_min_clearance_by_zone_m", "knife_min_height_m")
DRIVEN_SPEED = 0.05  # [m/s] inside and moving toward the zone faster than this = driven in


def _body(info: dict[str, Any]) -> WearerBody:
    raw = info.get("body_zones")
    if not raw:
        return EATING.body
    fields = json.loads(str(raw))
    fields.pop("blade_length", None)
    return WearerBody(**{k: tuple(v) if isinstance(v, list) else v for k, v in fields.items()})


def _clearances(episode: Episode, body: WearerBody) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(c, own, zone_in), each (Nc, 4) over :data:`BODY_PARTS` (NaN where a zone is absent), every step at once.

    own_k = −n·ṗ_b with ṗ_b the backward difference of the closest blade point (needs step k − 1's tip);
    zone_in_k = n·(a_k − a_k')/Δ, k' the zone's last earlier step with a finite blade."""
    n, dt = episode.t.size, float(episode.info.get("control_period_s", 0.01))
    c, own, zin = (np.full((n, len(BODY_PARTS)), np.nan) for _ in range(3))
    tip, heel = np.asarray(episode.tip, dtype=float), np.asarray(episode.knife_heel, dtype=float)
    blade = np.isfinite(tip).all(axis=1) & np.isfinite(heel).all(axis=1)
    prev_tip = np.zeros(n, dtype=bool)
    prev_tip[1:] = np.isfinite(tip[:-1]).all(axis=1)
    d_tip, d_heel = np.full_like(tip, np.nan), np.full_like(heel, np.nan)
    d_tip[1:], d_heel[1:] = tip[1:] - tip[:-1], heel[1:] - heel[:-1]
    axes = body_zone_axes(body, episode.fork_pose[:n], episode.base_pose[:n])
    for j, name in enumerate(BODY_PARTS):
        a, b, radius = axes[name]
        rows = np.flatnonzero(blade & np.isfinite(a).all(axis=1) & np.isfinite(b).all(axis=1))
        if not rows.size:
            continue
        dist, s, normal = segment_zone_clearances(tip[rows], heel[rows], a[rows], b[rows], radius)
        c[rows, j] = dist
        moved = prev_tip[rows]
        vb = ((1 - s)[:, None] * d_tip[rows] + s[:, None] * d_heel[rows]) / dt
        own[rows[moved], j] = -_dots(normal, vb)[moved]
        last = np.concatenate([[-1], rows[:-1]])  # the zone's previous step with a finite blade
        seen = moved & (last >= 0)
        a_rows = a[rows]
        step = np.where(seen[:, None], a_rows - a[np.maximum(last, 0)], np.nan)
        zin[rows[seen], j] = (_dots(normal, step) / dt)[seen]
    return c, own, zin


def _dots(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    return x[:, 0] * y[:, 0] + x[:, 1] * y[:, 1] + x[:, 2] * y[:, 2]


def episode_keepout_metrics(episode: Episode, near_m: float = 0.05) -> dict[str, Any]:
    """The keep-out figures of ``episode`` (module docstring); None where the run file has no
    fork pose or knife heel (an older run file)."""
    if episode.fork_pose is None or episode.knife_heel is None or episode.t.size == 0:
        return {k: None for k in KEEPOUT_KEYS}
    dt = float(episode.info.get("control_period_s", 0.01))
    c, own, zin = _clearances(episode, _body(episode.info))
    with np.errstate(invalid="ignore"):
        inside = c < 0.0
        driven = inside & (own > DRIVEN_SPEED)
        moving = inside & (zin > np.nan_to_num(own, nan=0.0))
        near = c < near_m
    seen = np.isfinite(c)  # a lost sample's row is all NaN: its minimum is NaN, not a warning
    cmin = np.where(seen.any(axis=1), np.min(np.where(seen, c, np.inf), axis=1), np.nan)
    finite = np.isfinite(cmin)
    min_c = float(np.min(cmin[finite])) if finite.any() else None
    near_own = own[near & np.isfinite(own)]
    return {
        "keepout_min_clearance_m": min_c,
        "keepout_max_depth_m": max(0.0, -min_c) if min_c is not None else None,
        "keepout_time_inside_s": float(inside.any(axis=1).sum() * dt),
        "keepout_steps_driven_in": int(driven.any(axis=1).sum()),
        "keepout_inside_zone_moving_s": float(moving.any(axis=1).sum() * dt),
        "keepout_near_speed_mps": float(max(0.0, near_own.max())) if near_own.size else 0.0,
        "keepout_min_clearance_by_zone_m": {name: (float(np.nanmin(c[:, j])) if np.isfinite(c[:, j]).any() else None)
                                            for j, name in enumerate(BODY_PARTS)},
        "knife_min_height_m": _lowest(episode),
    }


def _lowest(episode: Episode) -> float | None:
    """The blade's lowest z [m] (plate frame) over the episode: tip or heel (module docstring)."""
    z = np.concatenate([episode.tip[:, 2], episode.knife_heel[:, 2]])
    z = z[np.isfinite(z)]
    return float(z.min()) if z.size else None
