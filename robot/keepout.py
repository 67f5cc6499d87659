"""Keep-out zones as QP rows: the knife (tip and blade segment) stays out of moving capsules.

A *zone* (:class:`Zone`) is a capsule (a sphere when its ends coincide) with a velocity v_z in the
model's world frame; the blade is the segment p_b(s) = (1 − s)·p_tip + s·p_heel of one rigid body
(:class:`Blade`; heel a frame at a fixed offset from the tip frame), so its Jacobian and drift are
the same interpolation (exact). The closest points of blade and zone axis give the clearance and
the unit normal n (zone → knife):  d = ‖p_b(s*) − c_z‖ − r_z − margin  [m].  With a constant a
over dt, v_b⁺ = v_b + dt·(J_b·a + J̇_b·v). Two rows ``G·a ≤ h`` per zone (:class:`KeepOutLimit`):

* barrier (second-order, relative to the zone): s⁺ = −n·(v_b⁺ − v_z) ≤ u_A(d, s), the viable bound
  of :func:`robot.constraints.viable_velocity_bound` with gap d (the knife can still stop at A);
* speed and separation monitoring (ISO/TS 15066 5.5.4, Marvel & Norcross 2017):
  −n·v_b⁺ ≤ max(0, min((d − v_h·T_h)/T_r, v_cap + max(0, d − d_near)/T_r)), v_h = max(0, n·v_z);
  a zone's uncertainty counts as distance lost, and inside it the knife backs away:
  −n·v_b⁺ ≤ max(−v_cap, d_u/T_r).

Zones beyond ``KeepOutConfig.active_distance`` give ``0·a ≤ 1e6`` (always ``2·max_zones`` rows).
:func:`retreat` is the safest action when the rows cannot all be met (keep-out softened, other
limits hard). Bad settings raise ``ValueError``; an unknown frame, a bad heel offset or too many zones
raise :class:`robot.errors.ControllerConfigError` subclasses. Design: docs/design.md, "The person first".
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple, Sequence

import numpy as np
import pinocchio as pin

from .constraints import Constraint, _viable_bound_scalar, intersect_by_priority
from .errors import ControllerConfigError, FrameNotFoundError
from .state import ControlState

__all__ = ["BLADE_LENGTH", "Blade", "KeepOutConfig", "KeepOutLimit", "RetreatAction", "Zone", "ZoneClearance",
           "closest_segment_points", "retreat", "segment_zone_clearance", "segment_zone_clearances"]

_LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
#: [m] the SuperLimb's blade, tip to heel along the tool frame's −x (of its 0.14 m knife, the
#: rest is the handle stub in the holder): the knife body is this segment
BLADE_LENGTH = 0.09
_FREE = 1e6  # h of an inactive row


class Zone(NamedTuple):
    """A capsule from ``a`` to ``b`` (3,) [m] of ``radius`` [m] moving at ``velocity`` (3,) [m/s];
    ``speed_cap`` [m/s]: the knife's speed toward it near the person (speed and separation);
    ``uncertainty`` [m] growing at ``uncertainty_rate`` [m/s]: where the body part may have gone
    since it was last measured (a lost marker). The barrier keeps the knife out of the part as
    last measured; the separation row counts the uncertainty as distance lost and its rate as
    the part's approach speed, so the knife comes to a protective stop (never a flight) as the
    uncertain region reaches it."""

    name: str
    a: np.ndarray
    b: np.ndarray
    radius: float
    velocity: np.ndarray
    speed_cap: float
    uncertainty: float = 0.0
    uncertainty_rate: float = 0.0


class ZoneClearance(NamedTuple):
    """Clearance ``distance`` [m] (surface to surface, negative inside), blade parameter ``s``
    (0 tip, 1 heel), ``normal`` (3,) zone → knife, the closest points on the blade and the zone axis."""

    distance: float
    s: float
    normal: np.ndarray
    blade_point: np.ndarray
    zone_point: np.ndarray


def closest_segment_points(p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray
                           ) -> tuple[float, float]:
    """Parameters (s, t) ∈ [0, 1]² of the closest points p0 + s·(p1 − p0), q0 + t·(q1 − q0)
    of two segments (Ericson, *Real-Time Collision Detection*, 5.1.9; degenerate segments allowed).

    Plain floats: for 3-vectors they are several times faster than numpy calls (it runs per
    zone and step)."""
    return _closest(p0.tolist(), p1.tolist(), q0.tolist(), q1.tolist())


def _closest(P0: list[float], P1: list[float], Q0: list[float], Q1: list[float]) -> tuple[float, float]:
    """:func:`closest_segment_points` on plain lists; each x·y written out as x0·y0 + x1·y1 + x2·y2."""
    p0, p1, p2 = P0
    q0, q1, q2 = Q0
    x0, x1, x2 = P1[0] - p0, P1[1] - p1, P1[2] - p2  # d1
    y0, y1, y2 = Q1[0] - q0, Q1[1] - q1, Q1[2] - q2  # d2
    r0, r1, r2 = p0 - q0, p1 - q1, p2 - q2
    a, e, f = x0 * x0 + x1 * x1 + x2 * x2, y0 * y0 + y1 * y1 + y2 * y2, y0 * r0 + y1 * r1 + y2 * r2
    eps = 1e-18
    if a <= eps and e <= eps:
        return 0.0, 0.0
    if a <= eps:
        return 0.0, min(max(f / e, 0.0), 1.0)
    c = x0 * r0 + x1 * r1 + x2 * r2
    if e <= eps:
        return min(max(-c / a, 0.0), 1.0), 0.0
    b = x0 * y0 + x1 * y1 + x2 * y2
    denom = a * e - b * b
    s = min(max((b * f - c * e) / denom, 0.0), 1.0) if denom > eps else 0.0
    t = (b * s + f) / e
    if t < 0.0:
        t, s = 0.0, min(max(-c / a, 0.0), 1.0)
    elif t > 1.0:
        t, s = 1.0, min(max((b - c) / a, 0.0), 1.0)
    return s, t


def segment_zone_clearance(tip: np.ndarray, heel: np.ndarray, zone: Zone) -> ZoneClearance:
    """Clearance of the blade segment tip–heel to ``zone`` (surface distance, no margin)."""
    return _clearance(tip, heel, tip.tolist(), heel.tolist(), zone)


def _clearance(tip: np.ndarray, heel: np.ndarray, T: list[float], H: list[float], zone: Zone) -> ZoneClearance:
    """:func:`segment_zone_clearance` with the blade also as lists ``T``, ``H``."""
    A, B = zone.a.tolist(), zone.b.tolist()
    s, t = _closest(T, H, A, B)
    (t0, t1, t2), (h0, h1, h2), (a0, a1, a2), (b0, b1, b2) = T, H, A, B
    pb = [t0 + s * (h0 - t0), t1 + s * (h1 - t1), t2 + s * (h2 - t2)]  # elementwise as numpy's: the same floats
    pz = [a0 + t * (b0 - a0), a1 + t * (b1 - a1), a2 + t * (b2 - a2)]
    e0, e1, e2 = pb[0] - pz[0], pb[1] - pz[1], pb[2] - pz[2]
    dist = math.sqrt(e0 * e0 + e1 * e1 + e2 * e2)
    if dist > 1e-12:
        normal = np.array((e0 / dist, e1 / dist, e2 / dist))
    else:  # on the axis: push along the blade's perpendicular nearest to world up
        axis = heel - tip
        normal = np.cross(axis, np.cross(np.array([0.0, 0.0, 1.0]), axis))
        nn = float(np.linalg.norm(normal))
        normal = normal / nn if nn > 1e-12 else np.array([0.0, 0.0, 1.0])
    return ZoneClearance(dist - zone.radius, s, normal, np.array(pb), np.array(pz))


def segment_zone_clearances(tip: np.ndarray, heel: np.ndarray, a: np.ndarray, b: np.ndarray,
                            radius: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`segment_zone_clearance` of N blades and N zone axes at once: tip, heel, a, b (N, 3) [m], one
    radius [m]. Returns (distance (N,), s (N,), normal (N, 3)); the same arithmetic per row (NaN rows stay NaN)."""
    d1, d2, r = heel - tip, b - a, tip - a
    aa, e, f = _dots(d1, d1), _dots(d2, d2), _dots(d2, r)
    c, bb = _dots(d1, r), _dots(d1, d2)
    eps = 1e-18
    with np.errstate(divide="ignore", invalid="ignore"):
        denom = aa * e - bb * bb
        s = np.where(denom > eps, np.clip((bb * f - c * e) / denom, 0.0, 1.0), 0.0)
        t = (bb * s + f) / e
        s = np.where(t < 0.0, np.clip(-c / aa, 0.0, 1.0), np.where(t > 1.0, np.clip((bb - c) / aa, 0.0, 1.0), s))
        t = np.clip(t, 0.0, 1.0)
        point_zone, point_blade = e <= eps, aa <= eps
        s = np.where(point_zone, np.clip(-c / aa, 0.0, 1.0), s)
        t = np.where(point_zone, 0.0, t)
        t = np.where(point_blade, np.clip(f / e, 0.0, 1.0), t)
        s = np.where(point_blade, 0.0, s)
        both = point_blade & point_zone
        s, t = np.where(both, 0.0, s), np.where(both, 0.0, t)
        diff = (tip + s[:, None] * (heel - tip)) - (a + t[:, None] * (b - a))
        dist = np.sqrt(_dots(diff, diff))
        normal = diff / dist[:, None]
    on_axis = ~(dist > 1e-12) & np.isfinite(dist)
    if on_axis.any():  # push along the blade's perpendicular nearest to world up (as segment_zone_clearance)
        for k in np.flatnonzero(on_axis):
            normal[k] = segment_zone_clearance(tip[k], heel[k], Zone("", a[k], b[k], radius, a[k], 0.0)).normal
    return dist - radius, s, normal


