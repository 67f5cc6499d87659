"""The schedules of the replayed runs ``random_handover`` and ``oracle_handover`` from episodes.

* ``random_handover`` (the placebo): the gate's schedule on the trial, ``on[k] = α_k ≥ 0.5`` (the robot leads),
  redrawn by :func:`mpcshare.evaluation.schedule.random_schedule` with the same steps on, hand-overs and first
  state, interior segments ≥ the dwell d = ⌈``min_dwell_s`` / Δ⌉ steps (or the gate's shortest interior segment,
  if shorter), seeded by (seed, trial, draw); replayed at the gate's mean α over its robot-led steps.
* ``oracle_handover`` (never worse than the better party): :func:`mpcshare.evaluation.schedule.oracle_schedule`
  on the per-step errors e_k = ‖p_k − p*_k‖ [m] of the ``voluntary`` and ``reactive`` episodes, with dwell d, at
  the switch costs λ_c = c · (1/Δ) · mean(e_v² + e_r²)/2 for c in :data:`ORACLE_SWITCH_COSTS_S` [s]
  (:func:`oracle_handover_schedules`); each is replayed and the run keeps, per trial, the episode with the lowest
  tracking RMS among the replays and the two pure runs' own episodes.
* ``oracle_line``: :func:`line_oracle_schedules`, the same search with the cost of a party e_k² + μ·ε_k
  (ε_k = ‖θ_k‖ [rad], the shoulder in that party's run), μ = c·(m_r − m_v)/(E_v − E_r) for c in
  :data:`LINE_ORACLE_WEIGHTS`, at the switch costs :data:`LINE_ORACLE_SWITCH_COSTS_S`; the run keeps, per trial,
  the replay with the lowest line ratio among those costing at most :data:`LINE_ORACLE_MAX_EFFORT` × the
  ``voluntary`` effort, the pure runs included (ratio 1). Not a strict bound: the search prices the pure runs'
  errors, not the replay's.

All are replayed by the controller's ``schedule`` strategy, read ``handover_s``/2 ahead so that α's ramp crosses
0.5 on the scheduled step (:class:`mpcshare.evaluation.schedule.StepSchedule`); why: docs/design.md.
"""

from __future__ import annotations

import math
from dataclasses import asdict
from typing import Any, Sequence

import numpy as np

from mpcshare.control.strategies import DEFAULT_STRATEGY
from mpcshare.control.types import ControllerConfig
from mpcshare.evaluation.schedule import ScheduleStats, StepSchedule, oracle_schedule, random_schedule, schedule_stats

__all__ = ["LINE_ORACLE_MAX_EFFORT", "LINE_ORACLE_SWITCH_COSTS_S", "LINE_ORACLE_WEIGHTS", "ORACLE_SWITCH_COSTS_S",
           "SCHEDULE_SOURCES", "dwell_steps", "oracle_handover_schedule",
           "line_oracle_schedules", "oracle_handover_schedules", "random_handover_schedules",
           "random_schedules_from", "schedule_record", "tracking_error"]

#: Switch costs of the oracle's candidates, in seconds of the parties' mean squared error (module docstring).
ORACLE_SWITCH_COSTS_S: tuple[float, ...] = (0.0, 0.5, 2.0, 8.0)
#: ``oracle_line``'s prices of effort, as multiples c of the line's exchange rate (module docstring).
LINE_ORACLE_WEIGHTS: tuple[float, ...] = (0.6, 1.0, 1.5)
#: ``oracle_line``'s switch costs, in seconds of the parties' mean squared error.
LINE_ORACLE_SWITCH_COSTS_S: tuple[float, ...] = (0.5, 1.5)
#: ``oracle_line`` keeps replays costing at most this × the ``voluntary`` effort (the effort target).
LINE_ORACLE_MAX_EFFORT = 0.75
#: The runs each scheduled run is computed from.
SCHEDULE_SOURCES: dict[str, tuple[str, ...]] = {"random": (DEFAULT_STRATEGY,), "oracle": ("voluntary", "reactive"),
                                                "oracle_line": ("voluntary", "reactive")}


def _period(episode: Any) -> float:
    return float(np.median(np.diff(episode.t))) if episode.t.size > 1 else 0.01


def dwell_steps(min_dwell_s: float, dt: float) -> int:
    """d = max(1, ⌈min_dwell_s / dt⌉) control steps."""
    return max(1, math.ceil(min_dwell_s / dt - 1e-9))


def tracking_error(episode: Any) -> np.ndarray:
    """(N,) per-step ‖tip − intent‖ [m] of an episode."""
    return np.linalg.norm(np.asarray(episode.tip) - np.asarray(episode.tip_intent), axis=1)


def schedule_record(episode: Any) -> dict[str, Any]:
    """What a matched-random schedule needs of an episode (JSON-able): the
    :class:`~mpcshare.evaluation.schedule.ScheduleStats` of ``α ≥ 0.5`` (the robot leads), ``on_alpha`` (the
    mean α over those steps, its share while it leads) and the step times
    ``t0_s + k·dt_s``."""
    alpha = np.nan_to_num(np.asarray(episode.alpha, dtype=float), nan=0.0)
    on = alpha >= 0.5
    on_alpha = float(np.mean(alpha[on])) if on.any() else 1.0
    return {**asdict(schedule_stats(on)), "on_alpha": min(max(on_alpha, 0.5), 1.0), "t0_s": float(episode.t[0]),
            "dt_s": _period(episode)}


