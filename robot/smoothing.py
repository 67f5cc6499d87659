"""Jerk-limited smoothing of a jumping reference stream with ruckig.

The fused reference jumps when control passes between the robot and the
wearer.  :class:`ReferenceSmoother` keeps a state (p, ṗ, p̈) and, every cycle
dt [s], moves it one step along ruckig's time-optimal trajectory toward the
latest target, within |ṗ| ≤ v_max [m/s], |p̈| ≤ a_max [m/s²] and
|d³p/dt³| ≤ j_max [m/s³] per axis.  The target may change every cycle: ruckig
recomputes the trajectory from the current state each time (online).

Odd inputs never raise in the loop:

* non-finite target → the last valid target is kept (``invalid_target``);
* target velocity / acceleration beyond the limits → clipped (``clipped``);
* ruckig still rejects the input (e.g. an unreachable target state) → the
  target velocity and acceleration are dropped and ruckig is asked again;
  if that fails too, the state is brought to rest by ruckig's velocity
  interface, or, as the last resort, held with zero velocity (``fallback``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from enum import Enum

import numpy as np
from ruckig import ControlInterface, InputParameter, OutputParameter, Result, Ruckig

from .errors import ControllerConfigError


class SmoothingStatus(str, Enum):
    """Outcome of one :meth:`ReferenceSmoother.update`."""

    WORKING = "working"  # moving toward the target
    FINISHED = "finished"  # at the target state
    CLIPPED = "clipped"  # target velocity/acceleration clipped to the limits
    INVALID_TARGET = "invalid_target"  # non-finite target ignored, previous target kept
    FALLBACK = "fallback"  # ruckig rejected the target: braking / holding


@dataclass
class SmoothedReference:
    """Smoothed reference at the end of the cycle: position [m], velocity [m/s], acceleration [m/s²]."""

    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    status: SmoothingStatus
    reason: str = ""


def _limit(name: str, x: object, dofs: int) -> list[float]:
    arr = np.asarray(x, dtype=float)
    if arr.ndim == 0:
        arr = np.full(dofs, float(arr))
    if arr.shape != (dofs,) or not np.all(np.isfinite(arr)) or np.any(arr <= 0):
        raise ControllerConfigError(f"{name} must be positive and finite, shape ({dofs},) or scalar")
    return arr.tolist()


class ReferenceSmoother:
    """Online jerk-limited filter for a ``dofs``-dimensional reference (default: knife tip xyz).

    dt [s]; max_velocity [m/s], max_acceleration [m/s²], max_jerk [m/s³]
    (scalars or per axis).  The first :meth:`update` starts at the first
    finite target unless :meth:`reset` was called.
    """

    def __init__(self, dofs: int = 3, dt: float = 0.01, max_velocity: object = 0.3,
                 max_acceleration: object = 2.0, max_jerk: object = 30.0) -> None:
        if dofs < 1:
            raise ControllerConfigError("dofs must be ≥ 1")
        if not (np.isfinite(dt) and dt > 0):
            raise ControllerConfigError(f"dt must be > 0, got {dt}")
        self.dofs, self.dt = dofs, float(dt)
        self.v_max = np.array(_limit("max_velocity", max_velocity, dofs))
        self.a_max = np.array(_limit("max_acceleration", max_acceleration, dofs))
        self.j_max = np.array(_limit("max_jerk", max_jerk, dofs))
        self._otg = Ruckig(dofs, self.dt)
        self._inp = InputParameter(dofs)
        self._out = OutputParameter(dofs)
        for inp in (self._inp,):
            inp.max_velocity = self.v_max.tolist()
            inp.max_acceleration = self.a_max.tolist()
            inp.max_jerk = self.j_max.tolist()
        self._brake_otg = Ruckig(dofs, self.dt)
        self._brake_inp = InputParameter(dofs)
        self._brake_inp.control_interface = ControlInterface.Velocity
        self._brake_inp.max_velocity = self.v_max.tolist()
        self._brake_inp.max_acceleration = self.a_max.tolist()
        self._brake_inp.max_jerk = self.j_max.tolist()
        self._brake_inp.target_velocity = [0.0] * dofs
        self._brake_inp.target_acceleration = [0.0] * dofs
        self._brake_out = OutputParameter(dofs)
        self._zeros = [0.0] * dofs
        self._initialized = False
        self._target: tuple[list[float], list[float], list[float]] | None = None

    # ------------------------------------------------------------------
    @property
    def initialized(self) -> bool:
        return self._initialized

    def reset(self, position: object, velocity: object | None = None, acceleration: object | None = None) -> None:
        """Set the current state (e.g. the measured tip) [m], [m/s], [m/s²]; forgets the target."""
        p = np.asarray(position, dtype=float).reshape(-1)
        if p.shape != (self.dofs,) or not np.all(np.isfinite(p)):
            raise ControllerConfigError(f"reset position must be finite with shape ({self.dofs},)")
        v = np.zeros(self.dofs) if velocity is None else np.asarray(velocity, dtype=float)
        a = np.zeros(self.dofs) if acceleration is None else np.asarray(acceleration, dtype=float)
        self._inp.current_position = p.tolist()
        self._inp.current_velocity = v.tolist()
        self._inp.current_acceleration = a.tolist()
        self._target = None
        self._initialized = True

    def state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Current (position, velocity, acceleration)."""
        inp = self._inp
        return (np.array(inp.current_position), np.array(inp.current_velocity), np.array(inp.current_acceleration))

    # ------------------------------------------------------------------
    def _as_list(self, name: str, x: object | None) -> list[float]:
        if x is None:
            return self._zeros
        out = [float(e) for e in np.asarray(x, dtype=float).reshape(-1)] if isinstance(x, np.ndarray) \
            else [float(e) for e in x]  # type: ignore[union-attr]
        if len(out) != self.dofs:
            raise ControllerConfigError(f"{name} must have {self.dofs} entries, got {len(out)}")
        return out

    def update(self, target_position: object, target_velocity: object | None = None,
               target_acceleration: object | None = None) -> SmoothedReference:
        """Advance one cycle toward the target state; see the module docstring for odd inputs."""
        status = SmoothingStatus.WORKING
        reasons: list[str] = []
        p = self._as_list("target_position", target_position)
        v = self._as_list("target_velocity", target_velocity)
        a = self._as_list("target_acceleration", target_acceleration)

        if math.isfinite(sum(p) + sum(v) + sum(a)):
            if not self._initialized:
                self.reset(p)
            if v is not self._zeros or a is not self._zeros:
                # np.clip's min(max(x, −m), m) in plain floats (the same values, cheaper on a few entries)
                v_c = [min(max(x, -m), m) for x, m in zip(v, self.v_max.tolist())]
                a_c = [min(max(x, -m), m) for x, m in zip(a, self.a_max.tolist())]
                if v_c != v or a_c != a:
                    status = SmoothingStatus.CLIPPED
                    reasons.append("target velocity/acceleration clipped to the limits")
                v, a = v_c, a_c
            self._target = (p, v, a)
        else:
            status = SmoothingStatus.INVALID_TARGET
            reasons.append("non-finite target ignored")
            if not self._initialized:  # nothing to smooth yet: report a zero state
                z = np.zeros(self.dofs)
                return SmoothedReference(z, z.copy(), z.copy(), status, "no valid target yet")
            if self._target is None:
                self._target = (list(self._inp.current_position), self._zeros, self._zeros)

        tp, tv, ta = self._target  # type: ignore[misc]
        result = self._step(tp, tv, ta)
        if result is None and (any(tv) or any(ta)):
            reasons.append("ruckig rejected the target velocity/acceleration: dropped")
            self._target = (tp, self._zeros, self._zeros)
            result = self._step(tp, self._zeros, self._zeros)
        if result is None:
            status = SmoothingStatus.FALLBACK
            reasons.append("ruckig rejected the target: braking to rest")
            self._brake()
        elif result == Result.Finished and status is SmoothingStatus.WORKING:
            status = SmoothingStatus.FINISHED
        out = self._out if result is not None else None
        if out is not None:
            pos, vel, acc = np.array(out.new_position), np.array(out.new_velocity), np.array(out.new_acceleration)
        else:
            pos, vel, acc = self.state()
        return SmoothedReference(pos, vel, acc, status, "; ".join(reasons) if reasons else "")

    # ------------------------------------------------------------------
    def _step(self, tp: list[float], tv: list[float], ta: list[float]) -> Result | None:
        inp, out = self._inp, self._out
        inp.target_position, inp.target_velocity, inp.target_acceleration = tp, tv, ta
        try:
            result = self._otg.update(inp, out)
        except Exception:  # RuckigError for invalid input: handled by the caller
            return None
        if result not in (Result.Working, Result.Finished):
            return None
        out.pass_to_input(inp)
        return result

    def _brake(self) -> None:
        """Bring the velocity to zero with ruckig's velocity interface; else hold in place."""
        inp, b_inp, b_out = self._inp, self._brake_inp, self._brake_out
        b_inp.current_position = inp.current_position
        b_inp.current_velocity = inp.current_velocity
        b_inp.current_acceleration = inp.current_acceleration
        try:
            result = self._brake_otg.update(b_inp, b_out)
            ok = result in (Result.Working, Result.Finished)
        except Exception:
            ok = False
        if ok:
            inp.current_position = b_out.new_position
            inp.current_velocity = b_out.new_velocity
            inp.current_acceleration = b_out.new_acceleration
        else:
            inp.current_velocity = self._zeros
            inp.current_acceleration = self._zeros