def _dots(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Row-wise x·y of (N, 3) arrays in :func:`_closest`'s order of operations (x0·y0 + x1·y1 + x2·y2)."""
    return x[:, 0] * y[:, 0] + x[:, 1] * y[:, 1] + x[:, 2] * y[:, 2]


def _lerp(x: list[float], y: list[float], s: float) -> tuple[float, float, float]:
    """(1 − s)·x + s·y of two 3-vectors, elementwise as numpy computes it (the same floats)."""
    w = 1.0 - s
    return w * x[0] + s * y[0], w * x[1] + s * y[1], w * x[2] + s * y[2]


@dataclass(frozen=True)
class KeepOutConfig:
    """Settings of the keep-out rows.

    margin [m] kept beyond each zone's surface (the intrusion allowance C of ISO/TS 15066);
    brake_acceleration A [m/s²] of the barrier row (the knife's braking toward a zone, well
    inside what the arm's joint limits give near the plate); reaction_time_s T_r and
    human_time_s T_h [s] of the separation row; near_distance_m [m] within which the zone's
    speed cap applies in full; active_distance_m [m] beyond which a zone gives no rows;
    max_zones: the row budget (2 rows per zone).
    """

    margin: float = 0.02
    brake_acceleration: float = 2.0
    reaction_time_s: float = 0.1
    human_time_s: float = 0.1
    near_distance_m: float = 0.05
    active_distance_m: float = 0.25
    max_zones: int = 4

    def __post_init__(self) -> None:
        for name in ("margin", "human_time_s"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) >= 0):
                raise ValueError(f"KeepOutConfig.{name} must be finite and >= 0, got {getattr(self, name)!r}")
        for name in ("brake_acceleration", "reaction_time_s", "near_distance_m", "active_distance_m"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) > 0):
                raise ValueError(f"KeepOutConfig.{name} must be finite and > 0, got {getattr(self, name)!r}")
        if int(self.max_zones) < 1:
            raise ValueError(f"KeepOutConfig.max_zones must be >= 1, got {self.max_zones!r}")


