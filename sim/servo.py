"""Joint servo at the physics rate: tracks the controller's command within every limit, in MuJoCo.

Between two controller steps (T = 10 ms) it follows the constant-acceleration segment ending at (q_cmd, v_cmd)
[rad, rad/s]: q_ref(s) = q_cmd − v_cmd·r + ½·a_cmd·r², v_ref(s) = v_cmd − a_cmd·r, r = t_end − s, with a PD
law on the feed-forward acceleration: a_des = a_cmd + k_p·(q_ref − q) + k_d·(v_ref − v).

**Limits.** MuJoCo's semi-implicit ``Euler`` step h [s] with zero damping gives exactly

    v⁺ = v + h·M(q)⁻¹·(τ − b(q, v)),      q⁺ = q + h·v⁺

(M: ``mj_fullM`` with armature; b: ``qfrc_bias``). The servo keeps v⁺ in the *viable* interval

    −v_max ≤ v⁺ ≤ v_max,   v⁺ ≤ u(q_max − q),   −v⁺ ≤ u(q − q_min),   u(gap) = −A·h + sqrt(A²h² + 2A·gap)

(A: braking acceleration), so q⁺ + v⁺²/(2A) ≤ q_max and braking at A stops in time
(:func:`viable_next_velocity`; :func:`robot.constraints.viable_velocity_bound` is the same for the controller's
exact integration, which MuJoCo's step is not). Then τ = M·a + b; beyond τ_max the QP min ‖a − a_des‖² s.t.
the viable box and |M·a + b| ≤ τ_max (DAQP, :mod:`robot.solvers`) picks the nearest feasible a. It is feasible
whenever braking a_b = clip(−v/h, ±A) needs at most τ_max, checked every step (``brake_infeasible`` counts
the steps where it would not).
"""

from __future__ import annotations

import math
import operator
from dataclasses import dataclass

import mujoco
import numpy as np

from robot.default_arm import as_description
from robot.description import RobotDescription
from robot.solvers import make_backend

__all__ = ["JointServo", "ServoConfig", "viable_next_velocity"]


def viable_next_velocity(gap: float, A: float, h: float) -> float:
    """Largest v⁺ [rad/s] toward a limit ``gap`` [rad] away (≥ 0) under semi-implicit steps h [s].

    Solves q + h·v⁺ + v⁺²/(2A) ≤ q_lim for v⁺:  v⁺ ≤ −A·h + sqrt(A²h² + 2A·gap).
    A negative gap (beyond the limit) gives gap/h < 0: the velocity that brings
    q⁺ back onto the limit in one step.
    """
    if gap <= 0.0:
        return gap / h
    return -A * h + math.sqrt(A * A * h * h + 2.0 * A * gap)


@dataclass(frozen=True)
class ServoConfig:
    """Servo gains: natural frequency ``omega`` [rad/s] and damping ratio ``zeta`` of the PD loop.

    k_p = ω², k_d = 2ζω.  ω = 2π·25 Hz: a stiff position loop as a harmonic-drive
    servo's, well inside the 1 kHz step (k_d·h ≈ 0.3).
    """

    omega: float = 2.0 * math.pi * 25.0
    zeta: float = 1.0

    def __post_init__(self) -> None:
        if not (self.omega > 0 and self.zeta > 0):
            raise ValueError(f"ServoConfig needs omega > 0 and zeta > 0, got {self.omega}, {self.zeta}")


