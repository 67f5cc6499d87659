"""Controllers written for the closed-loop tests (they implement SharedController.step's interface)."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from robot.qp import QPConfig, QPController
from robot.smoothing import ReferenceSmoother
from robot.superlimb import SuperLimbParams
from sim.task import EATING


@dataclass
class TestCommand:
    __test__ = False  # a command object, not a test class

    q_cmd: np.ndarray
    v_cmd: np.ndarray
    a_cmd: np.ndarray
    tau: np.ndarray
    alpha: float = 1.0
    beta: float = 0.0
    mode_proba: np.ndarray = field(default_factory=lambda: np.array([1.0]))
    tip_reference: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    status: str = "ok"


class OracleController:
    """Tracks the demonstration's knife tip (the wearer's intent) with QP + ruckig: a perfect reactive predictor."""

    def __init__(self, knife_xyz: np.ndarray, params: SuperLimbParams | None = None, dt: float = 0.01) -> None:
        from sim.wearer import smooth_intent

        self.knife = smooth_intent(np.asarray(knife_xyz, dtype=float), 1.0 / dt, 5.0)[0]  # the wearer's plan
        self.qp = QPController.for_superlimb(params, QPConfig(dt=dt))
        self.smoother = ReferenceSmoother(3, dt, max_velocity=1.0, max_acceleration=10.0, max_jerk=300.0)
        self.dt = dt

    def reset(self) -> None:
        self.qp.reset()
        self.smoother = ReferenceSmoother(3, self.dt, max_velocity=1.0, max_acceleration=10.0, max_jerk=300.0)

    def step(self, t, obs, voluntary, q, v, base_pose=None):
        k = min(round(t / self.dt) + 1, len(self.knife) - 1)
        s = self.smoother.update(self.knife[k])
        R, p = base_pose[:3, :3], base_pose[:3, 3]
        res = self.qp.step(q, v, R.T @ (s.position - p), R.T @ s.velocity, R.T @ s.acceleration)
        return TestCommand(res.q_next, res.v_next, res.a, res.tau, 1.0, 0.0, np.array([1.0]), s.position,
                           res.status.value)


class IdleController:
    """Does nothing for the tip: the QP holds the posture (the wearer has no help at all)."""

    def __init__(self, params: SuperLimbParams | None = None) -> None:
        self.qp = QPController.for_superlimb(params)

    def step(self, t, obs, voluntary, q, v, base_pose=None):
        res = self.qp.step(q, v, None)
        return TestCommand(res.q_next, res.v_next, res.a, res.tau, 0.0, 1.0, np.array([1.0]), np.full(3, np.nan),
                           res.status.value)


class AggressiveController:
    """Commands bang-bang joint accelerations at the limits, integrated as if nothing could stop them.

    It ignores the position and velocity limits (q_cmd may lie beyond them): the servo
    alone must keep the physics within the limits.
    """

    def __init__(self, params: SuperLimbParams | None = None, dt: float = 0.01, period_s: float = 1.5) -> None:
        self.p = params or SuperLimbParams()
        self.dt, self.period = dt, period_s

    def step(self, t, obs, voluntary, q, v, base_pose=None):
        sign = 1.0 if (t // self.period) % 2 == 0 else -1.0
        a = sign * self.p.acceleration_limit * np.array([1.0, 1.0, -1.0])
        v_cmd = np.clip(v + a * self.dt, -1.2 * self.p.velocity_limit, 1.2 * self.p.velocity_limit)
        q_cmd = q + 0.5 * (v + v_cmd) * self.dt
        return TestCommand(q_cmd, v_cmd, a, np.zeros(3), 0.0, 1.0, np.array([0.5, 0.5]), np.full(3, np.nan))


class VoluntaryController:
    """Integrates the wearer's shoulder command into the tip reference (α = 0, β = 1), tracked by the QP."""

    def __init__(self, params: SuperLimbParams | None = None, dt: float = 0.01, shoulder=None) -> None:

        self.qp = QPController.for_superlimb(params, QPConfig(dt=dt))
        self.shoulder = shoulder or EATING.shoulder_map()
        self.dt, self.ref = dt, None

    def reset(self) -> None:
        self.qp.reset()
        self.ref = None

    def step(self, t, obs, voluntary, q, v, base_pose=None):
        R, p = base_pose[:3, :3], base_pose[:3, 3]
        if self.ref is None:
            self.ref = R @ self.qp.tip_position(q) + p  # start at the current tip (plate frame)
        u = self.shoulder.tip_velocity(voluntary)
        self.ref = self.ref + u * self.dt
        res = self.qp.step(q, v, R.T @ (self.ref - p), R.T @ u)
        return TestCommand(res.q_next, res.v_next, res.a, res.tau, 0.0, 1.0, np.array([1.0]), self.ref.copy(),
                           res.status.value)