class _Point(NamedTuple):
    p: np.ndarray
    v: np.ndarray
    J: np.ndarray
    drift: np.ndarray


class Blade:
    """The knife's tip and heel on any Pinocchio model: ``frame`` (name or id) holds the tip, the heel is
    ``heel_offset`` (3,) [m] in that frame (a frame added to a copy of the model)."""

    def __init__(self, model, frame: str | int, heel_offset: Sequence[float]) -> None:
        if isinstance(frame, str):
            if not model.existFrame(frame):
                raise FrameNotFoundError(f"frame {frame!r} not in model {model.name!r}")
            frame = model.getFrameId(frame)
        heel = np.asarray(heel_offset, dtype=float)
        if heel.shape != (3,) or not np.isfinite(heel).all() or np.linalg.norm(heel) < 1e-6:
            raise ControllerConfigError(f"heel_offset must be a non-zero finite (3,) vector [m], got {heel_offset!r}")
        self.model, self.heel_offset = model.copy(), heel
        tool = self.model.frames[int(frame)]
        placement = tool.placement * pin.SE3(np.eye(3), heel)
        self.tip_id = int(frame)
        self.heel_id = self.model.addFrame(pin.Frame("keepout_heel", tool.parentJoint, int(frame), placement,
                                                     pin.FrameType.OP_FRAME))
        self.data = self.model.createData()
        self._zero = np.zeros(self.model.nv)
        self._last: tuple[bytes, bytes | None, tuple[_Point, _Point]] | None = None

    def _point(self, fid: int) -> _Point:
        m, d = self.model, self.data
        p = d.oMf[fid].translation.copy()
        v = pin.getFrameVelocity(m, d, fid, _LWA).linear.copy()
        drift = pin.getFrameClassicalAcceleration(m, d, fid, _LWA).linear.copy()
        J = pin.getFrameJacobian(m, d, fid, _LWA)[:3].copy()
        return _Point(p, v, J, drift)

    def knife(self, q: np.ndarray, v: np.ndarray | None = None) -> tuple[_Point, _Point]:
        """(tip, heel) positions [m], velocities [m/s], Jacobians and drifts J̇·v [m/s²] at (q, v); the
        last state's are kept, so limits that share a blade (the keep-out and the floor) compute them once.
        Read-only: the points are shared."""
        key_q = np.asarray(q, dtype=float).tobytes()
        key_v = None if v is None else np.asarray(v, dtype=float).tobytes()
        if self._last is not None and self._last[0] == key_q and self._last[1] == key_v:
            return self._last[2]
        m, d = self.model, self.data
        pin.forwardKinematics(m, d, q, self._zero if v is None else v, self._zero)
        pin.updateFramePlacements(m, d)
        pin.computeJointJacobians(m, d)
        points = self._point(self.tip_id), self._point(self.heel_id)
        self._last = (key_q, key_v, points)
        return points


