"""Pooling per-episode metrics over the trials of a closed-loop run (:mod:`mpcshare.evaluation`):
the tracking and effort figures of :func:`sim.metrics.episode_metrics` (:func:`pool_metrics`), a task's
figures (:func:`pool_task_metrics`, its ``metric_keys``) and the keep-out figures of
:mod:`sim.keepout_metrics` (:func:`pool_keepout_metrics`)."""

from __future__ import annotations

import math
import numbers
from typing import Any, Callable, Sequence

import numpy as np

from sim.task import EATING, Task

__all__ = ["pool_keepout_metrics", "pool_metrics", "pool_task_metrics"]


def pool_metrics(metrics: Sequence[dict[str, float]], step_times: Sequence[np.ndarray],
                 sim_seconds: Sequence[float]) -> dict[str, float]:
    """Pool per-trial metrics into one row.

    Tracking RMS: √(Σ_k n_k·rms_k² / Σ_k n_k) (n_k control steps of trial k); p95 and the
    shares and effort: means weighted by n_k; counts (hand-overs, limit violations):
    sums; step-time percentiles over all steps pooled; real-time factor: total
    simulated time / total wall time.
    """
    if not metrics:
        raise ValueError("no episodes to pool")
    metrics = [{k: (float("nan") if v is None else v) for k, v in m.items()} for m in metrics]
    n = np.array([len(s) for s in step_times], dtype=float)
    w = n / n.sum()

    def mean(key: str) -> float:
        return float(np.sum(w * np.array([m[key] for m in metrics], dtype=float)))

    steps = np.concatenate([np.asarray(s, dtype=float) for s in step_times])
    wall = sum(s / m["realtime_factor"] for s, m in zip(sim_seconds, metrics) if m["realtime_factor"] > 0)
    rtf = float(sum(sim_seconds) / wall) if wall > 0 else float("nan")
    return {
        "tracking_rmse_m": float(math.sqrt(np.sum(w * np.array([m["tracking_rmse_m"] ** 2 for m in metrics])))),
        "tracking_p95_m": mean("tracking_p95_m"),
        "voluntary_effort": mean("voluntary_effort"),
        "reactive_share": mean("reactive_share"),
        "handovers": int(sum(int(m["handovers"]) for m in metrics)),
        "conflict_share": mean("conflict_share"),
        "limit_violations": int(sum(int(m["limit_violations"]) for m in metrics)),
        "step_p50_ms": float(np.percentile(steps, 50) * 1e3),
        "step_p99_ms": float(np.percentile(steps, 99) * 1e3),
        "realtime_factor": rtf,
    }


def pool_task_metrics(metrics: Sequence[dict[str, Any]], step_times: Sequence[np.ndarray],
                      task: Task = EATING) -> dict[str, Any]:
    """Pool the figures of ``task`` (the keys its ``metric_keys``, in that order): lag and RMS at
    it weighted by steps; the sawing amplitude and correlation weighted by time in the stroke mode
    (``cutting_s``); the cutting episodes (``saw_by_episode``) listed in the episodes' order; strokes summed
    (share = executed / intended); RMS per mode √(Σ n·rms² / Σ n); the wearer's
    pick-ups (:func:`sim.task.metrics.pickup_error`) counted and timed in sum, their RMS √(Σ s·rms² / Σ s) over
    their times s, their share of the squared error weighted by each episode's Σ‖e‖² = n·rms²; any other key of
    the task the step-weighted mean of its numbers (None where no episode has one)."""
    n = np.array([len(s) for s in step_times], dtype=float)
    known = _pool_known(metrics, n)
    return {k: known[k] if k in known else _weighted(metrics, k, n) for k in task.metric_keys}


def _weighted(metrics: Sequence[dict[str, Any]], key: str, w: np.ndarray) -> float | None:
    """Σ w·x / Σ w over the episodes whose ``key`` is a finite number with weight > 0; None where none is."""
    vals = np.array([m[key] if isinstance(m.get(key), numbers.Real) else np.nan for m in metrics], dtype=float)
    ok = np.isfinite(vals) & (w > 0)
    return float(np.sum(w[ok] * vals[ok]) / np.sum(w[ok])) if ok.any() else None


