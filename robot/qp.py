"""Acceleration-level QP controller: knife-tip reference → joint commands within limits.

Each control period dt [s] it solves, for the joint acceleration a [rad/s²],

    minimise   Σ_tasks w·‖A_k·a − b_k‖²          (tip tracking, posture, damping, regularisation)
    subject to lo ≤ a ≤ hi                        (acceleration, velocity, viable position limits)
               −τ_max ≤ M(q)·a + h(q, v) ≤ τ_max  (torque limits, inverse dynamics)

and returns a, τ = M(q)·a + h(q, v) [N·m] and the state after dt at constant a:
v⁺ = v + a·dt, q⁺ = q + v·dt + ½·a·dt². It never raises in the loop; ``QPResult.status`` says
what held: ``ok`` (every limit); ``recovering`` (state outside a kinematic limit: the box by
:func:`robot.constraints.intersect_by_priority`, acceleration > velocity > position);
``relaxed`` (box and torque limits disjoint: slack s ≥ 0 on the box, cost ρ₁·Σs + ½ρ₂·‖s‖²,
torque limits hard, ``slack`` = max s [rad/s²]); ``invalid_reference`` (non-finite reference:
posture and damping hold the arm); ``invalid_state`` (non-finite q or v: a = 0, the last valid
torque and state); ``solver_failed`` (brake, a = clip(−v/dt) into the box, torque clipped). The
torque limits hold in every case. A singular pose (√det(J·Jᵀ) < ``QPConfig.singular_threshold``)
is only reported in ``reason``. Misuse (unknown frame, wrong shapes, bad gains) raises
:class:`robot.errors.ControllerConfigError` subclasses.
"""

from __future__ import annotations

import math
import time
from typing import Sequence

import numpy as np

from .constraints import BoxConstraint, Limit, TorqueLimit, default_constraints, intersect_by_priority
from .errors import ControllerConfigError, FrameNotFoundError, UnsupportedModelError
from .limits import JointLimits
from .solvers import make_backend
from .state import ControlState, StateEvaluator

__all__ = ["QPController", "QPConfig", "QPResult", "QPStatus", "manipulability"]
from .qp_types import Actuation, QPConfig, QPResult, QPStatus, RelaxedSolution, VerifiedActuation
from .tasks import AccelerationRegularization, DampingTask, PostureTask, Task, TipTrackingTask


def _finite(x: np.ndarray) -> bool:
    """True when every entry is finite: x·x is NaN/inf otherwise (|x| > 1e154, absurd here, also counts)."""
    return math.isfinite(float(x @ x))


def manipulability(J: np.ndarray) -> float:
    """Yoshikawa manipulability √det(J·Jᵀ) of a (3, n) translational Jacobian [m³ for n = 3]."""
    a = (J @ J.T).tolist()
    det = (a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1])
           - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0])
           + a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]))
    return math.sqrt(max(float(det), 0.0))


