"""The schedules of the replayed runs ``random_handover`` and ``oracle_handover`` from episodes.

* ``random_handover`` (the placebo): from the gate's episode on the trial, the schedule
  ``on[k] = α_k > 0.5``; each draw is :func:`mpcshare.experiments.schedule.random_schedule` with the
  same steps on, hand-overs and first state, and interior segments ≥ the dwell
  d = ⌈``min_dwell_s`` / Δ⌉ steps (or the gate's own shortest interior segment, if shorter:
  the gate's overrides switch without dwell), seeded by (seed, trial, draw).
* ``oracle_handover`` (the upper bound, never worse than the better party): the candidates of
  :func:`oracle_handover_schedules` — :func:`mpcshare.experiments.schedule.oracle_schedule` on the
  per-step tracking errors e_k = ‖p_k − p*_k‖ of the ``voluntary`` and ``reactive`` episodes on
  the trial, with dwell d, at the switch costs λ_c = c · (1/Δ) · mean(e_v² + e_r²)/2 for c in
  :data:`ORACLE_SWITCH_COSTS_S` (a hand-over costs c seconds of the parties' mean squared error:
  the wearer's pick-up and the ramp that the pure runs' errors leave out) — are each replayed in
  the closed loop, and the run keeps, per trial, the episode with the lowest tracking RMS among
  those replays *and the pure runs' own episodes* (the all-wearer and all-robot schedules). So
  per trial, and pooled (√ of weighted mean squares), it is never worse than the better party.

Both are replayed by the controller's ``schedule`` strategy, read ``handover_s``/2 ahead so
that α's ramp crosses 0.5 on the scheduled step (:class:`mpcshare.experiments.schedule.StepSchedule`).
"""

from __future__ import annotations

import math
from dataclasses import asdict
from typing import Any, Sequence

import numpy as np

from mpcshare.control.strategies import DEFAULT_STRATEGY
from mpcshare.control.types import ControllerConfig
from mpcshare.experiments.schedule import ScheduleStats, StepSchedule, oracle_schedule, random_schedule, schedule_stats

__all__ = ["ORACLE_SWITCH_COSTS_S", "SCHEDULE_SOURCES", "dwell_steps", "oracle_handover_schedule",
           "oracle_handover_schedules", "random_handover_schedules",
           "random_schedules_from", "schedule_record", "tracking_error"]

#: Switch costs of the oracle's candidates, in seconds of the parties' mean squared error (module docstring).
ORACLE_SWITCH_COSTS_S: tuple[float, ...] = (0.0, 0.5, 2.0, 8.0)
#: The runs each scheduled run is computed from.
SCHEDULE_SOURCES: dict[str, tuple[str, ...]] = {"random": (DEFAULT_STRATEGY,), "oracle": ("voluntary", "reactive")}


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
    :class:`~mpcshare.experiments.schedule.ScheduleStats` of ``α > 0.5`` and the step times
    ``t0_s + k·dt_s``."""
    alpha = np.nan_to_num(np.asarray(episode.alpha, dtype=float), nan=0.0)
    return {**asdict(schedule_stats(alpha > 0.5)), "t0_s": float(episode.t[0]), "dt_s": _period(episode)}


def random_schedules_from(record: dict[str, Any], draws: int, seed: Sequence[int],
                          config: ControllerConfig | None = None) -> list[StepSchedule]:
    """``draws`` matched-random schedules of a :func:`schedule_record` (module docstring)."""
    cfg = config or ControllerConfig()
    stats = ScheduleStats(**{k: record[k] for k in ScheduleStats.__dataclass_fields__})
    d = dwell_steps(cfg.min_dwell_s, record["dt_s"])
    if stats.min_interior is not None:
        d = min(d, stats.min_interior)
    times = record["t0_s"] + record["dt_s"] * np.arange(stats.steps)
    return [StepSchedule(times, random_schedule(stats, d, [*seed, j]), cfg.handover_s / 2) for j in range(draws)]


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
