"""Fusion inside the QP (strategies with ``fusion = "qp"``, e.g. ``qp_blend``): each party keeps its own tip
reference chain and the QP's tip cost weighs the two (docs/design.md, "Authority inside the optimisation").

Per step, plate frame, with the robot's weight α (the Arbiter's) and dt [s]:

    û_r = sat(ṗ̂ + k·(p̂ − p_r)),   p_r ← B(p_r + û_r·dt)        (the robot's chain, as ``reactive``'s)
    p_v ← B(p_v + û_v·dt),  then p_v ← p_r + (p_v − p_r)·min(1, d / (α·‖p_v − p_r‖))   (the wearer's, anti-windup)

B: the workspace box and the arm's reach (:func:`~mpcshare.control.workspace.bound_reference`), d: the
settings' ``wearer_offset_m``. Each chain has its own jerk-limited smoother; the QP minimises
α·‖J·a + J̇·v − ẍ_r‖² + (1 − α)·‖J·a + J̇·v − ẍ_v‖² (:class:`robot.tasks.BlendedTipTrackingTask`). That cost is
that of tracking α·ẍ_r + (1 − α)·ẍ_v plus a constant, so the constrained minimiser is the same as tracking the
blended reference, limits and keep-out binding or not: what differs from fusion before the QP is the references
(two chains, each bounded and smoothed on its own, weighed convexly), not the optimisation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Callable, NamedTuple

import numpy as np

from mpcshare.control.arbitration import reactive_velocity
from mpcshare.control.types import ControllerConfig
from robot.smoothing import ReferenceSmoother

__all__ = ["PartyReferences", "PartyState", "SmoothedParty", "advance", "smooth"]

#: (p, u, acc) → (p', u', acc', fault): the reference bound (box and reach).
Bound = Callable[[np.ndarray, np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray, np.ndarray, "str | None"]]


@dataclass
class PartyState:
    """The two chains' episode state: references p_r, p_v [m] (plate; None before the first step) and their
    smoothers (model frame)."""

    smoother_r: ReferenceSmoother
    smoother_v: ReferenceSmoother
    p_r: np.ndarray | None = None
    p_v: np.ndarray | None = None

    @classmethod
    def new(cls, dt: float, cfg: ControllerConfig) -> PartyState:
        """Both chains unset, smoothers with the controller's limits at period ``dt`` [s]."""
        make = lambda: ReferenceSmoother(3, dt, cfg.max_velocity, cfg.max_acceleration, cfg.max_jerk)  # noqa: E731
        return cls(make(), make())


class PartyReferences(NamedTuple):
    """One step's references of the two parties (plate frame) and the robot's weight α in the QP."""

    alpha: float  # the robot's weight; the wearer's is 1 − α
    p_r: np.ndarray  # (3,) the robot's reference [m]
    u_r: np.ndarray  # (3,) its velocity [m/s], after the bound
    acc_r: np.ndarray  # (3,) its feed-forward acceleration [m/s²]
    p_v: np.ndarray  # (3,) the wearer's reference [m]
    u_v: np.ndarray  # (3,) its velocity [m/s], after the bound
    limited: bool  # whether the anti-windup moved the wearer's reference this step


class SmoothedParty(NamedTuple):
    """A party's smoothed reference, model frame: position [m], velocity [m/s], acceleration [m/s²]."""

    position: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray


def advance(state: PartyState, alpha: float, start: np.ndarray, p_hat: np.ndarray, v_hat: np.ndarray,
            a_hat: np.ndarray, forecast_ok: bool, u_wearer: np.ndarray, dt: float, cfg: ControllerConfig,
            bound: Bound, offset_m: float) -> tuple[PartyReferences, list[str]]:
    """Both chains one step ahead (module docstring); ``start``: where they begin on the first step (plate),
    ``u_wearer``: û_v [m/s] (zeros to hold the wearer's chain). Returns the record and the bound's faults."""
    if state.p_r is None or state.p_v is None:
        state.p_r, state.p_v = start.copy(), start.copy()
    faults: list[str] = []
    if forecast_ok:
        u_r = reactive_velocity(p_hat, state.p_r, cfg.reactive_gain, cfg.reactive_max_speed,
                                v_hat if cfg.reactive_feedforward else None)
        acc_r = a_hat if cfg.reactive_feedforward else np.zeros(3)
    else:
        u_r, acc_r = np.zeros(3), np.zeros(3)
    p_r, u_r, acc_r, f_r = bound(state.p_r + u_r * dt, u_r, acc_r)
    p_v, u_v, _, f_v = bound(state.p_v + u_wearer * dt, u_wearer, np.zeros(3))
    faults += [f"robot's reference: {f_r}"] if f_r else []
    faults += [f"wearer's reference: {f_v}"] if f_v else []
    gap = p_v - p_r
    dist = math.sqrt(float(gap @ gap))
    limited = alpha * dist > offset_m
    if limited:
        p_v = p_r + gap * (offset_m / (alpha * dist))
    state.p_r, state.p_v = p_r, p_v
    return PartyReferences(float(alpha), p_r, u_r, acc_r, p_v, u_v, bool(limited)), faults


def smooth(state: PartyState, refs: PartyReferences, pose: np.ndarray, tip: np.ndarray, cfg: ControllerConfig
           ) -> tuple[SmoothedParty, SmoothedParty]:
    """Each party's reference through its own smoother, in the model frame under the base ``pose`` (4, 4);
    ``tip``: the measured tip (model frame) a smoother starts from. Returns (robot, wearer)."""
    R, t = pose[:3, :3], pose[:3, 3]
    out = []
    for sm, p, u, acc in ((state.smoother_r, refs.p_r, refs.u_r, refs.acc_r),
                          (state.smoother_v, refs.p_v, refs.u_v, np.zeros(3))):
        if not sm.initialized:
            sm.reset(tip)
        p_m, u_m = R.T @ (p - t), R.T @ u
        s = sm.update(p_m + cfg.smoother_lead_s * u_m) if cfg.smoother_target == "position" else \
            sm.update(p_m, u_m, R.T @ acc)
        out.append(SmoothedParty(s.position, s.velocity, s.acceleration))
    return out[0], out[1]