class QPController:
    """Joint acceleration QP for any Pinocchio model and end-effector frame.

    Parameters: ``model`` (Pinocchio, nq == nv), ``frame`` (name or id of the
    tool frame), ``limits`` (default: from the model's URDF limits with
    a_max = 10 rad/s², see :meth:`JointLimits.from_model`), ``config``;
    ``tasks``, ``box_constraints`` (priority order) and ``constraints``
    override the defaults built from ``config`` and ``limits``; ``tip_task`` replaces the default
    tip task in the default task list (e.g. a :class:`~robot.tasks.BlendedTipTrackingTask`); custom ``tasks``
    must hold exactly one :class:`TipTrackingTask` (``step``'s ``p_ref`` drives it,
    ``QPResult.tip_error`` reports it), else :class:`ControllerConfigError`.
    :meth:`evaluate` gives the kinematic and dynamic state the controller sees.
    """

    TORQUE_TOL = 1e-9  # [N·m] rounding allowance in the clip+verify step, ≪ the 1e-6 contract

    def __init__(self, model, frame: str | int, limits: JointLimits | None = None,
                 config: QPConfig | None = None, tasks: Sequence[Task] | None = None,
                 box_constraints: Sequence[BoxConstraint] | None = None,
                 constraints: Sequence[Limit] | None = None, tip_task: TipTrackingTask | None = None) -> None:
        self.config = cfg = config or QPConfig()
        if model.nq != model.nv:
            raise UnsupportedModelError(
                f"model has nq={model.nq} ≠ nv={model.nv} (free-flyer, spherical or continuous joints); "
                "the controller integrates q additively and supports revolute/prismatic joints only")
        if isinstance(frame, str):
            if not model.existFrame(frame):
                raise FrameNotFoundError(f"frame {frame!r} not in model {model.name!r}")
            frame_id = model.getFrameId(frame)
        else:
            frame_id = int(frame)
            if not 0 <= frame_id < model.nframes:
                raise FrameNotFoundError(f"frame id {frame_id} out of range [0, {model.nframes})")
        if not (np.isfinite(cfg.dt) and cfg.dt > 0):
            raise ControllerConfigError(f"dt must be > 0, got {cfg.dt}")
        n = model.nv
        self.model, self.frame_id, self.n = model, frame_id, n
        self.limits = limits if limits is not None else JointLimits.from_model(model, a_max=10.0)
        if self.limits.n != n:
            raise ControllerConfigError(f"limits are for {self.limits.n} joints, model has {n}")

        q_post = cfg.q_posture if cfg.q_posture is not None else 0.5 * (self.limits.q_min + self.limits.q_max)
        q_post = np.asarray(q_post, dtype=float)
        if q_post.shape != (n,):
            raise ControllerConfigError(f"q_posture must have shape ({n},), got {q_post.shape}")
        if tip_task is not None and not isinstance(tip_task, TipTrackingTask):
            raise ControllerConfigError(f"tip_task must be a TipTrackingTask, got {type(tip_task).__name__}")
        if tip_task is not None and tasks is not None:
            raise ControllerConfigError("give the tip task inside tasks or as tip_task, not both")
        self.tip_task = tip_task or TipTrackingTask(cfg.tip_weight, cfg.tip_kp, cfg.tip_kd, cfg.tip_max_error)
        if tasks is None:
            tasks = [self.tip_task, PostureTask(q_post, cfg.posture_weight, cfg.posture_kp, cfg.posture_kd),
                     AccelerationRegularization(cfg.regularization)]
            if cfg.damping_weight > 0:
                tasks.append(DampingTask(cfg.damping_weight, cfg.damping_kd))
        else:
            found = [t for t in tasks if isinstance(t, TipTrackingTask)]
            if len(found) != 1:
                names = [getattr(t, "name", type(t).__name__) for t in tasks]
                raise ControllerConfigError(
                    f"tasks must include exactly one TipTrackingTask (step()'s p_ref drives it and "
                    f"QPResult.tip_error reports it), found {len(found)} among {names}; give one with "
                    f"weight=0 to run without tip tracking")
            self.tip_task = found[0]
        self.tasks = list(tasks)
        self._other_tasks = self.tasks[1:]
        default_boxes, default_rows = default_constraints(self.limits)
        self.box_constraints = list(box_constraints) if box_constraints is not None else default_boxes
        self.constraints = list(constraints) if constraints is not None else default_rows
        if not self.box_constraints:
            raise ControllerConfigError("at least one box constraint (the acceleration limit) is required")
        self._torque = next((c for c in self.constraints if isinstance(c, TorqueLimit)), None)
        self.m = sum(c.num_rows(n) for c in self.constraints)

        self._evaluator = StateEvaluator(model, frame_id)
        self._primary = make_backend(cfg.solver, n, self.m, cfg.eps)
        self._relaxed = make_backend(cfg.solver, 2 * n, 2 * n + self.m, cfg.eps)
        eye = np.eye(n)
        self._g_relax_top = np.block([[eye, -eye], [-eye, -eye]])
        self._no_rows = (np.zeros((0, n)), np.zeros(0))
        self._lb_relax = np.concatenate([np.full(n, -1e30), np.zeros(n)])  # 1e30: "infinite" for OSQP and DAQP
        self._ub_relax = np.full(2 * n, 1e30)
        self._last_tau = np.zeros(n)
        self._last_q: np.ndarray | None = None
        self._last_v: np.ndarray | None = None

    # ------------------------------------------------------------------
    @classmethod
    def for_robot(cls, robot, config: QPConfig | None = None) -> "QPController":
        """Controller on a :class:`~robot.description.RobotDescription`'s tip frame with its limits; the
        posture task defaults to the arm's ``q_home`` (the SuperLimb: mid-range, as the QP's own default)."""
        cfg = config or QPConfig()
        if cfg.q_posture is None:
            cfg = QPConfig(**{**cfg.__dict__, "q_posture": robot.q_home})
        return cls(robot.model, robot.tip_frame_id, robot.limits, cfg)

    @classmethod
    def for_superlimb(cls, params=None, config: QPConfig | None = None) -> "QPController":
        """Controller on the SuperLimb's ``knife_tip`` with its derived limits."""
        from .superlimb.model_files import build_pinocchio_model
        from .superlimb.params import TOOL_FRAME, SuperLimbParams

        p = params or SuperLimbParams()
        return cls(build_pinocchio_model(p).model, TOOL_FRAME, JointLimits.from_superlimb(p), config)

    @property
    def dt(self) -> float:
        return self.config.dt

    def _vector(self, name: str, x: object, size: int) -> np.ndarray:
        if type(x) is np.ndarray and x.shape == (size,) and x.dtype == np.float64:
            return x
        arr = np.asarray(x, dtype=float)
        if arr.shape != (size,):
            raise ControllerConfigError(f"{name} must have shape ({size},), got {arr.shape}")
        return arr

    def evaluate(self, q: np.ndarray, v: np.ndarray) -> ControlState:
        """The state the controller sees at (q [rad], v [rad/s]): tip position p [m], velocity
        [m/s], Jacobian, M(q), h(q, v), drift J̇·v (see :class:`~robot.state.ControlState`).

        Raises :class:`ControllerConfigError` for wrong shapes; the arrays are the
        caller's own (q and v are copied).
        """
        q = np.array(self._vector("q", q, self.n), dtype=float)
        v = np.array(self._vector("v", v, self.n), dtype=float)
        return self._evaluator(q, v, self.config.dt)

    def tip_position(self, q: np.ndarray) -> np.ndarray:
        """Tool-frame position p(q) [m] in the model's world frame."""
        return self.evaluate(q, np.zeros(self.n)).p

    # ------------------------------------------------------------------
    def step(self, q: np.ndarray, v: np.ndarray, p_ref: np.ndarray | None = None,
             v_ref: np.ndarray | None = None, a_ref: np.ndarray | None = None) -> QPResult:
        """One control period from state (q [rad], v [rad/s]) toward the tip reference.

        p_ref [m], v_ref [m/s], a_ref [m/s²] in the world frame; p_ref None
        means "no tip task" (the arm holds its posture).  Never raises for
        non-finite values; raises :class:`ControllerConfigError` for wrong shapes.
        """
        t0 = time.perf_counter()
        n, dt = self.n, self.config.dt
        q = self._vector("q", q, n)
        v = self._vector("v", v, n)
        if not (_finite(q) and _finite(v)):
            return self._hold(q, v, t0)
        reasons: list[str] = []
        status = self._set_reference(p_ref, v_ref, a_ref, reasons)
        state = self._evaluator(q, v, dt)
        manip = manipulability(state.J)
        if manip < self.config.singular_threshold:
            reasons.append(f"near singular pose (manipulability {manip:.2e})")
        task = self.tip_task
        if task.p_ref is not None:
            e = task.p_ref - state.p
            tip_error = math.sqrt(float(e @ e))
        else:
            tip_error = float("nan")
        lo, hi, G, h, status = self._limits(state, status, reasons)
        H, c = self._objective(state)
        a, tau, status, slack, iterations = self._solve(state, H, c, lo, hi, G, h, status, reasons)
        v_next = v + a * dt
        q_next = q + (v + 0.5 * dt * a) * dt
        self._last_tau, self._last_q, self._last_v = tau, q_next, v_next
        return QPResult(a, tau, v_next, q_next, status, "; ".join(reasons), tip_error, slack, manip,
                        iterations, time.perf_counter() - t0)

    def _set_reference(self, p_ref: np.ndarray | None, v_ref: np.ndarray | None, a_ref: np.ndarray | None,
                       reasons: list[str]) -> QPStatus:
        """Give the tip task its reference (None: no tip task); non-finite parts are dropped and said."""
        task = self.tip_task
        if p_ref is None:
            task.clear_reference()
            return QPStatus.OK
        p_ref = self._vector("p_ref", p_ref, 3)
        v_ref = None if v_ref is None else self._vector("v_ref", v_ref, 3)
        a_ref = None if a_ref is None else self._vector("a_ref", a_ref, 3)
        if not _finite(p_ref):
            task.clear_reference()
            reasons.append("non-finite p_ref: tip tracking dropped")
            return QPStatus.INVALID_REFERENCE
        if v_ref is not None and not _finite(v_ref):
            v_ref = None
            reasons.append("non-finite v_ref ignored")
        if a_ref is not None and not _finite(a_ref):
            a_ref = None
            reasons.append("non-finite a_ref ignored")
        task.set_reference(p_ref, v_ref, a_ref)
        return QPStatus.OK

    def _limits(self, state: ControlState, status: QPStatus, reasons: list[str]
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, QPStatus]:
        """Box bounds ``lo ≤ a ≤ hi`` (by priority) and inequality rows ``G·a ≤ h`` of every limit."""
        lo, hi, conflict = intersect_by_priority([c.bounds(state) for c in self.box_constraints])
        if conflict.any():
            if status is QPStatus.OK:
                status = QPStatus.RECOVERING
            reasons.append("outside kinematic limits on joints " + ",".join(map(str, np.flatnonzero(conflict)))
                           + ": maximum-effort recovery")
        if len(self.constraints) == 1:
            G, h = self.constraints[0].compute_qp_inequalities(state)
        elif self.constraints:
            rows = [c.compute_qp_inequalities(state) for c in self.constraints]
            G = np.concatenate([r.G for r in rows])
            h = np.concatenate([r.h for r in rows])
        else:
            G, h = self._no_rows
        return lo, hi, G, h, status

    def _objective(self, state: ControlState) -> tuple[np.ndarray, np.ndarray]:
        """The summed cost ½·aᵀHa + cᵀa of every task."""
        H, c = self.tasks[0].compute_qp_objective(state)
        for t in self._other_tasks:
            objective = t.compute_qp_objective(state)
            H = H + objective.H
            c = c + objective.c
        return H, c

    def _solve(self, state: ControlState, H: np.ndarray, c: np.ndarray, lo: np.ndarray, hi: np.ndarray,
               G: np.ndarray, h: np.ndarray, status: QPStatus, reasons: list[str]
               ) -> tuple[np.ndarray, np.ndarray, QPStatus, float, int]:
        """(a, τ, status, slack, iterations): the primary QP, else the box-relaxed one, else braking."""
        slack = 0.0
        out = self._primary.solve(H, c, lo, hi, G, h)
        iterations = out.iterations
        if out.x is not None:
            a, tau, done = self._finalize(state, out.x, lo, hi)
            if done:
                return a, tau, status, slack, iterations
        a_r, s, it2, why = self._solve_relaxed(H, c, lo, hi, G, h)
        iterations += it2
        done = False
        if a_r is not None:
            slack = float(s.max())
            a, tau, done = self._finalize(state, a_r, lo - s, hi + s)
        if done and slack <= 1e-9:  # the primary answer was only inaccurate, nothing had to give
            reasons.append(f"primary QP inaccurate ({out.status}): answer of the slack QP, zero slack")
            return a, tau, status, 0.0, iterations
        if done:
            if status in (QPStatus.OK, QPStatus.RECOVERING):
                status = QPStatus.RELAXED
            reasons.append(f"box and torque limits conflict ({out.status}): box relaxed by {slack:.3g} rad/s²")
            return a, tau, status, slack, iterations
        reasons.append(f"QP failed ({out.status}; relaxed: {why}): braking")
        a, tau = self._brake(state, lo, hi)
        return a, tau, QPStatus.SOLVER_FAILED, slack, iterations

    # ------------------------------------------------------------------
    def _solve_relaxed(self, H: np.ndarray, c: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                       G: np.ndarray, h: np.ndarray) -> RelaxedSolution:
        """QP over x = [a, s]: box softened by s ≥ 0, torque rows hard (always feasible)."""
        n, cfg = self.n, self.config
        # Normalise the task part so that the slack penalty dominates whatever the task gains:
        # the relaxation is then (nearly) the smallest possible, the tasks only break ties.
        scale = 1.0 / max(1.0, float(np.abs(H).max()), float(np.abs(c).max()))
        P2 = np.zeros((2 * n, 2 * n))
        P2[:n, :n] = H * scale
        P2[n:, n:] = cfg.slack_quadratic * np.eye(n)
        c2 = np.concatenate([c * scale, np.full(n, cfg.slack_linear)])
        G2 = np.vstack([self._g_relax_top, np.hstack([G, np.zeros((G.shape[0], n))])])
        h2 = np.concatenate([hi, -lo, h])
        out = self._relaxed.solve(P2, c2, self._lb_relax, self._ub_relax, G2, h2)
        if out.x is None:
            return RelaxedSolution(None, None, out.iterations, out.status)
        return RelaxedSolution(out.x[:n], np.maximum(out.x[n:], 0.0), out.iterations, out.status)

    def _finalize(self, state: ControlState, a: np.ndarray, lo: np.ndarray, hi: np.ndarray
                  ) -> VerifiedActuation:
        """Clip+verify a solver's answer: returns ``VerifiedActuation(a, τ, ok)``.

        a is clipped into [lo, hi]; if the solver tolerance left |τ| above
        τ_max, a moves by δa = M⁻¹·(clip(τ) − τ), alternated with clipping
        (projections onto two convex sets, at most 5 rounds).  ``ok`` is False
        when they do not meet (the problem was infeasible after all).  Torques
        within ``TORQUE_TOL`` [N·m] of the limit (rounding at a vertex of the
        feasible set) count as satisfied.
        """
        a = np.minimum(np.maximum(a, lo), hi)
        tau = state.M @ a + state.h
        if self._torque is None:
            return VerifiedActuation(a, tau, True)
        tau_max = self._torque.tau_max
        tau_ok = tau_max + self.TORQUE_TOL
        for _ in range(5):
            if not (np.abs(tau) > tau_ok).any():
                return VerifiedActuation(a, tau, True)
            tau_c = np.minimum(np.maximum(tau, -tau_max), tau_max)
            a_t = a + np.linalg.solve(state.M, tau_c - tau)
            a = np.minimum(np.maximum(a_t, lo), hi)
            if not (a != a_t).any():
                return VerifiedActuation(a, tau_c, True)
            tau = state.M @ a + state.h
        return VerifiedActuation(a, tau, False)

    def _brake(self, state: ControlState, lo: np.ndarray, hi: np.ndarray) -> Actuation:
        """Last resort: a = clip(−v/dt, lo, hi), then τ clipped to its limits and a = M⁻¹(τ − h)."""
        a = np.minimum(np.maximum(-state.v / state.dt, lo), hi)
        tau = state.M @ a + state.h
        if self._torque is not None:
            tau = np.minimum(np.maximum(tau, -self._torque.tau_max), self._torque.tau_max)
            a = np.linalg.solve(state.M, tau - state.h)
        return Actuation(a, tau)

    def _hold(self, q: np.ndarray, v: np.ndarray, t0: float) -> QPResult:
        n = self.n
        q_hold = self._last_q if self._last_q is not None else np.where(np.isfinite(q), q, 0.0)
        v_hold = self._last_v if self._last_v is not None else np.zeros(n)
        return QPResult(np.zeros(n), self._last_tau.copy(), v_hold.copy(), q_hold.copy(), QPStatus.INVALID_STATE,
                        "non-finite q or v: holding the last valid command", solve_time=time.perf_counter() - t0)

    def reset(self) -> None:
        """Forget the last command (used by ``invalid_state`` answers)."""
        self._last_tau = np.zeros(self.n)
        self._last_q = self._last_v = None
