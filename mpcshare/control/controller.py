"""The online shared controller: one :meth:`SharedController.step` every 10 ms (docs/design.md, "Online control").

Each step, as stages that return typed records (:mod:`mpcshare.control.records`):

1. sense (:mod:`mpcshare.control.sensing`): the front end (:mod:`mpcshare.control.frontend`), on 10 Hz
   ticks the gate and the streaming predictor, the forecast tip p̂(·) (:class:`~mpcshare.control.forecast.ForecastTrack`,
   re-made every step by :mod:`mpcshare.control.fastpath` where the bundle has it);
2. arbitrate (:mod:`mpcshare.control.arbitration`, :mod:`mpcshare.control.strategies`): α, β and
   û = α·û_r + β·û_v [m/s], û_r = sat(ṗ̂(t + τ) + k·(p̂(t + τ) − p_ref)), τ = ``forecast_lead_s``;
   û integrated into the plate-frame reference p_ref, clamped by :mod:`mpcshare.control.workspace`;
3. track: ``robot.smoothing.ReferenceSmoother`` (ruckig) toward p_ref, the optional MPC on the preview
   r_k = p_s + α·(p̂(t + τ + k·dt) − p̂(t + τ)) + β·û_v·k·dt (:mod:`mpcshare.control.preview`, followed
   between solves by :class:`~mpcshare.control.mpc_follow.MPCFollower`), then ``robot.qp.QPController``,
   which enforces the joint limits and, above tracking, the keep-out (:mod:`mpcshare.control.keepout`);
   a failed or late MPC leaves the QP tracking the smoothed reference;
4. command: :class:`~mpcshare.control.types.ControlCommand`.

``step`` never raises: every fault gives a safe command and a status, the most severe of the step's
faults (:data:`~mpcshare.control.types.STATUSES`, each listed with what the step does; ``reasons`` lists
every fault).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from mpcshare.control.arbitration import check_beta, check_strategy, fuse, reactive_velocity
from mpcshare.control.builder import ControllerParts, build_parts
from mpcshare.control.forecast import TipTrajectory
from mpcshare.control.holding import brake, fallback_joint_state, rest_command
from mpcshare.control.party_fusion import PartyState, advance, smooth
from mpcshare.control.preview import PreviewPlan, mpc_preview
from mpcshare.control.records import Arbitration, Sensed, TickState, Tracking
from mpcshare.control.sensing import fast_step, models_tick, sense
from mpcshare.control.types import DEFAULT_BETA, STATUSES, ControlCommand, ControllerConfig
from mpcshare.control.workspace import bound_reference, check_base_pose
from mpcshare.errors import ControllerSetupError
from robot.description import RobotDescription
from robot.qp import QPResult, QPStatus
from robot.shoulder import ShoulderMap
from robot.smoothing import ReferenceSmoother

if TYPE_CHECKING:  # annotations only: importing the bundle module pulls in torch
    from mpcshare.bundle import ModelBundle

__all__ = ["STATUSES", "ControlCommand", "ControllerConfig", "EpisodeState", "SharedController"]

_RANK = {s: i for i, s in enumerate(STATUSES)}
_NO_FORECAST = (np.full(3, np.nan),) * 3


def _finite(x: np.ndarray) -> bool:
    """True when every entry of the array ``x`` is finite (plain floats: on a few entries, cheaper than numpy)."""
    return all(map(math.isfinite, x.ravel().tolist()))


@dataclass
class EpisodeState:
    """What the controller carries from one step to the next, forgotten by ``reset``: the smoother, the
    predictor's stream, the last step's time [s], the base pose (4, 4) in force, the tip reference (plate frame;
    None before the first step), the learned parts' outputs held since the last model tick, the last forecast tip
    and fork velocity (reported while holding) and the last command."""

    smoother: ReferenceSmoother
    stream: Any
    pose: np.ndarray | None
    tick: TickState
    last_t: float = -math.inf
    p_ref: np.ndarray | None = None
    p_pred: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    fork_velocity: np.ndarray = field(default_factory=lambda: np.zeros(0))
    last: ControlCommand | None = None
    parties: PartyState | None = None  # the parties' own reference chains where the QP fuses them


class SharedController:
    """Shared control of an arm's knife tip from a trained bundle (module docstring); ``robot``: any
    ``RobotDescription`` (a ``SuperLimbParams`` or None: the SuperLimb). Build with :meth:`from_bundle`.
    ``base_pose``: the arm's mount, T_plate_torso (4×4) with the torso at rest (``mpcshare.arms.rest_base_pose``),
    used until a step gives one; None: the steps must give it (a step before any was given holds the
    arm, status ``invalid_base_pose``). Misuse at construction raises ``mpcshare.errors.ControllerSetupError``
    (a ValueError; ``ControllerTypeError``: also a TypeError) naming what is wrong (channels, strategy, β,
    shapes, the base pose …).
    Its parts (:class:`~mpcshare.control.builder.ControllerParts`, built once) are ``parts`` and, by name,
    attributes of the controller (``qp``, ``arbiter``, ``forecast`` …); the episode's state is ``state``.
    """

    def __init__(self, bundle: ModelBundle, *, robot: RobotDescription | None = None, strategy: str = "gate",
                 beta: float = DEFAULT_BETA, use_mpc: bool = False, shoulder: ShoulderMap | None = None,
                 tip_channels: tuple[str, str, str] | None = None,
                 fork_channels: tuple[str, str, str] | None = None, mpc=None,
                 config: ControllerConfig | None = None, preview: TipTrajectory | None = None,
                 schedule: Callable[[float], float] | None = None, frontend: Any = None,
                 base_pose: np.ndarray | None = None) -> None:
        try:
            self.base_pose = None if base_pose is None else check_base_pose(base_pose)
        except ValueError as exc:
            raise ControllerSetupError(str(exc)) from None
        self.parts: ControllerParts = build_parts(
            bundle, robot=robot, strategy=strategy, beta=beta, use_mpc=use_mpc, shoulder=shoulder,
            tip_channels=tip_channels, fork_channels=fork_channels, mpc=mpc, config=config, preview=preview,
            schedule=schedule, frontend=frontend)
        self.reset()

    def __getattr__(self, name: str) -> Any:
        """The parts by name (``ctl.qp`` is ``ctl.parts.qp``)."""
        parts = self.__dict__.get("parts")
        if parts is not None and name in ControllerParts.__dataclass_fields__:
            return getattr(parts, name)
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

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
        (t → α ∈ {0, 1} with strategy ``schedule``: a replayed hand-over schedule), ``frontend`` (an object
        with ``step(t, obs) -> FrontEndOutput`` and ``reset()`` in place of the streaming front end, e.g. one
        that replays recorded outputs; :mod:`mpcshare.control.sensing`), ``base_pose`` (the mount, T_plate_torso at
        rest: see the class).
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
        return self.parts.arbiter.handovers

    @property
    def smoother(self) -> ReferenceSmoother:
        """The episode's reference smoother."""
        return self.state.smoother

    def reset(self) -> None:
        """Start a new episode: filters, predictor state, reference and logs forgotten."""
        p, cfg = self.parts, self.parts.config
        p.frontend.reset()
        if p.keepout is not None:
            p.keepout.reset()
        p.arbiter.reset()
        p.qp.reset()
        if p.mpc_follower is not None:
            p.mpc_follower.reset()
        p.forecast.reset()
        if p.fast is not None:
            p.fast.reset()
        K = p.layout.n_modes
        self.state = EpisodeState(
            smoother=ReferenceSmoother(3, p.dt, cfg.max_velocity, cfg.max_acceleration, cfg.max_jerk),
            stream=p.bundle.predictor.make_stream(), pose=None if self.base_pose is None else self.base_pose.copy(),
            tick=TickState(np.full(K, 1.0 / K), float("nan"), False, None),
            fork_velocity=np.zeros(p.layout.d_o),
            parties=PartyState.new(p.dt, cfg) if p.arbiter.spec.fusion == "qp" else None)
        self._set_floor(self.state.pose)

    # ------------------------------------------------------------------ frames
    def _set_floor(self, pose: np.ndarray | None) -> None:
        """The floor z_plate ≥ floor_z in the model frame: n = Rᵀ·e_z, n·p ≥ floor_z − t_z (none before a pose)."""
        if self.parts.floor is not None and pose is not None:
            self.parts.floor.set_plane(pose[2, :3], self.parts.config.floor_z - pose[2, 3])

    def _to_plate(self, p: np.ndarray) -> np.ndarray:
        """A model-frame point in the plate frame under the base pose in force."""
        pose = self.state.pose
        return pose[:3, :3] @ p + pose[:3, 3]

    # ------------------------------------------------------------------ the loop
    def step(self, t: float, obs, voluntary, q, v, base_pose=None) -> ControlCommand:
        """One control period (module docstring). Never raises."""
        t0 = time.perf_counter()
        try:
            return self._step(t0, t, obs, voluntary, q, v, base_pose)
        except Exception as exc:  # noqa: BLE001 — last line of defence: brake within limits, say why
            reason = f"{type(exc).__name__}: {exc}"
            p, s = self.parts, self.state
            qa, va = fallback_joint_state(q, v, p.qp.n)
            try:
                faults = [("internal_error", reason)]
                return self._command(brake(p.qp, p.keepout, s.smoother, p.tip, qa, va, faults), 0.0, 1.0, None,
                                     faults, {}, t0)
            except Exception:  # noqa: BLE001 — even the QP failed: repeat the last command at rest
                return rest_command(p.qp.n, s.last, s.tick.mode_proba, s.tick.novelty, reason, t0)

    def _step(self, t0: float, t, obs, voluntary, q, v, base_pose) -> ControlCommand:
        p, s = self.parts, self.state
        faults: list[tuple[str, str]] = []
        timings: dict[str, float] = {}
        n = p.qp.n
        q = np.asarray(q, dtype=float) if np.size(q) == n else np.full(n, np.nan)
        v = np.asarray(v, dtype=float) if np.size(v) == n else np.full(n, np.nan)
        q, v = q.reshape(n), v.reshape(n)
        if not (_finite(q) and _finite(v)):
            faults.append(("invalid_joint_state", "q or v not finite or of the wrong shape: holding"))
            return self._command(p.qp.step(q, v), 0.0, 1.0, None, faults, timings, t0)
        t = float(t)
        if not t > s.last_t:
            faults.append(("time_went_backwards", f"t = {t!r} after {s.last_t!r}: holding"))
            return self._hold(q, v, faults, timings, t0)
        dt = min(t - s.last_t, p.config.max_dt)
        s.last_t = t
        if base_pose is not None:
            try:
                s.pose = check_base_pose(base_pose)
                self._set_floor(s.pose)
            except ValueError as exc:
                faults.append(("invalid_base_pose", f"{exc}: last valid pose kept"))
        if s.pose is None:
            faults.append(("invalid_base_pose", "no base pose yet (none given to the constructor or a step): holding"))
            return self._hold(q, v, faults, timings, t0)
        sensed = self._sense(t, dt, q, v, obs, faults, timings)  # 1. front end, learned parts, forecast
        if sensed is None:
            return self._hold(q, v, faults, timings, t0)
        ta = time.perf_counter()  # 2. arbitration and the tip reference
        arb = self._arbitrate(sensed, voluntary, faults)
        timings["arbitration"] = time.perf_counter() - ta
        tracking = self._track(sensed, arb, faults, timings)  # 3. smoothing, MPC, QP
        return self._command(tracking.result, arb.alpha, arb.beta, sensed, faults, timings, t0, arb.p_ref)

    def _sense(self, t: float, dt: float, q: np.ndarray, v: np.ndarray, obs, faults: list[tuple[str, str]],
               timings: dict[str, float]) -> Sensed | None:
        """The fork through the front end, the learned parts on their ticks, the forecast at t + τ; None when no
        fork sample was ever measured (:mod:`mpcshare.control.sensing`)."""
        p, s = self.parts, self.state
        ta = time.perf_counter()
        fe = sense(t, obs, faults, frontend=p.frontend, d_o=p.layout.d_o, stale_after_s=p.config.stale_after_s,
                   keepout=p.keepout, pose=s.pose)
        if fe is None:
            return None
        s.fork_velocity = fe.fork_velocity
        timings["frontend"] = time.perf_counter() - ta
        ta = time.perf_counter()
        if fe.tick is not None:
            s.tick = models_tick(t, fe.tick, stream=s.stream, gates=p.bundle.gates, layout=p.layout, fast=p.fast,
                                 forecast=p.forecast, oracle=p.oracle, faults=faults)
        timings["models"] = time.perf_counter() - ta
        if p.fast is not None:
            ta = time.perf_counter()
            fast_step(t, fe, s.tick.mode_proba, p.fast, p.forecast, faults)
            timings["fast"] = time.perf_counter() - ta
        t_aim = t + p.lead_s
        p_hat, v_hat, a_hat = p.forecast.at(t_aim) if p.forecast.ready else _NO_FORECAST
        s.p_pred = p_hat
        return Sensed(t, dt, q, v, s.pose, fe, s.tick, t_aim, p_hat, v_hat, a_hat,
                      _finite(p_hat) and _finite(v_hat) and _finite(a_hat))

    def _arbitrate(self, sensed: Sensed, voluntary, faults: list[tuple[str, str]]) -> Arbitration:
        """α, β and the new tip reference: û = α·û_r + β·û_v integrated over the step, kept in the workspace box
        and the arm's reach (the reference is the episode's: read and written back here); with a strategy whose
        fusion is ``qp``, each party's own chain and their blend (:mod:`mpcshare.control.party_fusion`)."""
        p, s, cfg = self.parts, self.state, self.parts.config
        pose = sensed.pose
        if s.p_ref is None:
            s.p_ref = self._to_plate(p.tip.position(sensed.q))
        p_ref = s.p_ref
        pred_ok, tick = sensed.forecast_ok, sensed.tick
        ff = sensed.v_hat if cfg.reactive_feedforward else None
        u_r = reactive_velocity(sensed.p_hat, p_ref, cfg.reactive_gain, cfg.reactive_max_speed, ff) if pred_ok \
            else np.zeros(3)
        n_th = p.shoulder.n_channels
        th = np.asarray(voluntary, dtype=float) if voluntary is not None else np.full(n_th, np.nan)
        shoulder_ok = th.shape == (n_th,) and _finite(th)
        u_v = p.shoulder.tip_velocity(th) if shoulder_ok else np.zeros(3)
        if sensed.front.predicting_for_s > cfg.stale_after_s:
            why = f"no fork measurement for {sensed.front.predicting_for_s:.2f} s: control handed to the wearer"
            faults.append(("stale_fork_sensor", why))
            alpha, beta = 0.0, 1.0
            p.arbiter.decide(sensed.t, None, available=False)
        else:
            d = p.arbiter.decide(sensed.t, tick.gate_proba, tick.novelty, pred_ok, tick.window_ready,
                                 mode_proba=tick.mode_proba, u_r=u_r if pred_ok else None,
                                 u_v=u_v if shoulder_ok else None)
            alpha, beta = d.alpha, d.beta
        acc_ff = alpha * sensed.a_hat if pred_ok and cfg.reactive_feedforward else np.zeros(3)
        if shoulder_ok:
            u = fuse(alpha, u_r, beta, u_v)
        else:
            faults.append(("invalid_shoulder", f"shoulder signal NaN, missing or not ({n_th},): reference held"))
            u, acc_ff = np.zeros(3), np.zeros(3)
        plan = PreviewPlan(alpha if pred_ok else 0.0, beta, u_v, sensed.t_aim)
        pivot = self._to_plate(p.reach.pivot)
        parties = None
        if s.parties is None:
            p_new, u, acc_ff, fault = bound_reference(p_ref + u * sensed.dt, u, acc_ff, p.box, pivot, p.reach.r_min,
                                                      p.reach.r_max)
            if fault is not None:
                faults.append(("reference_unreachable", fault))
        else:  # fusion in the QP: each party's chain, the blend as the step's reference (mpcshare.control.party_fusion)
            parties, bound_faults = advance(
                s.parties, alpha, p_ref, sensed.p_hat, sensed.v_hat, sensed.a_hat, pred_ok and shoulder_ok,
                u_v if shoulder_ok else np.zeros(3), sensed.dt, cfg,
                lambda x, vel, acc: bound_reference(x, vel, acc, p.box, pivot, p.reach.r_min, p.reach.r_max),
                p.arbiter.settings.wearer_offset_m)
            faults += [("reference_unreachable", f) for f in bound_faults]
            beta = 1.0 - alpha
            p_new = alpha * parties.p_r + beta * parties.p_v
            u, acc_ff = alpha * parties.u_r + beta * parties.u_v, alpha * parties.acc_r
        s.p_ref = p_new
        p_model = pose[:3, :3].T @ (p_new - pose[:3, 3])
        return Arbitration(alpha, beta, u, p_new, p_model, acc_ff, plan, parties)

    def _track(self, sensed: Sensed, arb: Arbitration, faults: list[tuple[str, str]],
               timings: dict[str, float]) -> Tracking:
        """Smooth the reference (ruckig), plan with the MPC when there is one, and step the QP."""
        p, cfg, smoother = self.parts, self.parts.config, self.state.smoother
        q, v, R = sensed.q, sensed.v, sensed.pose[:3, :3]
        ta = time.perf_counter()
        if not smoother.initialized:
            smoother.reset(p.tip.position(q))
        u_model = R.T @ arb.u
        if cfg.smoother_target == "position":
            sm = smoother.update(arb.p_model + cfg.smoother_lead_s * u_model)
        else:
            sm = smoother.update(arb.p_model, u_model, R.T @ arb.acc_ff)
        # fusion in the QP: each party's own smoothed reference, (robot, wearer) in the model frame
        both = None if arb.parties is None else smooth(self.state.parties, arb.parties, sensed.pose, p.tip.position(q),
                                                       cfg)
        timings["smoothing"] = time.perf_counter() - ta
        p_qp, v_qp, a_qp = sm.position, sm.velocity, sm.acceleration
        if p.mpc_follower is not None:
            ta = time.perf_counter()
            if p.keepout is not None and callable(getattr(p.mpc, "set_zones", None)):
                p.mpc.set_zones(p.keepout.limit.zones)  # the MPC's horizon sees the zones moving
            refs = p.mpc_follower.step(q, v, lambda H: self.mpc_preview(sm, H, sensed, arb), faults)
            if refs is not None:
                p_qp, v_qp, a_qp = refs
            timings["mpc"] = time.perf_counter() - ta
        ta = time.perf_counter()
        if both is None:
            res = p.qp.step(q, v, p_qp, v_qp, a_qp)
        else:  # both parties' smoothed references in the QP's tip cost, weighted α and 1 − α
            robot, wearer = both
            a = arb.parties.alpha
            p.qp.tip_task.set_second(1.0 - a, wearer.position, wearer.velocity, wearer.acceleration)
            try:
                res = p.qp.step(q, v, robot.position, robot.velocity, robot.acceleration)
            finally:
                p.qp.tip_task.clear_second()
            p_qp = a * robot.position + (1.0 - a) * wearer.position
        if p.keepout is not None:
            res = p.keepout.check(p.qp, q, v, res, faults)
        timings["qp"] = time.perf_counter() - ta
        if res.status is QPStatus.SOLVER_FAILED:
            faults.append(("qp_failed", res.reason))
        return Tracking(res, p_qp)

    def mpc_preview(self, sm, H: int, sensed: Sensed, arb: Arbitration) -> np.ndarray:
        """The MPC's reference (H+1, 3), model frame, from the smoothed state ``sm`` and this step's records
        (:func:`mpcshare.control.preview.mpc_preview`)."""
        p = self.parts
        return mpc_preview(sm, H, p.dt, arb.plan, p.forecast, sensed.pose[:3, :3], enabled=p.config.mpc_preview,
                           fast=p.fast, t_now=sensed.t, mode_proba=sensed.tick.mode_proba)

    # ------------------------------------------------------------------ commands
    def _hold(self, q: np.ndarray, v: np.ndarray, faults, timings, t0) -> ControlCommand:
        """Brake toward the current smoothed reference (or the measured tip) within the limits."""
        p = self.parts
        return self._command(brake(p.qp, p.keepout, self.state.smoother, p.tip, q, v, faults), 0.0, 1.0, None,
                             faults, timings, t0)

    def _command(self, res: QPResult, alpha: float, beta: float, sensed: Sensed | None,
                 faults: list[tuple[str, str]], timings: dict[str, float], t0: float,
                 reference: np.ndarray | None = None) -> ControlCommand:
        """The step's command: the QP's answer, α, β, the most severe fault as the status; ``sensed`` None: a held
        step, reporting what the episode last sensed; ``reference``: the new tip reference (None: the episode's)."""
        s = self.state
        status = min((f[0] for f in faults), key=_RANK.__getitem__, default="ok")
        timings["total"] = time.perf_counter() - t0
        ref = reference if reference is not None else s.p_ref
        ref = ref.copy() if ref is not None else np.full(3, np.nan)
        tick = s.tick if sensed is None else sensed.tick
        cmd = ControlCommand(tau=np.array(res.tau), q_cmd=np.array(res.q_next), v_cmd=np.array(res.v_next),
                             a_cmd=np.array(res.a), alpha=float(alpha), beta=float(beta),
                             mode_proba=tick.mode_proba.copy(), novelty=tick.novelty, tip_reference=ref,
                             status=status, reasons=tuple(f"{s_}: {r}" for s_, r in faults), timings=timings,
                             predicted_tip=s.p_pred.copy(), fork_velocity=s.fork_velocity.copy())
        s.last = cmd
        return cmd
