"""The wearer's shoulder as a command channel: shoulder angles → knife-tip velocity.

The voluntary channel is the wearer's affected-side shoulder (elevation,
protraction, abduction) [rad], measured relative to a neutral posture. Used as a
rate command (like a joystick), as in Song & Asada's voluntary channel:

    û_v = g · P · dz(θ)        [m/s]

with ``dz`` a dead zone of half-width ``deadband_rad`` that is continuous at its
edge (dz(θ) = sign(θ)·max(|θ| − δ, 0)), ``P`` (3, n) the fixed map from the n
measured angles to the plate axes (the task's layout: ``sim.task.eating.SHOULDER_TO_PLATE``), and
``g`` the per-user gain [m/s per rad]. The controller uses
:meth:`ShoulderMap.tip_velocity`; a simulated wearer who wants a tip velocity uses
the inverse :meth:`ShoulderMap.angles_for`.

A sensor may measure 1, 2 or 3 of the angles (or more channels, of which only those
named by a role command the knife): :meth:`ShoulderMap.for_channels` builds P from the
channel names, one column per channel, the column of its role in the task's layout or zero.
With fewer than three angles the wearer commands only the plate axes they map to.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

__all__ = ["ShoulderMap"]


@dataclass(frozen=True)
class ShoulderMap:
    """Shoulder angles [rad] → tip velocity [m/s] (module docstring).

    Attributes:
        matrix: P (3, n), plate axes × shoulder channels; read-only. Its non-zero columns are
            linearly independent (a zero column: a channel that commands nothing).
        gain: g [m/s per rad] (> 0).
        deadband_rad: δ [rad] (≥ 0): angles within ±δ command nothing.
    """

    matrix: np.ndarray
    gain: float = 0.5
    deadband_rad: float = 0.01

    def __post_init__(self) -> None:
        if not (np.isfinite(self.gain) and self.gain > 0):
            raise ValueError(f"ShoulderMap.gain must be finite and > 0, got {self.gain!r}")
        if not (np.isfinite(self.deadband_rad) and self.deadband_rad >= 0):
            raise ValueError(f"ShoulderMap.deadband_rad must be finite and >= 0, got {self.deadband_rad!r}")
        m = np.array(self.matrix, dtype=float)
        if m.ndim != 2 or m.shape[0] != 3 or m.shape[1] < 1 or not np.all(np.isfinite(m)):
            raise ValueError(f"ShoulderMap.matrix must be a finite (3, n) array, n >= 1, got shape {m.shape}")
        used = m[:, np.abs(m).sum(axis=0) > 0]
        if used.shape[1] == 0 or np.linalg.svd(used, compute_uv=False).min() < 1e-9:
            raise ValueError("ShoulderMap.matrix must have linearly independent non-zero columns")
        m.setflags(write=False)
        object.__setattr__(self, "matrix", m)

    @classmethod
    def for_channels(cls, names: Sequence[str], roles: Sequence[str], layout: np.ndarray, gain: float = 0.5,
                     deadband_rad: float = 0.01) -> ShoulderMap:
        """The map of a sensor whose channels are ``names`` (module docstring), in a task's layout:
        ``roles`` name the columns of ``layout`` (3, len(roles)).

        No names: the channels ``roles``, P = ``layout``. Where some names are roles, those channels
        take their role's column of ``layout`` and the others a zero column; where none is, the channels
        (at most len(roles)) take the roles in order. Raises ValueError for a repeated name, for more
        channels than roles none of which is named by a role, or for a layout of another shape.
        """
        roles = tuple(str(r) for r in roles)
        layout = np.asarray(layout, dtype=float)
        if layout.shape != (3, len(roles)):
            raise ValueError(f"the shoulder layout has shape {layout.shape}, its roles {roles} need (3, {len(roles)})")
        names = [str(n) for n in names]
        if not names:
            return cls(layout, gain, deadband_rad)
        if len(set(names)) != len(names):
            raise ValueError(f"the shoulder channels {names} repeat a name")
        named = [n for n in names if n in roles]
        if not named and len(names) > len(roles):
            raise ValueError(f"{len(names)} shoulder channels {names} and none named by its role: the shoulder map "
                             f"takes at most {len(roles)} by position; name those that command the knife "
                             f"({', '.join(roles)})")
        m = np.zeros((3, len(names)))
        for j, name in enumerate(names):
            if not named:
                m[:, j] = layout[:, j]
            elif name in roles:
                m[:, j] = layout[:, roles.index(name)]
        return cls(m, gain, deadband_rad)

    @property
    def n_channels(self) -> int:
        """n: the shoulder channels (angles) the map reads."""
        return int(self.matrix.shape[1])

    @property
    def invertible(self) -> bool:
        """True for a (3, 3) P without a zero column: P⁻¹ exists."""
        return self.matrix.shape == (3, 3) and bool(np.all(np.abs(self.matrix).sum(axis=0) > 0))

    def inverse(self) -> np.ndarray:
        """(n, 3) P⁻¹ (:attr:`invertible`) or the pseudo-inverse P⁺: tip velocity / g → the least-squares
        angles (zero for a channel of a zero column)."""
        return np.linalg.inv(self.matrix) if self.invertible else np.linalg.pinv(self.matrix)

    def tip_velocity(self, theta: np.ndarray) -> np.ndarray:
        """û_v = g · P · dz(θ) [m/s] for shoulder angles θ (n,) [rad]."""
        th = np.asarray(theta, dtype=float)
        if th.shape != (self.n_channels,):
            raise ValueError(f"shoulder angles must have shape ({self.n_channels},), got {th.shape}")
        dz = np.sign(th) * np.maximum(np.abs(th) - self.deadband_rad, 0.0)
        return self.gain * (self.matrix @ dz)

    def angles_for(self, tip_velocity: np.ndarray) -> np.ndarray:
        """The smallest-magnitude θ (n,) whose command is ``tip_velocity`` (inverse of the dead zone); with
        fewer than three angles, the command nearest to ``tip_velocity`` (least squares)."""
        u = np.asarray(tip_velocity, dtype=float)
        if u.shape != (3,):
            raise ValueError(f"tip velocity must have shape (3,), got {u.shape}")
        m = self.matrix
        dz = np.linalg.solve(m, u / self.gain) if self.invertible else np.linalg.pinv(m) @ (u / self.gain)
        return np.where(dz == 0.0, 0.0, dz + np.sign(dz) * self.deadband_rad)