class KeepOutLimit:
    """Keep-out rows ``G·a ≤ h`` (module docstring) for any Pinocchio model and tool frame.

    ``heel_offset`` (3,) [m]: the blade's heel in the tool frame (the SuperLimb's knife runs
    along the tool frame's x: ``(−blade_length, 0, 0)``); ``blade``: a :class:`Blade` of the same model,
    frame and heel to share (its kinematics computed once per state) instead of a new one. Give the zones of
    each step with :meth:`set_zones` (model world frame) before the QP's step; :attr:`clearances` holds the
    step's :class:`ZoneClearance` per zone, :attr:`approach` the knife's own speed toward it [m/s]
    and :attr:`rows` the last rows computed.
    """

    name = "keepout"

    def __init__(self, model, frame: str | int, heel_offset: Sequence[float],
                 config: KeepOutConfig | None = None, blade: Blade | None = None) -> None:
        self.config = config or KeepOutConfig()
        self.blade = blade if blade is not None else Blade(model, frame, heel_offset)
        self.zones: list[Zone] = []
        self.clearances: list[ZoneClearance] = []
        self.approach: list[float] = []
        self.rows: Constraint | None = None

    def num_rows(self, n: int) -> int:
        return 2 * int(self.config.max_zones)

    def set_zones(self, zones: Sequence[Zone]) -> None:
        """The zones of this step (model world frame); at most ``config.max_zones``."""
        if len(zones) > self.config.max_zones:
            raise ControllerConfigError(f"{len(zones)} zones given, KeepOutConfig.max_zones is "
                                        f"{self.config.max_zones}")
        self.zones = list(zones)

    def knife(self, q: np.ndarray, v: np.ndarray | None = None) -> tuple[_Point, _Point]:
        """(tip, heel) at (q, v) (:meth:`Blade.knife`)."""
        return self.blade.knife(q, v)

    def compute_qp_inequalities(self, state: ControlState) -> Constraint:
        cfg, dt = self.config, state.dt
        rows = 2 * cfg.max_zones
        G, h = np.zeros((rows, state.q.size)), [_FREE] * rows
        tip, heel = self.knife(state.q, state.v)
        T, H = tip.p.tolist(), heel.p.tolist()
        tv, hv, ta, ha = tip.v.tolist(), heel.v.tolist(), tip.drift.tolist(), heel.drift.tolist()
        self.clearances, self.approach = [], []
        for i, z in enumerate(self.zones):
            c = _clearance(tip.p, heel.p, T, H, z)
            s, n = c.s, c.normal
            vb_l = _lerp(tv, hv, s)
            vb = np.array(vb_l)  # (1 − s)·v_tip + s·v_heel
            nvb = float(n @ vb)
            self.clearances.append(c)
            self.approach.append(-nvb)
            d = c.distance - cfg.margin
            if d - z.uncertainty > cfg.active_distance_m:
                continue
            Jb = (1.0 - s) * tip.J + s * heel.J
            ab = np.array(_lerp(ta, ha, s))
            nJ = -dt * (n @ Jb)
            own = nvb + dt * float(n @ ab)  # −(the knife's own approach speed after a = 0)
            nz = float(n @ z.velocity)
            zv0, zv1, zv2 = z.velocity.tolist()
            s_rel = -float(n @ np.array((vb_l[0] - zv0, vb_l[1] - zv1, vb_l[2] - zv2)))
            u_barrier = _viable_bound_scalar(d, s_rel, dt, cfg.brake_acceleration)
            G[2 * i:2 * i + 2] = nJ  # both rows
            h[2 * i] = u_barrier + own - nz
            v_h = max(0.0, nz) + z.uncertainty_rate
            d_ssm = d - z.uncertainty
            u_ssm = min((d_ssm - v_h * cfg.human_time_s) / cfg.reaction_time_s,
                        z.speed_cap + max(0.0, d_ssm - cfg.near_distance_m) / cfg.reaction_time_s)
            # a protective stop; inside an uncertain region, a gentle retreat (at most the zone's cap)
            u_ssm = max(-z.speed_cap, d_ssm / cfg.reaction_time_s) if z.uncertainty > 0.0 and d_ssm < 0.0 \
                else max(0.0, u_ssm)
            h[2 * i + 1] = u_ssm + own
        G.flags.writeable = False
        h_rows = np.array(h)
        h_rows.flags.writeable = False
        self.rows = Constraint(G, h_rows)
        return self.rows


