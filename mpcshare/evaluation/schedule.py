"""Given hand-over schedules: the matched-random placebo and the oracle upper bound.

A schedule is a boolean sequence ``on[k]`` over control steps k (True: the robot leads,
α = 1). Its *segments* are the maximal runs of equal values; its hand-overs are the
changes ``on[k] ≠ on[k-1]``; its dwell is the length of the interior segments (the first
segment starts before the episode and the last is cut by its end, so neither is bound).

* :func:`random_schedule` — the placebo ``random_handover``: the same number of steps on,
  the same number of hand-overs, the same first state and every interior segment at
  least ``dwell`` steps long, with the hand-over times drawn at random (seeded). The
  segment lengths are ``dwell`` plus a uniformly random composition of the slack
  (stars and bars), separately for the on and the off segments.
* :func:`oracle_schedule` — the upper bound ``oracle_handover``: the schedule that
  minimises Σ_k e_{on[k]}[k]² over the per-step tracking errors of the pure runs
  (e_0: ``voluntary``, e_1: ``reactive``) with interior segments ≥ ``dwell`` steps, by
  dynamic programming over (state, steps since the last switch capped at ``dwell``).
* :class:`StepSchedule` — a schedule as a function of time for the arbiter's
  ``schedule`` strategy, read ``lead_s`` ahead (the arbiter's α ramp then crosses 0.5 on
  the scheduled step instead of ``handover_s``/2 later).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Sequence

import numpy as np

__all__ = ["LevelSchedule", "ScheduleStats", "StepSchedule", "oracle_schedule", "random_schedule", "schedule_stats"]


@dataclass(frozen=True)
class ScheduleStats:
    """Steps on (α = 1), hand-overs, shortest interior segment [steps] (None: fewer than 3 segments),
    first state, steps in all."""

    on_steps: int
    handovers: int
    min_interior: int | None
    first_on: bool
    steps: int


def _segments(on: np.ndarray) -> np.ndarray:
    """Lengths of the maximal runs of equal values of ``on``."""
    on = np.asarray(on, dtype=bool)
    if on.size == 0:
        return np.zeros(0, dtype=int)
    edges = np.flatnonzero(np.diff(on.astype(np.int8))) + 1
    return np.diff(np.concatenate([[0], edges, [on.size]]))


def schedule_stats(on: np.ndarray) -> ScheduleStats:
    """The figures a matched schedule keeps (module docstring)."""
    on = np.asarray(on, dtype=bool)
    seg = _segments(on)
    return ScheduleStats(on_steps=int(on.sum()), handovers=max(int(seg.size) - 1, 0),
                         min_interior=int(seg[1:-1].min()) if seg.size >= 3 else None,
                         first_on=bool(on[0]) if on.size else False, steps=int(on.size))


def _composition(total: int, parts: int, minimum: list[int], rng: np.random.Generator) -> np.ndarray:
    """``parts`` integers ≥ ``minimum`` summing to ``total``, the slack split uniformly (stars and bars)."""
    if parts == 0:
        return np.zeros(0, dtype=int)
    slack = total - sum(minimum)
    if slack < 0:
        raise ValueError(f"cannot fit {parts} segments of at least {minimum} steps into {total} steps")
    cuts = np.sort(rng.choice(slack + parts - 1, parts - 1, replace=False)) if parts > 1 else np.zeros(0, int)
    bounds = np.concatenate([[-1], cuts, [slack + parts - 1]])
    return np.diff(bounds) - 1 + np.asarray(minimum, dtype=int)


def random_schedule(stats: ScheduleStats, dwell: int, seed: int | Sequence[int]) -> np.ndarray:
    """A random schedule with ``stats``' steps, steps on, hand-overs and first state, interior
    segments ≥ ``dwell`` steps (first and last ≥ 1). ValueError when that cannot be met."""
    if dwell < 1:
        raise ValueError(f"dwell must be at least 1 step, got {dwell!r}")
    n_seg = stats.handovers + 1
    states = [(stats.first_on if i % 2 == 0 else not stats.first_on) for i in range(n_seg)]
    mins = [1 if i in (0, n_seg - 1) else dwell for i in range(n_seg)]
    if stats.handovers == 0:
        return np.full(stats.steps, stats.first_on)
    rng = np.random.default_rng(seed)
    lengths = np.zeros(n_seg, dtype=int)
    for value, total in ((True, stats.on_steps), (False, stats.steps - stats.on_steps)):
        idx = [i for i in range(n_seg) if states[i] == value]
        lengths[idx] = _composition(total, len(idx), [mins[i] for i in idx], rng)
    return np.repeat(np.array(states, dtype=bool), lengths)


def oracle_schedule(err_off: np.ndarray, err_on: np.ndarray, dwell: int, switch_cost: float = 0.0) -> np.ndarray:
    """The schedule minimising Σ_k e_{on[k]}[k]² + ``switch_cost``·(hand-overs) [m²] with interior
    segments ≥ ``dwell`` steps.

    ``err_off``, ``err_on``: (N,) per-step tracking errors [m] of the wearer alone and the
    robot alone (non-finite errors count as 0: no information). Dynamic programming over
    the state (on, r) with r = min(steps in the current segment, dwell); a switch needs
    r = dwell; the first segment is free (the episode starts at r = dwell).
    """
    e0 = np.nan_to_num(np.asarray(err_off, dtype=float) ** 2, nan=0.0, posinf=0.0)
    e1 = np.nan_to_num(np.asarray(err_on, dtype=float) ** 2, nan=0.0, posinf=0.0)
    if e0.shape != e1.shape or e0.ndim != 1:
        raise ValueError(f"err_off and err_on must be equal-length 1-D arrays, got {e0.shape} and {e1.shape}")
    if dwell < 1:
        raise ValueError(f"dwell must be at least 1 step, got {dwell!r}")
    if not (math.isfinite(switch_cost) and switch_cost >= 0):
        raise ValueError(f"switch_cost must be finite and >= 0 [m²], got {switch_cost!r}")
    n, d, lam = e0.size, int(dwell), float(switch_cost)
    if n == 0:
        return np.zeros(0, dtype=bool)
    cost = np.full((2, d), math.inf)  # cost[s, r-1]
    cost[0, d - 1], cost[1, d - 1] = e0[0], e1[0]
    stay_at_d = np.zeros((n, 2), dtype=bool)  # at r = d: came from (s, d) rather than (s, d-1)
    for k in range(1, n):
        new = np.full((2, d), math.inf)
        for s, e in ((0, e0[k]), (1, e1[k])):
            new[s, 0] = cost[1 - s, d - 1] + e + lam  # switch
            if d > 1:
                new[s, 1:d - 1] = cost[s, :d - 2] + e
                stay = cost[s, d - 1] <= cost[s, d - 2]
                stay_at_d[k, s] = stay
                new[s, d - 1] = min(cost[s, d - 1], cost[s, d - 2]) + e
            else:  # every step may switch
                stay_at_d[k, s] = cost[s, 0] <= cost[1 - s, 0] + lam
                new[s, 0] = min(cost[s, 0], cost[1 - s, 0] + lam) + e
        cost = new
    s, r = np.unravel_index(int(np.argmin(cost)), cost.shape)
    on = np.zeros(n, dtype=bool)
    for k in range(n - 1, -1, -1):
        on[k] = bool(s)
        if k == 0:
            break
        if d == 1:
            s = s if stay_at_d[k, s] else 1 - s
        elif r == 0:
            s, r = 1 - s, d - 1
        elif r < d - 1 or not stay_at_d[k, s]:
            r -= 1
    return on


class StepSchedule:
    """α = ``on_alpha`` (the robot leads, at that share) or 0 by control step as a function of time: the
    call at t reads ``on[k]`` for the last step time ``times[k]`` ≤ t + ``lead_s`` (``on[0]`` before the first)."""

    def __init__(self, times: np.ndarray, on: np.ndarray, lead_s: float = 0.0, on_alpha: float = 1.0) -> None:
        self.times = np.asarray(times, dtype=float)
        self.on = np.asarray(on, dtype=bool)
        if self.times.shape != self.on.shape or self.times.ndim != 1 or self.times.size == 0:
            raise ValueError(f"times and on must be equal-length non-empty 1-D arrays, got {self.times.shape} "
                             f"and {self.on.shape}")
        if not (math.isfinite(lead_s) and lead_s >= 0):
            raise ValueError(f"lead_s must be finite and ≥ 0, got {lead_s!r}")
        self.lead_s = float(lead_s)
        if not 0.5 <= on_alpha <= 1.0:
            raise ValueError(f"on_alpha must be in [0.5, 1] (the robot leads from 0.5), got {on_alpha!r}")
        self.on_alpha = float(on_alpha)

    def __call__(self, t: float) -> float:
        k = int(np.searchsorted(self.times, float(t) + self.lead_s + 1e-9, side="right")) - 1
        return self.on_alpha if self.on[max(k, 0)] else 0.0


class LevelSchedule:
    """α by control step as a function of time, any authority level: 0 (the wearer leads) or a share in
    [0.5, 1] (the robot leads, the convex mixture below 1), as the ``schedule`` strategy replays it; the call
    at t reads ``alpha[k]`` for the last step time ``times[k]`` ≤ t + ``lead_s`` (``alpha[0]`` before)."""

    def __init__(self, times: np.ndarray, alpha: np.ndarray, lead_s: float = 0.0) -> None:
        self.times, self.alpha = np.asarray(times, dtype=float), np.asarray(alpha, dtype=float)
        if self.times.shape != self.alpha.shape or self.times.ndim != 1 or self.times.size == 0:
            raise ValueError(f"times and alpha must be equal-length non-empty 1-D arrays, got {self.times.shape} "
                             f"and {self.alpha.shape}")
        bad = ~((self.alpha == 0.0) | ((self.alpha >= 0.5) & (self.alpha <= 1.0)))
        if bad.any():
            raise ValueError(f"alpha must be 0 (the wearer leads) or in [0.5, 1] (the robot leads), got "
                             f"{self.alpha[bad][0]!r} at step {int(np.flatnonzero(bad)[0])}")
        if not (math.isfinite(lead_s) and lead_s >= 0):
            raise ValueError(f"lead_s must be finite and ≥ 0, got {lead_s!r}")
        self.lead_s = float(lead_s)

    def __call__(self, t: float) -> float:
        k = int(np.searchsorted(self.times, float(t) + self.lead_s + 1e-9, side="right")) - 1
        return float(self.alpha[max(k, 0)])