def _pool_known(metrics: Sequence[dict[str, Any]], n: np.ndarray) -> dict[str, Any]:
    """The figures of :func:`pool_task_metrics` with a rule of their own."""
    def weighted(key: str, w: np.ndarray) -> float | None:
        return _weighted(metrics, key, w)

    cut = np.array([float(m.get("cutting_s") or 0.0) for m in metrics])
    intended = sum(int(m.get("strokes_intended") or 0) for m in metrics)
    executed = sum(int(m.get("strokes_executed") or 0) for m in metrics)
    by_mode: dict[str, float | None] = {}
    for name in sorted({k for m in metrics for k in (m.get("rms_by_mode_m") or {})}):
        vals = [(w, (m.get("rms_by_mode_m") or {}).get(name)) for w, m in zip(n, metrics)]
        vals = [(w, v) for w, v in vals if v is not None]
        by_mode[name] = float(math.sqrt(sum(w * v * v for w, v in vals) / sum(w for w, _ in vals))) if vals else None
    return {"lag_s": weighted("lag_s", n), "rms_at_lag_m": weighted("rms_at_lag_m", n),
            "saw_amplitude_ratio": weighted("saw_amplitude_ratio", cut),
            "saw_correlation": weighted("saw_correlation", cut),
            "saw_by_episode": [e for m in metrics for e in (m.get("saw_by_episode") or [])],
            "strokes_intended": intended,
            "strokes_executed": executed, "stroke_share": executed / intended if intended else None,
            "cutting_s": float(cut.sum()), "rms_by_mode_m": by_mode, **_pool_wearer_share(metrics),
            **_pool_pickups(metrics, n)}


def _pool_pickups(metrics: Sequence[dict[str, Any]], n: np.ndarray) -> dict[str, Any]:
    """The pick-up figures over episodes (:func:`pool_task_metrics`)."""
    secs = np.array([float(m.get("pickup_s") or 0.0) for m in metrics])
    rms = np.array([np.nan if m.get("pickup_rms_m") is None else m["pickup_rms_m"] for m in metrics])
    share = np.array([np.nan if m.get("pickup_error_share") is None else m["pickup_error_share"] for m in metrics])
    sq = n * np.array([float(m.get("tracking_rmse_m") or 0.0) ** 2 for m in metrics])  # Σ‖e‖² per episode
    ok_r, ok_s = np.isfinite(rms) & (secs > 0), np.isfinite(share) & (sq > 0)
    return {"pickups": sum(int(m.get("pickups") or 0) for m in metrics), "pickup_s": float(secs.sum()),
            "pickup_rms_m": float(np.sqrt(np.sum(secs[ok_r] * rms[ok_r] ** 2) / np.sum(secs[ok_r])))
            if ok_r.any() else None,
            "pickup_error_share": float(np.sum(sq[ok_s] * share[ok_s]) / np.sum(sq)) if ok_s.any() else None}


def pool_keepout_metrics(metrics: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Pool the keep-out figures (:mod:`sim.keepout_metrics`): the least clearance (per zone too), the
    deepest intrusion, the highest speed near the person and the knife's lowest point over episodes;
    times and steps summed."""
    def values(key: str) -> list[float]:
        return [float(m[key]) for m in metrics if m.get(key) is not None]

    def pick(key: str, f: Callable[[list[float]], float]) -> float | None:
        v = values(key)
        return f(v) if v else None

    zones = sorted({z for m in metrics for z in (m.get("keepout_min_clearance_by_zone_m") or {})})
    by_zone = {}
    for z in zones:
        v = [m["keepout_min_clearance_by_zone_m"][z] for m in metrics
             if (m.get("keepout_min_clearance_by_zone_m") or {}).get(z) is not None]
        by_zone[z] = min(v) if v else None
    return {"keepout_min_clearance_m": pick("keepout_min_clearance_m", min),
            "keepout_max_depth_m": pick("keepout_max_depth_m", max),
            "keepout_time_inside_s": pick("keepout_time_inside_s", sum),
            "keepout_steps_driven_in": int(sum(values("keepout_steps_driven_in"))),
            "keepout_inside_zone_moving_s": pick("keepout_inside_zone_moving_s", sum),
            "keepout_near_speed_mps": pick("keepout_near_speed_mps", max),
            "keepout_min_clearance_by_zone_m": by_zone,
            "knife_min_height_m": pick("knife_min_height_m", min)}


def _pool_wearer_share(metrics: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """The wearer's share per mode pooled over episodes, weighted by each episode's steps in that mode."""
    shares: dict[str, float] = {}
    counts: dict[str, int] = {}
    for m in metrics:
        for name, n in (m.get("mode_steps") or {}).items():
            share = (m.get("wearer_share_by_mode") or {}).get(name)
            if share is not None and n:
                shares[name] = shares.get(name, 0.0) + share * n
                counts[name] = counts.get(name, 0) + int(n)
    return {"wearer_share_by_mode": {k: shares[k] / counts[k] for k in sorted(counts)}, "mode_steps": counts}
