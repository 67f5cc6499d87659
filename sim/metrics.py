"""Figures of one closed-loop episode (the keys of ``comparison.json``).

With e_k = ‖p_k − p*_k‖ the knife tip's distance to the wearer's intent at control step k (plate frame, [m]):

* ``tracking_rmse_m`` = sqrt(mean e_k²);  ``tracking_p95_m`` = 95th percentile of e_k.
* ``voluntary_effort`` [rad] = mean_k ‖θ_k‖₂, the shoulder angles θ (elevation, protraction, abduction) away
  from the neutral posture: the paper's effort measure.
* ``reactive_share`` = fraction of control steps with α > 0.5; ``handovers`` = crossings of α through 0.5.
* ``conflict_share`` = fraction of steps where the wearer and the robot push the tip in opposite directions:
  û_v = ShoulderMap.tip_velocity(θ_k) (the map's gain, dead zone and, if not the default, matrix are stored in
  the episode), û_r,eff = ṙ_k − β_k·û_v with ṙ_k the backward difference of ``tip_reference`` [m/s]; in
  conflict when both speeds exceed ``speed_deadband`` (0.01 m/s) and û_v · û_r,eff < 0.
* ``limit_violations`` = physics steps (1 kHz) where a realized joint position or velocity exceeded its limit
  by more than 1e-6, or an applied torque its limit (counted during the run, :mod:`sim.closed_loop`).
* ``step_p50_ms``, ``step_p99_ms`` = percentiles of the controller's step time [ms].
* ``realtime_factor`` = simulated time / wall-clock time of the whole loop.
"""

from __future__ import annotations

import json
from typing import Any

import numpy as np

from robot.shoulder import ShoulderMap
from sim.episode import Episode
from sim.task import EATING

__all__ = ["METRIC_KEYS", "conflict_mask", "episode_metrics"]

METRIC_KEYS = ("tracking_rmse_m", "tracking_p95_m", "voluntary_effort", "reactive_share", "handovers",
               "conflict_share", "limit_violations", "step_p50_ms", "step_p99_ms", "realtime_factor")


def conflict_mask(episode: Episode, speed_deadband: float = 0.01) -> np.ndarray:
    """(Nc,) bool: the steps in conflict (module docstring); the first step never is."""
    matrix = episode.info.get("shoulder_matrix")
    shoulder = ShoulderMap(gain=float(episode.info.get("shoulder_gain", 0.5)),
                           deadband_rad=float(episode.info.get("shoulder_deadband_rad", 0.01)),
                           matrix=EATING.shoulder_to_plate if not matrix else np.array(json.loads(matrix), dtype=float))
    n = episode.t.size
    out = np.zeros(n, dtype=bool)
    if n < 2:
        return out
    dt = float(episode.info.get("control_period_s", np.median(np.diff(episode.t))))
    u_v = np.array([shoulder.tip_velocity(th) if np.isfinite(th).all() else np.full(3, np.nan)
                    for th in episode.voluntary])
    r_dot = np.full((n, 3), np.nan)
    r_dot[1:] = np.diff(episode.tip_reference, axis=0) / dt
    beta = np.where(np.isfinite(episode.beta), episode.beta, 0.0)
    u_r = r_dot - beta[:, None] * u_v
    sv, sr = np.linalg.norm(u_v, axis=1), np.linalg.norm(u_r, axis=1)
    dot = np.einsum("ij,ij->i", u_v, u_r)
    with np.errstate(invalid="ignore"):
        out = (sv > speed_deadband) & (sr > speed_deadband) & (dot < 0)
    return np.nan_to_num(out, nan=0).astype(bool)


def _f(x: float) -> float | None:
    return float(x) if np.isfinite(x) else None


def episode_metrics(episode: Episode, speed_deadband: float = 0.01) -> dict[str, Any]:
    """The figures of ``episode`` (keys :data:`METRIC_KEYS`, JSON-able; None where undefined)."""
    e = np.linalg.norm(episode.tip - episode.tip_intent, axis=1)
    e = e[np.isfinite(e)]
    effort = np.linalg.norm(episode.voluntary, axis=1)
    effort = effort[np.isfinite(effort)]
    alpha = episode.alpha
    a_ok = np.isfinite(alpha)
    above = alpha[a_ok] > 0.5
    step_ms = episode.step_time * 1e3
    wall = float(episode.info.get("wall_time_s", np.nan))
    sim_time = float(episode.info.get("duration_s", episode.t.size * 0.01))
    return {
        "tracking_rmse_m": _f(np.sqrt(np.mean(e**2))) if e.size else None,
        "tracking_p95_m": _f(np.percentile(e, 95)) if e.size else None,
        "voluntary_effort": _f(np.mean(effort)) if effort.size else None,
        "reactive_share": _f(np.mean(above)) if above.size else None,
        "handovers": int(np.count_nonzero(np.diff(above.astype(int)))) if above.size else 0,
        "conflict_share": _f(np.mean(conflict_mask(episode, speed_deadband))) if episode.t.size else None,
        "limit_violations": int(episode.info.get("limit_violations", 0)),
        "step_p50_ms": _f(np.percentile(step_ms, 50)) if step_ms.size else None,
        "step_p99_ms": _f(np.percentile(step_ms, 99)) if step_ms.size else None,
        "realtime_factor": _f(sim_time / wall) if wall > 0 else None,
    }
