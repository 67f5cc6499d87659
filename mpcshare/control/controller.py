"""The online shared controller, every 10 ms (docs/design.md, "Online control").

Per :meth:`SharedController.step`:

1. front end (:mod:`mpcshare.control.frontend`): Kalman filter over the fork, anti-aliased
   10 Hz window, mode filter and novelty; on the 10 Hz ticks (:mod:`mpcshare.control.models_tick`)
   the gate of the most probable mode (``gates.proba_one``) and the streaming reactive predictor
   (``predictor.make_stream().step(concat(o_t, p_t))``), whose forecast of the tip over
   its horizon becomes a continuous trajectory p̂(·) (:class:`~mpcshare.control.forecast.ForecastTrack`:
   a spline, cross-faded between ticks; held when the predictor has no forecast); with the
   bundle's control-rate forecast (:mod:`mpcshare.control.fastpath`), the trajectory is
   re-made every step from the fork's Kalman state, the mode posterior and the LSTM's forecast;
2. arbitration (:mod:`mpcshare.control.arbitration`, the strategy of :mod:`mpcshare.control.strategies`
   given the gate probability, the mode posterior, û_r and û_v): α, β; û = α·û_r + β·û_v [m/s] with the
   reactive term aimed ``forecast_lead_s`` ahead to cancel the latency after the
   reference, û_r = sat(ṗ̂(t + τ) + k·(p̂(t + τ) − p_ref)); û integrated into the tip reference
   p_ref (plate frame), clamped to the workspace box and the reach shell
   (:mod:`mpcshare.control.workspace`), then moved into the arm's model frame with the base pose;
3. ``robot.smoothing.ReferenceSmoother`` (ruckig, jerk-limited) toward (p_ref, û, α·p̈̂(t + τ));
4. optional MPC (``robot.mpc.tip_mpc.TipMPC``; with the keep-out, ``KeepOutTipMPC``: the wearer's
   body zones as constraints over its horizon, moving with the hand's forecast) over its horizon on the preview
   (:mod:`mpcshare.control.preview`)
   r_k = p_s + α·(p̂(t + τ + k·dt) − p̂(t + τ)) + β·û_v·k·dt (the robot's share from the forecast,
   the wearer's extrapolated; ``mpc_preview=False``: the smoothed reference p_s extrapolated at
   its velocity; with the control-rate forecast, the forecast is read only up to the horizons
   where its skill against the hold is above 0 in the current mode, held beyond), solved every
   ``mpc_every`` steps and followed in between
   (:class:`~mpcshare.control.mpc_follow.MPCFollower`); its planned tip at t + dt (position,
   central-difference velocity and acceleration) is the reference of
5. ``robot.qp.QPController``, which enforces joint position, velocity, acceleration and
   torque limits at the control rate and, ranked above tracking, keeps the knife's blade out of
   the wearer's body zones (:mod:`mpcshare.control.keepout`). When the MPC fails or runs out of time, the QP
   tracks the smoothed reference alone.

``step`` never raises: every fault gives a safe command and a status, the most severe of the
step's faults (:data:`~mpcshare.control.types.STATUSES`, where each is listed with what the step
does; ``reasons`` lists every fault of the step).
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import TYPE_CHECKING, Callable

import numpy as np

from mpcshare.control.arbitration import Arbiter, check_beta, check_strategy, fuse, reactive_velocity
from mpcshare.control.fallback import fallback_joint_state, rest_command
from mpcshare.control.fastpath import FastPath
from mpcshare.control.forecast import ForecastTrack, TipTrajectory
from mpcshare.control.frontend import StreamingFrontEnd, sense
from mpcshare.control.keepout import KeepOutSettings, make_keepout_mpc, make_keepout_qp
from mpcshare.control.models_tick import fast_step, models_tick
from mpcshare.control.mpc_follow import MPCFollower
from mpcshare.control.preview import PreviewPlan, mpc_preview
from mpcshare.control.setup import BundleLayout, check_bundle, make_mpc, mode_figures, rule_settings, shoulder_map
from mpcshare.control.types import DEFAULT_BETA, STATUSES, ControlCommand, ControllerConfig
from mpcshare.control.workspace import DEFAULT_BASE_POSE, bound_reference, check_base_pose
from mpcshare.errors import ControllerTypeError
from robot.default_arm import as_description
from robot.description import RobotDescription
from robot.floor import FloorLimit
from robot.kinematics import TipKinematics
from robot.qp import QPStatus
from robot.shoulder import ShoulderMap
from robot.smoothing import ReferenceSmoother

if TYPE_CHECKING:  # annotations only: importing the bundle module pulls in torch
    from mpcshare.bundle import ModelBundle

__all__ = ["STATUSES", "ControlCommand", "ControllerConfig", "SharedController"]

_RANK = {s: i for i, s in enumerate(STATUSES)}


def _finite(x: np.ndarray) -> bool:
    """True when every entry is finite (a NaN or inf makes the sum non-finite)."""
    return math.isfinite(x.sum())


class SharedController:
    """Shared control of an arm's knife tip from a trained bundle (module docstring); ``robot``: any
    ``RobotDescription`` (a ``SuperLimbParams`` or None: the SuperLimb). Build with :meth:`from_bundle`.
    Misuse at construction raises ``mpcshare.errors.ControllerSetupError`` (a ValueError;
    ``ControllerTypeError``: also a TypeError) naming what is wrong (channels, strategy, β, shapes …).
    """

    default_base_pose = DEFAULT_BASE_POSE

    def __init__(self, bundle: ModelBundle, *, robot: RobotDescription | None = None, strategy: str = "gate",
                 beta: float = DEFAULT_BETA, use_mpc: bool = False, shoulder: ShoulderMap | None = None,
                 tip_channels: tuple[str, str, str] | None = None,
                 fork_channels: tuple[str, str, str] | None = None, mpc=None,
                 config: ControllerConfig | None = None, preview: TipTrajectory | None = None,
                 schedule: Callable[[float], float] | None = None) -> None:
        check_strategy(strategy, scheduled=schedule is not None)
        self.beta_user = check_beta(beta)
        self.config = cfg = config or ControllerConfig()
        self.layout: BundleLayout = check_bundle(bundle, tip_channels, fork_channels)
        self.bundle, self.strategy = bundle, strategy
        self.shoulder = shoulder_map(bundle, shoulder)
        self.robot = as_description(robot)  # TypeError naming the choices for anything else
        self.dt = 1.0 / float(bundle.rate_hz)
        heel = cfg.keepout.heel_offset if cfg.keepout is not None else KeepOutSettings().heel_offset
        self.floor = None if cfg.floor_z is None else \
            FloorLimit(self.robot.model, self.robot.tip_frame, heel, cfg.floor)
        self.qp, self.keepout = make_keepout_qp(self.robot, cfg.qp, self.dt, cfg.keepout, self.floor)
        if self.keepout is not None:
            self.keepout.bind(bundle.obs_names)
        zoned = cfg.keepout is not None and cfg.keepout.mpc_zones
        self.mpc = mpc if mpc is not None else None if not use_mpc else \
            make_keepout_mpc(self.robot, self.dt, cfg.keepout) if zoned else make_mpc(self.robot, self.dt)
        self.mpc_follower = None if self.mpc is None else \
            MPCFollower(self.mpc, self.dt, cfg.mpc_deadline_s, cfg.mpc_every)
        self.tip = TipKinematics(self.qp.model, self.robot.tip_frame)
        self.reach = self.robot.reach_shell(cfg.reach_margin)
        lower = np.array(cfg.workspace.lower, dtype=float)
        if cfg.floor_z is not None:
            lower[2] = max(lower[2], cfg.floor_z)
        self._box = (lower, np.array(cfg.workspace.upper, dtype=float))  # plate frame, floor raised to floor_z
        self.frontend = StreamingFrontEnd(bundle.preprocessor.obs, bundle.modes, rate_hz=bundle.rate_hz,
                                          model_hz=bundle.model_hz, window_s=bundle.window_s,
                                          detect_stale=cfg.detect_stale)
        self.arbiter = Arbiter(strategy, beta, settings=rule_settings(bundle, strategy, cfg.strategy_settings),
                               novelty_threshold=float(bundle.novelty_threshold), min_dwell_s=cfg.min_dwell_s,
                               handover_s=cfg.handover_s, novelty_persist_s=cfg.novelty_persist_s,
                               schedule=schedule, figures=mode_figures(bundle))
        self.smoother = ReferenceSmoother(3, self.dt, cfg.max_velocity, cfg.max_acceleration, cfg.max_jerk)
        if preview is not None and not callable(getattr(preview, "sample", None)):
            raise ControllerTypeError(f"preview must be a TipTrajectory (sample(times)), got {type(preview).__name__}")
        self.oracle = preview is not None
        self.fast = FastPath(bundle, self.layout) if cfg.fast_forecast and getattr(bundle, "fast", None) \
            is not None and not self.oracle else None
        self.lead_s = cfg.fast_lead_s if self.fast is not None else cfg.forecast_lead_s
        self.forecast: TipTrajectory = preview if preview is not None else \
            ForecastTrack(1.0 / float(bundle.model_hz), cfg.forecast_fade_s)
        self.reset()

    @classmethod
    def from_bundle(cls, folder_or_bundle: str | Path | ModelBundle, robot: RobotDescription | None = None,
                    strategy: str = "gate", beta: float = DEFAULT_BETA, use_mpc: bool = False,
                    shoulder: ShoulderMap | None = None,
                    **options) -> SharedController:
        """Controller from a bundle folder (``mpcshare.bundle.load_bundle``) or a loaded bundle.

        ``options``: ``tip_channels``, ``fork_channels`` (act/obs names of the knife and fork
        tip positions when they are not knife_x/y/z, fork_x/y/z), ``mpc`` (an MPC object),
        ``config`` (:class:`ControllerConfig`), ``preview`` (a known tip trajectory that replaces
        the predictor's forecast: the ``oracle_preview`` upper bound, not realisable), ``schedule``
        (t → α ∈ {0, 1} with strategy ``schedule``: a replayed hand-over schedule).
        """
        check_strategy(strategy, scheduled=options.get("schedule") is not None)
        check_beta(beta)
        bundle = folder_or_bundle
        if isinstance(folder_or_bundle, (str, Path)):
            from mpcshare.bundle import load_bundle

            bundle = load_bundle(folder_or_bundle)
        return cls(bundle, robot=robot, strategy=strategy, beta=beta, use_mpc=use_mpc, shoulder=shoulder,
                   **options)

    @property
    def handovers(self):
        """The arbitration's hand-over log (list of ``Handover``)."""
        return self.arbiter.handovers

    def reset(self) -> None:
        """Start a new episode: filters, predictor state, reference and logs forgotten."""
        self.frontend.reset()
        if self.keepout is not None:
            self.keepout.reset()
        self.arbiter.reset()
        self.qp.reset()
        if self.mpc_follower is not None:
            self.mpc_follower.reset()
        self.smoother = ReferenceSmoother(3, self.dt, self.config.max_velocity, self.config.max_acceleration,
                                          self.config.max_jerk)
        self._stream = self.bundle.predictor.make_stream()
        self.forecast.reset()
        if self.fast is not None:
            self.fast.reset()
        self._t_now = math.nan
        self._acc_ff = np.zeros(3)  # α·p̈̂ (plate frame), the smoother's target acceleration
        self._preview = PreviewPlan.empty()  # α, β, û_v (plate), the aimed time t + τ
        K = self.layout.n_modes
        self._mode_proba = np.full(K, 1.0 / K)
        self._novelty = float("nan")
        self._gate_proba: float | None = None
        self._window_ready = False
        self._p_pred = np.full(3, np.nan)
        self._p_ref: np.ndarray | None = None  # plate frame
        self._last_t = -math.inf
        self._pose = np.array(self.default_base_pose, dtype=float)
        self._set_floor()
        self._fork_vel = np.zeros(self.layout.d_o)
        self._last: ControlCommand | None = None

    # ------------------------------------------------------------------ helpers
    def _set_floor(self) -> None:
        """The floor z_plate ≥ floor_z in the model frame: n = Rᵀ·e_z, n·p ≥ floor_z − t_z."""
        if self.floor is not None:
            self.floor.set_plane(self._pose[2, :3], self.config.floor_z - self._pose[2, 3])

    def _to_model(self, p: np.ndarray) -> np.ndarray:
        return self._pose[:3, :3].T @ (p - self._pose[:3, 3])

    def _to_plate(self, p: np.ndarray) -> np.ndarray:
        return self._pose[:3, :3] @ p + self._pose[:3, 3]

    def _command(self, res, alpha: float, beta: float, faults: list[tuple[str, str]],
                 timings: dict[str, float], t0: float) -> ControlCommand:
        status = min((f[0] for f in faults), key=_RANK.__getitem__, default="ok")
        timings["total"] = time.perf_counter() - t0
        ref = self._p_ref.copy() if self._p_ref is not None else np.full(3, np.nan)
        cmd = ControlCommand(tau=np.array(res.tau), q_cmd=np.array(res.q_next), v_cmd=np.array(res.v_next),
                      a_cmd=np.array(res.a), alpha=float(alpha), beta=float(beta),
                      mode_proba=self._mode_proba.copy(), novelty=self._novelty, tip_reference=ref,
                      status=status, reasons=tuple(f"{s}: {r}" for s, r in faults), timings=timings,
                      predicted_tip=self._p_pred.copy(), fork_velocity=self._fork_vel.copy())
        self._last = cmd
        return cmd

    def _hold(self, q: np.ndarray, v: np.ndarray, faults, timings, t0) -> ControlCommand:
        """Brake toward the current smoothed reference (or the measured tip) within the limits."""
        if self.smoother.initialized:
            p_hold = self.smoother.state()[0]
        else:
            p_hold = self.tip.position(q) if _finite(q) else None
        res = self.qp.step(q, v, p_hold, np.zeros(3), np.zeros(3))
        if self.keepout is not None and _finite(q) and _finite(v):
            res = self.keepout.check(self.qp, q, v, res, faults)
        if res.status is QPStatus.SOLVER_FAILED:
            faults.append(("qp_failed", res.reason))
        return self._command(res, 0.0, 1.0, faults, timings, t0)

    # ------------------------------------------------------------------ the loop
    def step(self, t: float, obs, voluntary, q, v, base_pose=None) -> ControlCommand:
        """One control period (module docstring). Never raises."""
        t0 = time.perf_counter()
        try:
            return self._step(t0, t, obs, voluntary, q, v, base_pose)
        except Exception as exc:  # noqa: BLE001 — last line of defence: brake within limits, say why
            reason = f"{type(exc).__name__}: {exc}"
            qa, va = fallback_joint_state(q, v, self.qp.n)
            try:
                return self._hold(qa, va, [("internal_error", reason)], {}, t0)
            except Exception:  # noqa: BLE001 — even the QP failed: repeat the last command at rest
                return rest_command(self.qp.n, self._last, self._mode_proba, self._novelty, reason, t0)

    def _step(self, t0: float, t, obs, voluntary, q, v, base_pose) -> ControlCommand:
        faults: list[tuple[str, str]] = []
        timings: dict[str, float] = {}
        n = self.qp.n
        q = np.asarray(q, dtype=float) if np.size(q) == n else np.full(n, np.nan)
        v = np.asarray(v, dtype=float) if np.size(v) == n else np.full(n, np.nan)
        q, v = q.reshape(n), v.reshape(n)
        if not (_finite(q) and _finite(v)):
            faults.append(("invalid_joint_state", "q or v not finite or of the wrong shape: holding"))
            return self._command(self.qp.step(q, v), 0.0, 1.0, faults, timings, t0)
        t = float(t)
        if not t > self._last_t:
            faults.append(("time_went_backwards", f"t = {t!r} after {self._last_t!r}: holding"))
            return self._hold(q, v, faults, timings, t0)
        dt = min(t - self._last_t, self.config.max_dt)
        self._last_t = t
        if base_pose is not None:
            try:
                self._pose = check_base_pose(base_pose)
                self._set_floor()
            except ValueError as exc:
                faults.append(("invalid_base_pose", f"{exc}: last valid pose kept"))

        ta = time.perf_counter()  # 1. front end
        fe = sense(t, obs, faults, frontend=self.frontend, d_o=self.layout.d_o,
                   stale_after_s=self.config.stale_after_s, keepout=self.keepout, pose=self._pose)
        if fe is None:
            return self._hold(q, v, faults, timings, t0)
        self._fork_vel = fe.fork_velocity
        timings["frontend"] = time.perf_counter() - ta
        ta = time.perf_counter()  # 2. learned parts at the model rate
        if fe.tick is not None:
            self._mode_proba, self._novelty, self._window_ready, self._gate_proba = models_tick(
                t, fe.tick, stream=self._stream, gates=self.bundle.gates, layout=self.layout, fast=self.fast,
                forecast=self.forecast, oracle=self.oracle, faults=faults)
        timings["models"] = time.perf_counter() - ta
        if self.fast is not None:
            ta = time.perf_counter()  # 2b. the control-rate forecast
            fast_step(t, fe, self._mode_proba, self.fast, self.forecast, faults)
            timings["fast"] = time.perf_counter() - ta
        ta = time.perf_counter()  # 3. arbitration and the tip reference (plate frame)
        alpha, beta, u, p_model = self._arbitrate(t, dt, q, voluntary, fe, faults)
        timings["arbitration"] = time.perf_counter() - ta
        res = self._track(q, v, u, p_model, faults, timings)  # 4. smoothing, MPC, QP
        return self._command(res, alpha, beta, faults, timings, t0)

    def _arbitrate(self, t: float, dt: float, q: np.ndarray, voluntary, fe, faults: list[tuple[str, str]]
                   ) -> tuple[float, float, np.ndarray, np.ndarray]:
        """(α, β, the fused tip velocity u [m/s] (plate frame), the new tip reference (model frame)).

        û = α·û_r + β·û_v integrated over ``dt``, kept in the workspace box and the arm's reach.
        """
        cfg = self.config
        if self._p_ref is None:
            self._p_ref = self._to_plate(self.tip.position(q))
        p_ref = self._p_ref
        t_aim = t + self.lead_s
        self._t_now = t
        p_hat, v_hat, a_hat = self.forecast.at(t_aim) if self.forecast.ready else (np.full(3, np.nan),) * 3
        self._p_pred = p_hat
        pred_ok = _finite(p_hat) and _finite(v_hat) and _finite(a_hat)
        ff = v_hat if cfg.reactive_feedforward else None
        u_r = reactive_velocity(p_hat, p_ref, cfg.reactive_gain, cfg.reactive_max_speed, ff) if pred_ok \
            else np.zeros(3)
        n_th = self.shoulder.n_channels
        th = np.asarray(voluntary, dtype=float) if voluntary is not None else np.full(n_th, np.nan)
        shoulder_ok = th.shape == (n_th,) and _finite(th)
        u_v = self.shoulder.tip_velocity(th) if shoulder_ok else np.zeros(3)
        if fe.predicting_for_s > cfg.stale_after_s:
            why = f"no fork measurement for {fe.predicting_for_s:.2f} s: control handed to the wearer"
            faults.append(("stale_fork_sensor", why))
            alpha, beta = 0.0, 1.0
            self.arbiter.decide(t, None, available=False)
        else:
            d = self.arbiter.decide(t, self._gate_proba, self._novelty, pred_ok, self._window_ready,
                                    mode_proba=self._mode_proba, u_r=u_r if pred_ok else None,
                                    u_v=u_v if shoulder_ok else None)
            alpha, beta = d.alpha, d.beta
        self._acc_ff = alpha * a_hat if pred_ok and cfg.reactive_feedforward else np.zeros(3)
        if shoulder_ok:
            u = fuse(alpha, u_r, beta, u_v)
        else:
            faults.append(("invalid_shoulder", f"shoulder signal NaN, missing or not ({n_th},): reference held"))
            u = np.zeros(3)
            self._acc_ff = np.zeros(3)
        self._preview = PreviewPlan(alpha if pred_ok else 0.0, beta, u_v, t_aim)
        p_new, u = self._bound_reference(p_ref, u, dt, faults)
        p_model = self._to_model(p_new)
        self._p_ref = p_new
        return alpha, beta, u, p_model

    def _bound_reference(self, p_ref: np.ndarray, u: np.ndarray, dt: float, faults: list[tuple[str, str]]
                         ) -> tuple[np.ndarray, np.ndarray]:
        """p_ref + u·dt kept in the workspace box ∩ the arm's reach (:func:`bound_reference`)."""
        p_new, u, self._acc_ff, fault = bound_reference(p_ref + u * dt, u, self._acc_ff, self._box,
                                                        self._to_plate(self.reach.pivot), self.reach.r_min,
                                                        self.reach.r_max)
        if fault is not None:
            faults.append(("reference_unreachable", fault))
        return p_new, u

    def _track(self, q: np.ndarray, v: np.ndarray, u: np.ndarray, p_model: np.ndarray,
               faults: list[tuple[str, str]], timings: dict[str, float]):
        """Smooth the reference (ruckig), plan with the MPC when there is one, and step the QP."""
        ta = time.perf_counter()
        if not self.smoother.initialized:
            self.smoother.reset(self.tip.position(q))
        u_model = self._pose[:3, :3].T @ u
        if self.config.smoother_target == "position":
            sm = self.smoother.update(p_model + self.config.smoother_lead_s * u_model)
        else:
            sm = self.smoother.update(p_model, u_model, self._pose[:3, :3].T @ self._acc_ff)
        timings["smoothing"] = time.perf_counter() - ta
        p_qp, v_qp, a_qp = sm.position, sm.velocity, sm.acceleration
        if self.mpc_follower is not None:
            ta = time.perf_counter()
            if self.keepout is not None and callable(getattr(self.mpc, "set_zones", None)):
                self.mpc.set_zones(self.keepout.limit.zones)  # the MPC's horizon sees the zones moving
            refs = self.mpc_follower.step(q, v, lambda H: self._mpc_preview(sm, H), faults)
            if refs is not None:
                p_qp, v_qp, a_qp = refs
            timings["mpc"] = time.perf_counter() - ta
        ta = time.perf_counter()
        res = self.qp.step(q, v, p_qp, v_qp, a_qp)
        if self.keepout is not None:
            res = self.keepout.check(self.qp, q, v, res, faults)
        timings["qp"] = time.perf_counter() - ta
        if res.status is QPStatus.SOLVER_FAILED:
            faults.append(("qp_failed", res.reason))
        return res

    def _mpc_preview(self, sm, H: int) -> np.ndarray:
        """The MPC's reference (H+1, 3), model frame (:func:`mpcshare.control.preview.mpc_preview`)."""
        return mpc_preview(sm, H, self.dt, self._preview, self.forecast, self._pose[:3, :3],
                           enabled=self.config.mpc_preview, fast=self.fast, t_now=self._t_now,
                           mode_proba=self._mode_proba)