def random_schedules_from(record: dict[str, Any], draws: int, seed: Sequence[int],
                          config: ControllerConfig | None = None) -> list[StepSchedule]:
    """``draws`` matched-random schedules of a :func:`schedule_record` (module docstring)."""
    cfg = config or ControllerConfig()
    stats = ScheduleStats(**{k: record[k] for k in ScheduleStats.__dataclass_fields__})
    d = dwell_steps(cfg.min_dwell_s, record["dt_s"])
    if stats.min_interior is not None:
        d = min(d, stats.min_interior)
    times = record["t0_s"] + record["dt_s"] * np.arange(stats.steps)
    on_alpha = float(record.get("on_alpha", 1.0))
    return [StepSchedule(times, random_schedule(stats, d, [*seed, j]), cfg.handover_s / 2, on_alpha)
            for j in range(draws)]


def random_handover_schedules(gate_episode: Any, draws: int, seed: Sequence[int],
                              config: ControllerConfig | None = None) -> list[StepSchedule]:
    """``draws`` matched-random schedules of the gate's episode (module docstring)."""
    return random_schedules_from(schedule_record(gate_episode), draws, seed, config)


def oracle_handover_schedule(voluntary_episode: Any, reactive_episode: Any,
                             config: ControllerConfig | None = None, switch_cost_s: float = 0.0) -> StepSchedule:
    """The error-minimising schedule with the dwell from the pure runs' episodes, each hand-over
    costing ``switch_cost_s`` seconds of their mean squared error (module docstring)."""
    cfg = config or ControllerConfig()
    e0, e1 = tracking_error(voluntary_episode), tracking_error(reactive_episode)
    n = min(e0.size, e1.size)
    dt = _period(reactive_episode)
    e0, e1 = e0[:n], e1[:n]
    lam = switch_cost_s / dt * float(np.nanmean(e0 ** 2 + e1 ** 2) / 2) if n else 0.0
    on = oracle_schedule(e0, e1, dwell_steps(cfg.min_dwell_s, dt), lam if np.isfinite(lam) else 0.0)
    return StepSchedule(reactive_episode.t[:n], on, cfg.handover_s / 2)


def oracle_handover_schedules(voluntary_episode: Any, reactive_episode: Any,
                              config: ControllerConfig | None = None,
                              switch_costs_s: Sequence[float] = ORACLE_SWITCH_COSTS_S) -> list[StepSchedule]:
    """The oracle's candidate schedules, one per switch cost, distinct ones only (module docstring)."""
    out: list[StepSchedule] = []
    for c in switch_costs_s:
        s = oracle_handover_schedule(voluntary_episode, reactive_episode, config, c)
        if not any(np.array_equal(s.on, o.on) for o in out):
            out.append(s)
    return out


def line_oracle_schedules(voluntary_episode: Any, reactive_episode: Any, config: ControllerConfig | None = None,
                          weights: Sequence[float] = LINE_ORACLE_WEIGHTS,
                          switch_costs_s: Sequence[float] = LINE_ORACLE_SWITCH_COSTS_S) -> list[StepSchedule]:
    """``oracle_line``'s candidate schedules: min Σ_k (e_k² + μ·ε_k) + λ·(hand-overs) per weight c and
    switch cost (module docstring), distinct ones only. ValueError for a negative weight."""
    if any(not (math.isfinite(c) and c >= 0) for c in weights):
        raise ValueError(f"line oracle weights must be finite and >= 0, got {list(weights)!r}")
    cfg = config or ControllerConfig()
    e0, e1 = tracking_error(voluntary_episode), tracking_error(reactive_episode)
    f0 = np.linalg.norm(np.asarray(voluntary_episode.voluntary, dtype=float), axis=1)
    f1 = np.linalg.norm(np.asarray(reactive_episode.voluntary, dtype=float), axis=1)
    n = min(e0.size, e1.size, f0.size, f1.size)
    if n == 0:
        return []
    e0, e1, f0, f1 = e0[:n], e1[:n], f0[:n], f1[:n]
    dt = _period(reactive_episode)
    m0, m1 = float(np.nanmean(e0 ** 2)), float(np.nanmean(e1 ** 2))
    E0, E1 = float(np.nanmean(f0)), float(np.nanmean(f1))
    rate = max(m1 - m0, 0.0) / max(E0 - E1, 1e-9)  # [m²/rad]: the line's exchange of squared error for effort
    out: list[StepSchedule] = []
    for c in weights:
        # oracle_schedule squares what it is given: pass √(e² + μ·ε), the step's priced cost
        a0 = np.sqrt(np.nan_to_num(e0 ** 2 + c * rate * f0, nan=0.0))
        a1 = np.sqrt(np.nan_to_num(e1 ** 2 + c * rate * f1, nan=0.0))
        for sw in switch_costs_s:
            lam = sw / dt * float(np.nanmean(e0 ** 2 + e1 ** 2) / 2)
            on = oracle_schedule(a0, a1, dwell_steps(cfg.min_dwell_s, dt), lam if np.isfinite(lam) else 0.0)
            if not any(np.array_equal(on, o.on) for o in out):
                out.append(StepSchedule(reactive_episode.t[:n], on, cfg.handover_s / 2))
    return out
