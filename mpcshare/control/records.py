"""The typed records the stages of :meth:`SharedController.step <mpcshare.control.controller.SharedController.step>`
hand each other: what was sensed (:class:`Sensed`), the arbitration (:class:`Arbitration`) and the tracking
(:class:`Tracking`). Each stage takes the records of the stages before it and returns its own; none reads what
another left on the controller. Positions [m], velocities [m/s], accelerations [m/s²]; "plate" is the plate
frame, "model" the arm's model frame (docs/design.md, "Online control")."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from mpcshare.control.frontend import FrontEndOutput
from mpcshare.control.party_fusion import PartyReferences
from mpcshare.control.preview import PreviewPlan
from robot.qp import QPResult

__all__ = ["Arbitration", "Sensed", "TickState", "Tracking"]


class TickState(NamedTuple):
    """The learned parts' outputs of the last model tick, held until the next one."""

    mode_proba: np.ndarray  # (K,) the mode posterior
    novelty: float  # the window's novelty score
    window_ready: bool  # whether the anti-aliased 10 Hz window is full
    gate_proba: float | None  # the gate's probability of the most probable mode (None: no window or it failed)


class Sensed(NamedTuple):
    """What the step sensed: the arm, the base, the fork through the front end, the learned parts and the
    forecast of the tip at the aimed time."""

    t: float  # the step's time [s]
    dt: float  # the reference's integration step [s] (the time since the last step, at most max_dt)
    q: np.ndarray  # (n,) joint positions [rad]
    v: np.ndarray  # (n,) joint velocities [rad/s]
    pose: np.ndarray  # (4, 4) the base pose T_plate_model in force
    front: FrontEndOutput  # the front end's output of this sample
    tick: TickState  # the learned parts' outputs in force
    t_aim: float  # the aimed time t + τ [s]
    p_hat: np.ndarray  # (3,) the forecast tip at t_aim, plate (NaN: no forecast)
    v_hat: np.ndarray  # (3,) its velocity
    a_hat: np.ndarray  # (3,) its acceleration
    forecast_ok: bool  # whether p_hat, v_hat and a_hat are finite


class Arbitration(NamedTuple):
    """Who leads and the tip reference this step made (with fusion in the QP: the blend α·p_r + (1 − α)·p_v of
    the parties' references, which the QP's cost tracks in effect)."""

    alpha: float  # the robot's share
    beta: float  # the wearer's share
    u: np.ndarray  # (3,) the fused tip velocity û = α·û_r + β·û_v, plate, after the bounds
    p_ref: np.ndarray  # (3,) the new tip reference, plate
    p_model: np.ndarray  # (3,) the same, model frame
    acc_ff: np.ndarray  # (3,) α·p̈̂, plate: the smoother's target acceleration (0 without feed-forward)
    plan: PreviewPlan  # what the MPC's preview is made from
    parties: PartyReferences | None = None  # each party's reference where the QP fuses them (None: fused here)


class Tracking(NamedTuple):
    """The QP's answer and the reference it tracked (model frame)."""

    result: QPResult
    reference: np.ndarray  # (3,) the QP's tip reference at t + dt: the MPC's plan or the smoothed reference
