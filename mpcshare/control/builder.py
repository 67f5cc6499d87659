"""The one builder of :class:`~mpcshare.control.controller.SharedController`: every part it runs, made once
from a bundle, an arm and the settings (:func:`build_parts`), with the QP built once with its whole
constraint list (:func:`build_qp`: the torque limit, the knife's floor, the keep-out rows).

Misuse raises ``mpcshare.errors.ControllerSetupError`` (a ValueError; ``ControllerTypeError``: also a
TypeError; RuntimeError for a missing optional part) naming what is wrong.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any, Callable

import numpy as np

from mpcshare.control.arbitration import Arbiter, check_beta, check_strategy
from mpcshare.control.bundle_inputs import (
    BundleLayout,
    bundle_task,
    check_bundle,
    mode_figures,
    rule_settings,
    shoulder_map,
)
from mpcshare.control.fastpath import FastPath
from mpcshare.control.forecast import ForecastTrack, TipTrajectory
from mpcshare.control.frontend import StreamingFrontEnd
from mpcshare.control.keepout import KeepOut, KeepOutSettings
from mpcshare.control.mpc_follow import MPCFollower
from mpcshare.control.strategies import REGISTRY
from mpcshare.control.types import ControllerConfig
from mpcshare.errors import ControllerSetupError, ControllerTypeError
from robot.constraints import TorqueLimit
from robot.default_arm import as_description
from robot.description import RobotDescription
from robot.floor import FloorLimit
from robot.keepout import KeepOutLimit
from robot.kinematics import TipKinematics
from robot.qp import QPConfig, QPController
from robot.shoulder import ShoulderMap
from robot.tasks import BlendedTipTrackingTask

if TYPE_CHECKING:  # annotations only: importing the bundle module pulls in torch
    from mpcshare.bundle import ModelBundle

__all__ = ["ControllerParts", "build_parts", "build_qp", "make_keepout_mpc", "make_mpc"]


@dataclass(frozen=True)
class ControllerParts:
    """What the controller runs, built once (:func:`build_parts`); the per-episode state is the controller's.

    box: (lower, upper) of the workspace [m], plate frame, its floor raised to ``config.floor_z``; lead_s [s]: the
    aim ahead of the forecast; oracle: ``forecast`` is a given trajectory (the ``oracle_preview`` bound), not the
    predictor's; fast: the control-rate forecast or None.
    """

    bundle: Any
    config: ControllerConfig
    strategy: str
    beta_user: float
    layout: BundleLayout
    shoulder: ShoulderMap
    robot: RobotDescription
    dt: float
    floor: FloorLimit | None
    qp: QPController
    keepout: KeepOut | None
    mpc: Any
    mpc_follower: MPCFollower | None
    tip: TipKinematics
    reach: Any
    box: tuple[np.ndarray, np.ndarray]
    frontend: Any
    arbiter: Arbiter
    fast: FastPath | None
    lead_s: float
    forecast: TipTrajectory
    oracle: bool


def _qp_config(robot: RobotDescription, config: QPConfig, dt: float) -> QPConfig:
    """``config`` at period ``dt`` [s], its posture defaulting to the arm's home posture."""
    if abs(config.dt - dt) >= 1e-12:
        config = QPConfig(**{**config.__dict__, "dt": dt})
    if config.q_posture is None:
        config = QPConfig(**{**config.__dict__, "q_posture": robot.q_home})
    return config


def build_qp(robot: RobotDescription, config: ControllerConfig, dt: float, *, blended: bool = False
             ) -> tuple[QPController, KeepOut | None, FloorLimit | None]:
    """The joint QP on ``robot``'s tip frame at period ``dt`` [s] with its whole constraint list: with the keep-out
    (``config.keepout``) or the floor (``config.floor_z``), the torque limit, the floor rows and the keep-out rows
    (sharing the blade's kinematics where the heel is the same); else the QP's default rows. ``blended``: its tip
    task weighs two parties' references (``robot.tasks.BlendedTipTrackingTask``). Returns the QP, the
    keep-out (None: off) and the floor (None: off; its plane is set per step from the base pose)."""
    settings = config.keepout
    heel = settings.heel_offset if settings is not None else KeepOutSettings().heel_offset
    floor = None if config.floor_z is None else FloorLimit(robot.model, robot.tip_frame, heel, config.floor)
    qp_config = _qp_config(robot, config.qp, dt)
    tip_task = BlendedTipTrackingTask(qp_config.tip_weight, qp_config.tip_kp, qp_config.tip_kd,
                                      qp_config.tip_max_error) if blended else None
    if settings is None and floor is None:
        return QPController(robot.model, robot.tip_frame_id, robot.limits, qp_config, tip_task=tip_task), None, None
    shared = floor.blade if floor is not None and settings is not None and \
        np.array_equal(floor.blade.heel_offset, np.asarray(settings.heel_offset, dtype=float)) else None
    limit = None if settings is None else KeepOutLimit(robot.model, robot.tip_frame, settings.heel_offset,
                                                         settings.limit, blade=shared)
    rows: list = [TorqueLimit(robot.limits)] + ([floor] if floor is not None else []) + \
        ([limit] if limit is not None else [])
    qp = QPController(robot.model, robot.tip_frame, robot.limits, qp_config, constraints=rows, tip_task=tip_task)
    return qp, None if limit is None else KeepOut(settings, limit), floor


