"""A hard floor for the knife: the blade stays above a plane (the plate's top) as QP rows.

The knife's tip and heel (:class:`robot.keepout.Blade`) must stay on the upper side of the
plane n·p ≥ c (n unit, model frame; set every step with :meth:`FloorLimit.set_plane`, since the
plane moves in the arm's frame with the torso). A half-space is convex, so the blade segment is
above it when both ends are. For each end point with height d = n·p − c [m] and approach speed
s = −n·v [m/s] (downward), one row ``G·a ≤ h`` bounds the approach speed after the step,
s⁺ = s − dt·n·(J·a + J̇·v):

    s⁺ ≤ u,   u = u_A(d, s)                      d ≥ 0  (the viable bound of
                                                        :func:`robot.constraints.viable_velocity_bound`:
                                                        the point can still stop braking at A)
              u = max(d/T_r, −v_rec)             d < 0  (below: rise at most at v_rec)
    and u ≥ s − A·dt                                    (never more than braking at A asks: the
                                                        row stays feasible where A is)

so the floor holds in the physics as long as the arm can brake its tip at A [m/s²] upward. The
floor is a wall of the world (the table), not a person: it ranks with the joint limits, above
tracking and above the keep-out's soft retreat (:func:`robot.keepout.retreat` keeps it hard).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

from .constraints import Constraint, _viable_bound_scalar
from .errors import ControllerConfigError
from .keepout import Blade
from .state import ControlState

__all__ = ["FloorConfig", "FloorLimit"]


@dataclass(frozen=True)
class FloorConfig:
    """brake_acceleration A [m/s²] (well inside what the arm gives at the plate), reaction_time_s T_r [s]
    and recover_speed v_rec [m/s] of the climb back when below the plane."""

    brake_acceleration: float = 1.0
    reaction_time_s: float = 0.1
    recover_speed: float = 0.05

    def __post_init__(self) -> None:
        for name in ("brake_acceleration", "reaction_time_s", "recover_speed"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0):
                raise ControllerConfigError(f"FloorConfig.{name} must be finite and > 0, got {v!r}")


class FloorLimit:
    """Floor rows ``G·a ≤ h`` (module docstring) on the blade of any Pinocchio model and tool frame;
    ``heel_offset`` (3,) [m] the heel in the tool frame. No plane set: rows ``0·a ≤ 1e6``."""

    name = "floor"

    def __init__(self, model, frame: str | int, heel_offset: Sequence[float],
                 config: FloorConfig | None = None) -> None:
        self.config = config or FloorConfig()
        self.blade = Blade(model, frame, heel_offset)
        self.normal: np.ndarray | None = None
        self.offset = 0.0
        self.heights = np.full(2, np.nan)  # (tip, heel) heights d [m] above the plane at the last rows

    def num_rows(self, n: int) -> int:
        return 2

    def set_plane(self, normal: Sequence[float], offset: float) -> None:
        """The floor n·p ≥ ``offset`` [m] (model frame); ``normal`` (3,) is normalised."""
        n = np.asarray(normal, dtype=float)
        norm = math.sqrt(float(n.dot(n))) if n.shape == (3,) else 0.0  # np.linalg.norm's own sum, one call
        if not (norm > 1e-9 and math.isfinite(norm) and math.isfinite(float(offset))):
            raise ControllerConfigError(f"floor plane needs a finite non-zero (3,) normal and a finite offset, "
                                        f"got {normal!r}, {offset!r}")
        self.normal, self.offset = n / norm, float(offset)

    def compute_qp_inequalities(self, state: ControlState) -> Constraint:
        cfg, dt = self.config, state.dt
        G, h = np.zeros((2, state.q.size)), np.array([1e6, 1e6])
        n = self.normal
        if n is not None:
            for i, pt in enumerate(self.blade.knife(state.q, state.v)):
                d = float(n @ pt.p) - self.offset
                nv = float(n @ pt.v)
                s = -nv
                own = nv + dt * float(n @ pt.drift)  # −(approach speed after a = 0)
                if d >= 0.0:
                    u = _viable_bound_scalar(d, s, dt, cfg.brake_acceleration)
                else:
                    u = max(d / cfg.reaction_time_s, -cfg.recover_speed)
                u = max(u, s - cfg.brake_acceleration * dt)
                G[i], h[i] = -dt * (n @ pt.J), u + own
                self.heights[i] = d
        G.flags.writeable = False
        h.flags.writeable = False
        return Constraint(G, h)