class JointServo:
    """Computes the joint torques [N·m] of one physics step from MuJoCo's current state.

    Call :meth:`set_segment` at each controller step, then, every physics step,
    ``mj_step1`` → :meth:`torque` → write ``ctrl`` → ``mj_step2``.  Counters:
    ``qp_steps`` (torque limit active, QP used), ``fallback_steps`` (QP failed,
    braking with clipped torque), ``brake_infeasible`` (see module docstring).
    """

    def __init__(self, model: mujoco.MjModel, data: mujoco.MjData, robot: RobotDescription | None = None,
                 config: ServoConfig | None = None) -> None:
        robot = as_description(robot)  # None or SuperLimbParams: the SuperLimb
        lim = robot.limits
        self.n = n = robot.n
        self.model, self.data, self.config = model, data, config or ServoConfig()
        if model.nv != n or model.nq != n or model.nu != n:
            raise ValueError(f"JointServo drives the {n}-joint arm {robot.name!r} as the whole state "
                             f"(nq = nv = nu = {n}), model has nq={model.nq}, nv={model.nv}, nu={model.nu}")
        if model.opt.integrator != mujoco.mjtIntegrator.mjINT_EULER:
            raise ValueError("JointServo predicts MuJoCo's semi-implicit Euler step: set integrator=\"Euler\"")
        if np.any(model.dof_damping != 0):
            raise ValueError("JointServo assumes zero joint damping (Euler treats damping implicitly)")
        self.h = float(model.opt.timestep)
        self.q_min, self.q_max = lim.q_min.tolist(), lim.q_max.tolist()
        self.v_max, self.A = lim.v_max.tolist(), lim.a_brake.tolist()
        self.tau_max = np.array(lim.tau_max)
        self._tau_max_l = self.tau_max.tolist()
        self.kp = self.config.omega ** 2
        self.kd = 2.0 * self.config.zeta * self.config.omega
        self._M = np.zeros((n, n))
        # per-step scratch arrays (no allocation on the fast path)
        self._a = np.zeros(n)
        self._qpos, self._qvel, self._bias = data.qpos, data.qvel, data.qfrc_bias  # views into MuJoCo's state
        self._tau_brake, self._a_brake = np.zeros(n), np.zeros(n)
        # beyond this distance to a limit the viable bound exceeds v_max: v_max²/(2A) + v_max·h [rad]
        self._free_gap = [vm * vm / (2.0 * a) + vm * self.h for vm, a in zip(self.v_max, self.A)]
        self._joints = list(zip(self.q_min, self.q_max, self.v_max, self.A, self._free_gap))  # per joint, in order
        self._qp = make_backend("auto", n, 2 * n, 1e-12)
        self._G = np.zeros((2 * n, n))
        self.qp_steps = self.fallback_steps = self.brake_infeasible = 0
        self.hold()

    def set_segment(self, q_cmd: np.ndarray, v_cmd: np.ndarray, a_cmd: np.ndarray, t_end: float) -> None:
        """The commanded segment ending at t_end [s] in state (q_cmd, v_cmd) with acceleration a_cmd."""
        self._seg_l = (np.asarray(q_cmd, dtype=float).tolist(), np.asarray(v_cmd, dtype=float).tolist(),
                       np.asarray(a_cmd, dtype=float).tolist(), float(t_end))

    def hold(self) -> None:
        """Stop and hold the current position (used when a command is not usable)."""
        self._seg_l = (self.data.qpos[:self.n].tolist(), [0.0] * self.n, [0.0] * self.n, float(self.data.time))

    def torque(self) -> np.ndarray:
        """τ (n,) [N·m] for the state in ``data`` (after ``mj_step1``); within ±τ_max always (:meth:`torque_into`)."""
        return self.torque_into(np.empty(self.n))

    def torque_into(self, tau: np.ndarray) -> np.ndarray:
        """:meth:`torque` written into ``tau`` (n,) (e.g. ``data.ctrl``, sparing a copy per physics step); returns it.

        Plain-float arithmetic on the fast path: for a handful of joints at 1 kHz, numpy's
        per-call overhead would cost more than the physics step itself.  Far from
        a position limit (gap ≥ v_max²/(2A) + v_max·h) the viable bound cannot be
        below v_max and is not evaluated.  Braking feasibility is checked where
        the servo may rely on it: whenever the viable box or the torque limit is active.
        """
        d, h, data_time = self.data, self.h, self.data.time
        q, v = self._qpos.tolist(), self._qvel.tolist()  # nq = nv = n (checked in __init__)
        q_c, v_c, a_c, t_end = self._seg_l
        r = max(t_end - data_time, 0.0)
        kp, kd = self.kp, self.kd
        a_l, box = [], []  # box: (a_des, lo, hi) per joint, read only where the torque limit binds
        active = False
        for qi, vi, qc, vc, ac, (q_lo, q_hi, vm, A, free) in zip(q, v, q_c, v_c, a_c, self._joints):
            ad = ac + kp * (qc - vc * r + 0.5 * ac * r * r - qi) + kd * (vc - ac * r - vi)
            gap_up, gap_lo = q_hi - qi, qi - q_lo
            v_up = vm if gap_up >= free else min(vm, viable_next_velocity(gap_up, A, h))
            v_lo = -vm if gap_lo >= free else max(-vm, -viable_next_velocity(gap_lo, A, h))
            if v_lo > v_up:  # only beyond a position limit: head back at the speed limit
                v_lo = v_up = vm if qi < q_lo else -vm
            lo_i, hi_i = (v_lo - vi) / h, (v_up - vi) / h
            box.append((ad, lo_i, hi_i))
            if ad < lo_i:
                ad, active = lo_i, True
            elif ad > hi_i:
                ad, active = hi_i, True
            a_l.append(ad)
        a = self._a
        a[:] = a_l
        mujoco.mj_mulM(self.model, d, tau, a)  # M(q)·a from MuJoCo's own (sparse) inertia incl. armature
        tau += self._bias
        fits = all(map(operator.le, map(abs, tau.tolist()), self._tau_max_l))  # |τ_i| ≤ τ_max,i
        if active or not fits:
            self._check_brake(v)
        if fits:
            return tau
        mujoco.mj_fullM(self.model, d, self._M)
        ad_l, lo_l, hi_l = zip(*box)
        tau[:] = self._constrained(self._M.copy(), d.qfrc_bias.copy(), np.array(ad_l), np.array(lo_l),
                                   np.array(hi_l))
        return tau

    def _check_brake(self, v: list[float]) -> None:
        """Count the step if braking a_b = clip(−v/h, ±A) would need more than τ_max."""
        ab = self._a_brake
        for i in range(self.n):
            ab[i] = min(max(-v[i] / self.h, -self.A[i]), self.A[i])
        tb = self._tau_brake
        mujoco.mj_mulM(self.model, self.data, tb, ab)
        tb += self.data.qfrc_bias
        if np.any(np.abs(tb) > self.tau_max):
            self.brake_infeasible += 1

    def _constrained(self, M: np.ndarray, bias: np.ndarray, a_des: np.ndarray, lo: np.ndarray,
                     hi: np.ndarray) -> np.ndarray:
        """Nearest a to a_des in the viable box with |M a + b| ≤ τ_max; braking if the QP fails."""
        self.qp_steps += 1
        self._G[:self.n], self._G[self.n:] = M, -M
        h_rows = np.concatenate([self.tau_max - bias, self.tau_max + bias])
        out = self._qp.solve(np.eye(self.n), -a_des, lo, hi, self._G, h_rows)
        if out.x is not None:
            a = np.minimum(np.maximum(out.x, lo), hi)
            tau = M @ a + bias
            if np.all(np.abs(tau) <= self.tau_max + 1e-9):
                return np.clip(tau, -self.tau_max, self.tau_max)
        self.fallback_steps += 1
        return np.clip(M @ np.clip(self._a_brake, lo, hi) + bias, -self.tau_max, self.tau_max)