class RetreatAction(NamedTuple):
    """The retreat: acceleration a [rad/s²], torque τ [N·m], the largest keep-out slack [m/s]."""

    a: np.ndarray
    tau: np.ndarray
    slack: float


def retreat(qp, limit: KeepOutLimit, q: np.ndarray, v: np.ndarray) -> RetreatAction | None:
    """The safest feasible action when the keep-out rows cannot all be met (module docstring).

    Minimise ½·w‖a + v/dt‖² + ρ₁·Σσ + ½ρ₂‖σ‖² over (a, σ ≥ 0) s.t. the QP's box (by
    priority), its other rows hard, keep-out rows ``G·a − σ/dt·… ≤ h + σ``: as close to
    every zone row as the arm can get (retreat), stopping where nothing pulls. Returns None
    when even that fails (the caller then brakes). ``qp``: a :class:`robot.qp.QPController`
    whose ``constraints`` hold ``limit``.
    """
    from .solvers import make_backend

    state = qp.evaluate(q, v)
    n = state.q.size
    lo, hi, _ = intersect_by_priority([c.bounds(state) for c in qp.box_constraints])
    Gk, hk = limit.compute_qp_inequalities(state)
    others = [c.compute_qp_inequalities(state) for c in qp.constraints if c is not limit]
    Go = np.concatenate([r.G for r in others]) if others else np.zeros((0, n))
    ho = np.concatenate([r.h for r in others]) if others else np.zeros(0)
    mk = Gk.shape[0]
    scale = 1.0 / max(1.0, float(np.abs(Gk).max()))  # rows in m/s; slack in the same unit
    P = np.zeros((n + mk, n + mk))
    P[:n, :n] = np.eye(n) * state.dt ** 2
    P[n:, n:] = 1e2 * np.eye(mk)
    c = np.concatenate([state.v * state.dt, np.full(mk, 1e3)])
    G = np.vstack([np.hstack([Gk * scale, -np.eye(mk)]), np.hstack([Go, np.zeros((Go.shape[0], mk))])])
    h = np.concatenate([hk * scale, ho])
    lb = np.concatenate([lo, np.zeros(mk)])
    ub = np.concatenate([hi, np.full(mk, 1e30)])
    out = make_backend(qp.config.solver, n + mk, G.shape[0], qp.config.eps).solve(P, c, lb, ub, G, h)
    if out.x is None:
        return None
    a = np.minimum(np.maximum(out.x[:n], lo), hi)
    tau = state.M @ a + state.h
    torque = getattr(qp, "_torque", None)
    if torque is not None and (np.abs(tau) > torque.tau_max + 1e-9).any():
        return None
    return RetreatAction(a, tau, float(np.max(out.x[n:], initial=0.0)) / scale)
