"""The wearer's shoulder as a command channel: shoulder angles → knife-tip velocity.

The voluntary channel is the wearer's affected-side shoulder (elevation,
protraction, abduction) [rad], measured relative to a neutral posture. Used as a
rate command (like a joystick), as in Song & Asada's voluntary channel:

    û_v = g · P · dz(θ)        [m/s]

with ``dz`` a dead zone of half-width ``deadband_rad`` that is continuous at its
edge (dz(θ) = sign(θ)·max(|θ| − δ, 0)), ``P`` the fixed map from the three angles
to the plate axes (elevation → z up, protraction → x away from the wearer,
abduction → y), and ``g`` the per-user gain [m/s per rad]. The controller uses
:meth:`ShoulderMap.tip_velocity`; a simulated wearer who wants a tip velocity uses
the inverse :meth:`ShoulderMap.angles_for`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["ShoulderMap", "SHOULDER_TO_PLATE"]

#: rows: plate x, y, z; columns: elevation, protraction, abduction.
SHOULDER_TO_PLATE = np.array([[0.0, 1.0, 0.0],
                              [0.0, 0.0, 1.0],
                              [1.0, 0.0, 0.0]])
SHOULDER_TO_PLATE.setflags(write=False)


@dataclass(frozen=True)
class ShoulderMap:
    """Shoulder angles [rad] → tip velocity [m/s] (module docstring).

    Attributes:
        gain: g [m/s per rad] (> 0).
        deadband_rad: δ [rad] (≥ 0): angles within ±δ command nothing.
        matrix: P (3, 3), plate axes × shoulder angles; read-only.
    """

    gain: float = 0.5
    deadband_rad: float = 0.01
    matrix: np.ndarray = field(default_factory=lambda: SHOULDER_TO_PLATE)

    def __post_init__(self) -> None:
        if not (np.isfinite(self.gain) and self.gain > 0):
            raise ValueError(f"ShoulderMap.gain must be finite and > 0, got {self.gain!r}")
        if not (np.isfinite(self.deadband_rad) and self.deadband_rad >= 0):
            raise ValueError(f"ShoulderMap.deadband_rad must be finite and >= 0, got {self.deadband_rad!r}")
        m = np.array(self.matrix, dtype=float)
        if m.shape != (3, 3) or not np.all(np.isfinite(m)) or abs(np.linalg.det(m)) < 1e-9:
            raise ValueError("ShoulderMap.matrix must be a finite, invertible (3, 3) array")
        m.setflags(write=False)
        object.__setattr__(self, "matrix", m)

    def tip_velocity(self, theta: np.ndarray) -> np.ndarray:
        """û_v = g · P · dz(θ) [m/s] for shoulder angles θ (3,) [rad]."""
        th = np.asarray(theta, dtype=float)
        if th.shape != (3,):
            raise ValueError(f"shoulder angles must have shape (3,), got {th.shape}")
        dz = np.sign(th) * np.maximum(np.abs(th) - self.deadband_rad, 0.0)
        return self.gain * (self.matrix @ dz)

    def angles_for(self, tip_velocity: np.ndarray) -> np.ndarray:
        """The smallest-magnitude θ whose command is ``tip_velocity`` (inverse of the dead zone)."""
        u = np.asarray(tip_velocity, dtype=float)
        if u.shape != (3,):
            raise ValueError(f"tip velocity must have shape (3,), got {u.shape}")
        dz = np.linalg.solve(self.matrix, u / self.gain)
        return np.where(dz == 0.0, 0.0, dz + np.sign(dz) * self.deadband_rad)
