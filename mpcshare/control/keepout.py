"""The person first: the controller's keep-out (docs/design.md, "The person first").

Every step :meth:`KeepOut.update` turns the fork measurement into the wearer's body
zones (:mod:`robot.wearer_body`: hand at the fork handle's upper end, forearm, head,
torso), moves them into the arm's model frame with the base pose and hands them to the
QP's :class:`robot.keepout.KeepOutLimit` (barrier and speed-and-separation rows on the
knife's tip–heel segment). The hand's velocity is the front end's Kalman velocity of the
fork pose; while the marker is lost the zone stays where it was last measured and grows
by the hand's top speed times the marker's age, where the knife comes to a protective stop
rather than flee (fault ``keepout_stale_zone``).

After the QP, :meth:`KeepOut.check` makes keep-out rank above tracking:

* the QP failed (its brake ignores the zones) or its answer breaks a keep-out row →
  :func:`robot.keepout.retreat`, the safest feasible action (fault ``keepout_retreat``);
* the knife is inside a zone's margin: whose doing is it? If the knife moves toward the zone
  faster than ``driven_speed`` (0.05 m/s), both on its own and relative to the zone, it was
  driven in (``keepout_robot``: never expected, the rows forbid it); else, if the zone comes
  toward the knife, the person moved onto it (``keepout_person``); a knife sliding along the
  margin of a zone that moves away is neither.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Sequence

import numpy as np

from robot.keepout import BLADE_LENGTH, KeepOutConfig, KeepOutLimit, retreat
from robot.qp import QPController, QPResult, QPStatus
from robot.wearer_body import BODY_PARTS, WearerBody, body_zones

__all__ = ["FORK_POSE_CHANNELS", "KeepOut", "KeepOutSettings"]

FORK_POSE_CHANNELS = ("fork_x", "fork_y", "fork_z", "fork_roll", "fork_pitch", "fork_yaw")


@dataclass(frozen=True)
class KeepOutSettings:
    """The controller's keep-out: the body (None: the body zones of the task the bundle was trained for, set by
    :func:`mpcshare.control.builder.build_parts`), the rows' settings, the knife's heel offset in the
    tool frame [m] (the SuperLimb's blade: 9 cm back along the tool x axis), the parts kept out,
    and ``driven_speed`` [m/s]: a knife inside a margin moving toward the zone faster than this
    was driven in; ``mpc_zones``: the MPC (when on) also holds the zones
    over its horizon, moving with the hand's forecast (:class:`robot.mpc.keepout_mpc.KeepOutTipMPC`)."""

    body: WearerBody | None = None
    limit: KeepOutConfig = field(default_factory=KeepOutConfig)
    heel_offset: tuple[float, float, float] = (-BLADE_LENGTH, 0.0, 0.0)
    parts: tuple[str, ...] = BODY_PARTS
    driven_speed: float = 0.05
    mpc_zones: bool = True

    def __post_init__(self) -> None:
        bad = [p for p in self.parts if p not in BODY_PARTS]
        if bad:
            raise ValueError(f"KeepOutSettings.parts {bad} unknown; valid choices: {list(BODY_PARTS)}")
        if len(self.parts) > self.limit.max_zones:
            raise ValueError(f"{len(self.parts)} parts need KeepOutConfig.max_zones >= {len(self.parts)}")


class KeepOut:
    """Zones per step and the check after the QP (module docstring)."""

    def __init__(self, settings: KeepOutSettings, limit: KeepOutLimit) -> None:
        if settings.body is None:
            raise ValueError("KeepOut needs KeepOutSettings.body (the controller's builder sets the body of the "
                             "bundle's task)")
        self.settings, self.limit = settings, limit
        self._cols: np.ndarray | None = None
        self.reset()

    def bind(self, obs_names: Sequence[str]) -> None:
        """Find the fork pose channels in the observation (orientation optional: level fork if absent)."""
        names = list(obs_names)
        missing = [c for c in FORK_POSE_CHANNELS[:3] if c not in names]
        if missing:
            raise ValueError(f"keep-out needs the fork position channels {missing} in the observation {names}")
        self._cols = np.array([names.index(c) if c in names else -1 for c in FORK_POSE_CHANNELS])

    def reset(self) -> None:
        self._pose: np.ndarray | None = None  # last measured fork pose (plate frame)
        self._t_seen = 0.0  # when it was measured [s]
        self.age_s = 0.0

    def _fork(self, obs: object, fork_velocity: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None]:
        cols = self._cols
        o = np.asarray(obs, dtype=float).reshape(-1) if obs is not None else None
        if cols is None or o is None or o.size <= int(cols.max()):
            return None, None
        take = np.where(cols >= 0, cols, 0)
        pose = np.where(cols >= 0, o[take], 0.0)
        rate = np.where(cols >= 0, fork_velocity[take], 0.0) if fork_velocity.size > int(cols.max()) else None
        return (pose, rate) if np.isfinite(pose).all() else (None, None)

    def update(self, t: float, obs: object, fork_velocity: np.ndarray, repeated: bool, base_pose: np.ndarray,
               faults: list[tuple[str, str]]) -> None:
        """The zones of this step at time t [s] from the raw sample ``obs`` (its fork pose counts as
        measured when finite and not a ``repeated`` (frozen) sample), the fork's Kalman velocity and
        the base pose (T_plate_torso)."""
        pose, rate = (None, None) if repeated else self._fork(obs, fork_velocity)
        if pose is not None:
            self._pose, self._t_seen, self.age_s = pose, float(t), 0.0
        else:
            rate = None
            self.age_s = max(0.0, float(t) - self._t_seen) if self._pose is not None else 0.0
            if self._pose is not None:
                grow = self.settings.body.hand_top_speed * self.age_s
                faults.append(("keepout_stale_zone", f"fork marker {self.age_s:.2f} s old: hand and forearm "
                                                     f"uncertain by {grow * 1e3:.0f} mm (protective stop there)"))
        zones = body_zones(self.settings.body, self._pose, base_pose, rate, self.age_s, self.settings.parts)
        self.limit.set_zones(zones)

    def check(self, qp: QPController, q: np.ndarray, v: np.ndarray, res: QPResult,
              faults: list[tuple[str, str]]) -> QPResult:
        """Keep-out above tracking (module docstring): the QP's answer, or the retreat."""
        if not self.limit.zones or res.status is QPStatus.INVALID_STATE:
            return res
        self._attribute(faults)
        failed = res.status is QPStatus.SOLVER_FAILED
        if not failed and self._holds(qp, q, v, res):
            return res
        rows = self.limit.rows
        if failed and (rows is None or not (rows.h < 1e5).any()):
            return res  # no zone near: the QP's brake is the stop
        if failed:
            faults.append(("qp_failed", f"{res.reason}; a zone is near: the keep-out's retreat instead"))
        act = retreat(qp, self.limit, q, v)
        if act is None:
            faults.append(("keepout_retreat", "keep-out and limits cannot be met: braking (the QP's brake)"))
            return res
        dt = qp.dt
        faults.append(("keepout_retreat", f"keep-out rows infeasible ({res.status.value}): retreat, "
                                          f"largest shortfall {act.slack:.3g} m/s"))
        return QPResult(act.a, act.tau, v + act.a * dt, q + (v + 0.5 * dt * act.a) * dt, QPStatus.RELAXED,
                        "keep-out retreat", res.tip_error, res.slack, res.manipulability, res.iterations,
                        res.solve_time)

    def _holds(self, qp: QPController, q: np.ndarray, v: np.ndarray, res: QPResult) -> bool:
        """True when the answer meets the keep-out rows of this state (to 1e-6 m/s)."""
        rows = self.limit.rows
        if rows is None:
            return True
        G, h = rows
        return bool((G @ res.a <= h + 1e-6).all())

    def _attribute(self, faults: list[tuple[str, str]]) -> None:
        """Say whose doing a knife inside a zone's margin is (module docstring)."""
        margin = self.settings.limit.margin
        for z, c, own in zip(self.limit.zones, self.limit.clearances, self.limit.approach):
            if c.distance >= margin:
                continue
            zone_in = float(c.normal @ z.velocity)
            depth = (margin - c.distance) * 1e3
            if own > self.settings.driven_speed and own + zone_in > self.settings.driven_speed:
                faults.append(("keepout_robot", f"knife moving into the {z.name} at {own:.3f} m/s (relative "
                                                f"{own + zone_in:.3f} m/s), {depth:.0f} mm into its margin"))
            elif zone_in > 0.0:
                faults.append(("keepout_person", f"{z.name} {depth:.0f} mm into its margin, knife's own approach "
                                                 f"{own:.3f} m/s, {z.name} approaching at {zone_in:.3f} m/s"))
