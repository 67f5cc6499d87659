"""A command of ``mpcshare run`` as the robot stand-in's runner follows it (``mpcshare sim --serve``).

Each form ``run`` sends becomes the runner's segment (q₁, v₁, a) over the period T from the step's
measured (q, v), with the controller's own integration q₁ = q + (v + ½·T·a)·T, v₁ = v + a·T (so each
form gives back the controller's segment, to the wire's rounding):

- ``JointTrajectory`` (one point): positions, velocities, accelerations as they are (by joint name);
- ``Float64MultiArray`` position: q₁ given, a = 2·(q₁ − q − v·T)/T²;
- velocity: v₁ given, a = (v₁ − v)/T;
- effort: τ given, a = M(q)⁻¹·(τ − h(q, v)) in the arm's rigid-body model (pinocchio's ABA); with the
  configuration's ``driver_compensates_gravity`` the stand-in is that driver: τ + g(q).

:func:`remote_command` adds what the status of the same stamp says (α, β, novelty, the tip reference,
the mode probabilities, the status; NaN and ``no_status`` where it did not arrive).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Sequence

import numpy as np

__all__ = ["RemoteCommand", "command_segment", "remote_command"]


@dataclass
class RemoteCommand:
    """One command of ``mpcshare run`` as the runner reads it (the fields of ``ControlCommand`` it logs; from
    the status of the same stamp: ``no_status`` and NaN when that status did not arrive)."""

    q_cmd: np.ndarray
    v_cmd: np.ndarray
    a_cmd: np.ndarray
    status: str = "ok"
    alpha: float = math.nan
    beta: float = math.nan
    novelty: float = math.nan
    tip_reference: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    mode_proba: np.ndarray = field(default_factory=lambda: np.zeros(0))


def _floats(text: str) -> np.ndarray:
    try:
        return np.array([float(x) for x in text.split(",") if x], dtype=float)
    except ValueError:
        return np.zeros(0)


def command_segment(msg: Any, interface: str, joints: Sequence[str], period_s: float, q: np.ndarray, v: np.ndarray,
                    dynamics: tuple[Any, Any] | None = None,
                    add_gravity: bool = False) -> tuple[np.ndarray, ...] | None:
    """(q₁, v₁, a) of the command ``msg`` (module docstring); ``interface``: ``trajectory`` (a JointTrajectory)
    or the Float64MultiArray's position, velocity, effort; ``dynamics``: the arm's (pinocchio model, data),
    needed for effort (RuntimeError without); ``add_gravity``: the effort is τ − g(q) (the driver adds g). None:
    not a command for ``joints`` (a wrong length, a missing joint, a non-finite value)."""
    n, T = len(joints), period_s
    if interface == "trajectory":
        if len(msg.points) != 1:
            return None
        p = msg.points[0]
        index = {name: i for i, name in enumerate(msg.joint_names)}
        try:
            order = [index[j] for j in joints]
            return tuple(np.array([seq[i] for i in order], dtype=float)
                         for seq in (p.positions, p.velocities, p.accelerations))
        except (KeyError, IndexError):
            return None
    data = np.array(msg.data, dtype=float)
    if data.shape != (n,) or not np.isfinite(data).all():
        return None
    if interface == "position":
        a = 2.0 * (data - q - v * T) / (T * T)
    elif interface == "velocity":
        a = (data - v) / T
    else:
        if dynamics is None:
            raise RuntimeError("an effort command needs the arm's model: bind the arm first")
        import pinocchio as pin

        if add_gravity:
            data = data + pin.computeGeneralizedGravity(*dynamics, q)
        a = np.array(pin.aba(*dynamics, q, v, data), dtype=float)
    return q + (v + 0.5 * T * a) * T, v + a * T, a


def remote_command(segment: tuple[np.ndarray, ...], values: dict[str, str]) -> RemoteCommand:
    """The segment with its status's ``values`` (module docstring)."""
    def num(key: str) -> float:
        try:
            return float(values[key])
        except (KeyError, ValueError):
            return math.nan

    tip = _floats(values.get("tip_reference", ""))
    return RemoteCommand(*segment, status=values.get("status", "no_status"), alpha=num("alpha"), beta=num("beta"),
                         novelty=num("novelty"), tip_reference=tip if tip.size == 3 else np.full(3, np.nan),
                         mode_proba=_floats(values.get("mode_proba", "")))