def make_mpc(robot: RobotDescription, dt: float):
    """The CasADi tip MPC (``robot.mpc.tip_mpc.TipMPC``) for ``robot`` at period ``dt`` [s]."""
    try:
        from robot.mpc.tip_mpc import TipMPC
    except ImportError as exc:
        raise RuntimeError("use_mpc=True needs robot.mpc.tip_mpc.TipMPC, which cannot be imported "
                           f"({exc}); pass use_mpc=False to run the QP on the smoothed reference") from exc
    mpc = TipMPC(robot, dt=dt)
    if int(mpc.horizon) < 2:
        raise ControllerSetupError(f"the MPC horizon must be ≥ 2 steps, got {mpc.horizon}")
    return mpc


def make_keepout_mpc(robot: RobotDescription, dt: float, settings: KeepOutSettings):
    """The tip MPC of ``robot`` with the body zones over its horizon (``robot.mpc.keepout_mpc``), imported
    when used."""
    from robot.mpc.keepout_mpc import KeepOutTipMPC

    lim = settings.limit
    return KeepOutTipMPC(robot, dt=dt, max_zones=lim.max_zones, margin=lim.margin,
                         active_distance=lim.active_distance_m)


def build_parts(bundle: ModelBundle, *, robot: RobotDescription | None = None, strategy: str = "gate",
                beta: float, use_mpc: bool = False, shoulder: ShoulderMap | None = None,
                tip_channels: tuple[str, str, str] | None = None, fork_channels: tuple[str, str, str] | None = None,
                mpc: Any = None, config: ControllerConfig | None = None, preview: TipTrajectory | None = None,
                schedule: Callable[[float], float] | None = None, frontend: Any = None) -> ControllerParts:
    """Every part of the controller (the arguments are :class:`~mpcshare.control.controller.SharedController`'s).
    ``frontend``: an object with ``step(t, obs) -> FrontEndOutput`` and ``reset()`` in place of the bundle's
    :class:`~mpcshare.control.frontend.StreamingFrontEnd` (e.g. one that replays recorded outputs); None: that."""
    check_strategy(strategy, scheduled=schedule is not None)
    beta_user = check_beta(beta)
    cfg = config or ControllerConfig()
    if cfg.keepout is not None and cfg.keepout.body is None:  # the body zones of the bundle's task
        cfg = replace(cfg, keepout=replace(cfg.keepout, body=bundle_task(bundle).body))
    layout = check_bundle(bundle, tip_channels, fork_channels)
    shoulder = shoulder_map(bundle, shoulder)
    arm = as_description(robot)  # TypeError naming the choices for anything else
    dt = 1.0 / float(bundle.rate_hz)
    in_qp = REGISTRY[strategy].fusion == "qp"
    if in_qp and (use_mpc or mpc is not None):
        raise ControllerSetupError(f"strategy {strategy!r} fuses the parties in the QP, which tracks each party's own "
                                   "reference: it runs without the MPC (use_mpc=False)")
    qp, keepout, floor = build_qp(arm, cfg, dt, blended=in_qp)
    if keepout is not None:
        keepout.bind(bundle.obs_names)
    zoned = cfg.keepout is not None and cfg.keepout.mpc_zones
    mpc = mpc if mpc is not None else None if not use_mpc else \
        make_keepout_mpc(arm, dt, cfg.keepout) if zoned else make_mpc(arm, dt)
    follower = None if mpc is None else MPCFollower(mpc, dt, cfg.mpc_deadline_s, cfg.mpc_every)
    lower = np.array(cfg.workspace.lower, dtype=float)
    if cfg.floor_z is not None:
        lower[2] = max(lower[2], cfg.floor_z)
    if frontend is not None and not (callable(getattr(frontend, "step", None))
                                     and callable(getattr(frontend, "reset", None))):
        raise ControllerTypeError(f"frontend must have step(t, obs) and reset(), got {type(frontend).__name__}")
    frontend = frontend if frontend is not None else StreamingFrontEnd(
        bundle.preprocessor.obs, bundle.modes, rate_hz=bundle.rate_hz, model_hz=bundle.model_hz,
        window_s=bundle.window_s, detect_stale=cfg.detect_stale)
    arbiter = Arbiter(strategy, beta, settings=rule_settings(bundle, strategy, cfg.strategy_settings),
                      novelty_threshold=float(bundle.novelty_threshold), min_dwell_s=cfg.min_dwell_s,
                      handover_s=cfg.handover_s, novelty_persist_s=cfg.novelty_persist_s, schedule=schedule,
                      figures=mode_figures(bundle))
    if preview is not None and not callable(getattr(preview, "sample", None)):
        raise ControllerTypeError(f"preview must be a TipTrajectory (sample(times)), got {type(preview).__name__}")
    oracle = preview is not None
    fast = FastPath(bundle, layout) if cfg.fast_forecast and getattr(bundle, "fast", None) is not None \
        and not oracle else None
    forecast = preview if preview is not None else ForecastTrack(1.0 / float(bundle.model_hz), cfg.forecast_fade_s)
    return ControllerParts(
        bundle=bundle, config=cfg, strategy=strategy, beta_user=beta_user, layout=layout, shoulder=shoulder,
        robot=arm, dt=dt, floor=floor, qp=qp, keepout=keepout, mpc=mpc, mpc_follower=follower,
        tip=TipKinematics(qp.model, arm.tip_frame), reach=arm.reach_shell(cfg.reach_margin),
        box=(lower, np.array(cfg.workspace.upper, dtype=float)), frontend=frontend, arbiter=arbiter, fast=fast,
        lead_s=cfg.fast_lead_s if fast is not None else cfg.forecast_lead_s, forecast=forecast, oracle=oracle)
