"""What the online controller returns every step, and its settings.

The statuses of ``SharedController.step`` (:data:`STATUSES`, most severe first) and what the step does
in each (it never raises):

- ``internal_error``: an unexpected exception: brake toward the smoothed reference within limits (a
  failing gate or predictor only sets α = 0); ``invalid_joint_state`` (q or v NaN, wrong shape): the QP
  holds its last command; ``time_went_backwards`` (t ≤ previous t, or NaN): nothing updated, brake and
  hold; ``no_observation`` (no fork sample yet): brake and hold; ``qp_failed``: the QP's brake;
- ``keepout_robot``: the knife moved into a body zone's margin (never expected: the keep-out rows forbid
  it, :mod:`mpcshare.control.keepout`); ``keepout_retreat``: the rows and the limits cannot all be met:
  the safest feasible action (retreat, else stop); ``keepout_person``: the wearer moved onto a knife
  that was not moving into them;
- ``stale_fork_sensor`` (fork predicted for > ``stale_after_s``): α = 0, β = 1, no reactive term;
  ``invalid_shoulder`` (NaN, wrong shape): û = 0, reference held; ``mpc_timeout``, ``mpc_failed``: the
  QP tracks the smoothed reference alone;
- ``invalid_observation_shape``, ``missing_observation`` (NaN channels, a repeated sample): the Kalman
  prediction stands in; ``keepout_stale_zone`` (fork marker lost): the hand and forearm zones grow with
  its age; ``invalid_base_pose``: the last valid pose kept (none yet: the arm held);
  ``reference_unreachable``: the reference clamped to the workspace box and reach shell.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mpcshare.control.keepout import KeepOutSettings
from mpcshare.control.workspace import DEFAULT_WORKSPACE, WorkspaceBox
from mpcshare.errors import ControllerSetupError
from robot.floor import FloorConfig
from robot.qp import QPConfig

__all__ = ["DEFAULT_BETA", "SMOOTHER_TARGETS", "STATUSES", "ControlCommand", "ControllerConfig"]

#: The user's β ∈ [0, 1] (the wearer's weight while the robot leads) when none is given:
#: ``SharedController``, ``Arbiter``, the experiments and ``mpcshare sim --beta`` read it here.
DEFAULT_BETA: float = 0.5

#: What the reference smoother aims at: the reference's position (moved ``smoother_lead_s``
#: ahead along the fused velocity), or its whole state (position, velocity, acceleration).
SMOOTHER_TARGETS: tuple[str, ...] = ("position", "state")

#: Status names, most severe first.
STATUSES: tuple[str, ...] = (
    "internal_error", "invalid_joint_state", "time_went_backwards", "no_observation", "qp_failed", "keepout_robot",
    "keepout_retreat", "keepout_person", "stale_fork_sensor", "invalid_shoulder", "mpc_timeout",
    "mpc_failed", "invalid_observation_shape", "missing_observation", "keepout_stale_zone", "invalid_base_pose",
    "reference_unreachable", "ok")


@dataclass
class ControlCommand:
    """One control period's output (docs/design.md, "Online control").

    tau [N·m], q_cmd [rad], v_cmd [rad/s] (state to reach at t + dt), a_cmd [rad/s²]
    (constant over the period); alpha, beta; mode_proba (K,); novelty (−log predictive
    density); tip_reference (3,) plate frame [m]; status, reasons; timings [s] per stage;
    predicted_tip (3,) plate frame [m] (NaN without a prediction); fork_velocity (d_o,).
    """

    tau: np.ndarray
    q_cmd: np.ndarray
    v_cmd: np.ndarray
    a_cmd: np.ndarray
    alpha: float
    beta: float
    mode_proba: np.ndarray
    novelty: float
    tip_reference: np.ndarray
    status: str
    reasons: tuple[str, ...]
    timings: dict[str, float]
    predicted_tip: np.ndarray = field(default_factory=lambda: np.full(3, np.nan))
    fork_velocity: np.ndarray = field(default_factory=lambda: np.zeros(0))


@dataclass
class ControllerConfig:
    """Settings of the loop.

    reactive_gain [1/s], reactive_max_speed [m/s]: û_r = sat(k·(p̂ − p_ref));
    stale_after_s [s]: fork sensor predicted for longer → stale; max_dt [s]: longest
    integration step of the reference; smoother limits [m/s], [m/s²], [m/s³];
    mpc_deadline_s [s]; mpc_every: solve the MPC every n-th step and follow the last
    plan in between (shifted by the steps since its solve); detect_stale: a fork sample equal
    to the previous one counts as missing (a frozen sensor); min_dwell_s [s]: the least time between two
    hand-overs (see ``Arbiter``);
    workspace (plate frame), reach_margin [m]; qp: ``robot.qp.QPConfig``;
    forecast_lead_s [s]: the reactive term aims at the forecast this far ahead (the latency
    after the reference: smoother, QP, servo; docs/design.md, "Latency budget");
    reactive_feedforward: add the forecast's velocity (and acceleration, to the smoother)
    to the reactive term; mpc_preview: the MPC's reference over its horizon is the fused
    forecast (else the smoothed reference extrapolated at constant velocity); forecast_fade_s [s]:
    cross-fade between successive forecasts (None: one model period; 0: none, measured best);
    smoother_target (:data:`SMOOTHER_TARGETS`) and smoother_lead_s [s]; handover_s [s]: the
    gate's α ramp between the robot and the wearer (see ``Arbiter``); novelty_persist_s [s]: the
    novelty override acts once the novelty has stayed above the bundle's threshold this long (see
    ``Arbiter``); strategy_settings: the strategy's settings (an instance of its registry spec's ``settings``
    class, e.g. :class:`~mpcshare.control.strategies.gate.GateSettings`, or a mapping of its fields), which
    replace the bundle's calibrated rule; None: the bundle's rule where it is for this strategy, else the
    strategy's defaults;
    keepout: the wearer's body zones kept out of the knife's way
    (:class:`~mpcshare.control.keepout.KeepOutSettings`; None: off);
    fast_forecast: use the bundle's control-rate forecast when it has one (else, or False: the
    10 Hz forecast alone); fast_lead_s [s]: the aim ahead with the control-rate forecast
    (replaces forecast_lead_s); floor_z [m] (plate frame; None: off): the knife's hard floor, the
    plate's top less a tolerance: QP rows keep the blade above it (:class:`robot.floor.FloorLimit`,
    ``floor``: its settings) and the workspace box's floor is raised to it.
    """

    # the gain, caps, smoother limits, mpc_every and novelty_persist_s as measured: docs/results.md,
    # "The controller's defaults"
    reactive_gain: float = 20.0
    reactive_max_speed: float = 1.0
    stale_after_s: float = 0.5
    max_dt: float = 0.05
    max_velocity: float = 1.2
    max_acceleration: float = 10.0
    max_jerk: float = 200.0
    mpc_deadline_s: float = 0.003
    mpc_every: int = 2
    min_dwell_s: float = 0.5
    detect_stale: bool = True
    workspace: WorkspaceBox = DEFAULT_WORKSPACE
    reach_margin: float = 0.01
    qp: QPConfig = field(default_factory=QPConfig)
    forecast_lead_s: float = 0.01
    reactive_feedforward: bool = True
    mpc_preview: bool = True
    smoother_target: str = "position"
    forecast_fade_s: float | None = 0.0
    smoother_lead_s: float = 0.05
    handover_s: float = 0.5
    novelty_persist_s: float = 0.3
    strategy_settings: Any = None
    keepout: KeepOutSettings | None = field(default_factory=KeepOutSettings)
    fast_forecast: bool = True
    fast_lead_s: float = 0.03
    floor_z: float | None = -0.01
    floor: FloorConfig = field(default_factory=FloorConfig)

    def __post_init__(self) -> None:
        if self.smoother_target not in SMOOTHER_TARGETS:
            raise ControllerSetupError(f"smoother_target {self.smoother_target!r} not in {list(SMOOTHER_TARGETS)}")
        for name in ("forecast_lead_s", "smoother_lead_s", "handover_s", "fast_lead_s", "novelty_persist_s"):
            v = getattr(self, name)
            if not (math.isfinite(v) and 0.0 <= v <= 1.0):
                raise ControllerSetupError(f"ControllerConfig.{name} must be in [0, 1] s, got {v!r}")
        if self.floor_z is not None and not (math.isfinite(self.floor_z)
                                             and self.floor_z < self.workspace.upper[2]):
            raise ControllerSetupError(f"ControllerConfig.floor_z must be None or finite and below the workspace's "
                                       f"top {self.workspace.upper[2]} m, got {self.floor_z!r}")
        if self.forecast_fade_s is not None and not (math.isfinite(self.forecast_fade_s) and self.forecast_fade_s >= 0):
            raise ControllerSetupError(f"ControllerConfig.forecast_fade_s must be None or >= 0, "
                                       f"got {self.forecast_fade_s!r}")
