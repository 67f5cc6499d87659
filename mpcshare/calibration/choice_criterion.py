"""The closed-loop rule choice's criterion: which candidate wins, from the figures on the choice trials.

Criterion (in words: :func:`mpcshare.reports.rule_choice.criterion_words`): among the candidates whose effort is at
most ``max_effort`` × the voluntary effort, those that meet the task's criterion (:func:`saws`: ``task.done``;
eating's: the knife saws) in every episode of its stroke mode (each run of it at least
:data:`sim.task.metrics.MIN_EPISODE_S` long; where no candidate does, or the rows have no episodes, in each trial's
episodes as a whole) where the wearer alone does (:func:`saws_where_the_wearer_saws`; an episode where the wearer
alone does not does not count against a candidate), and of those the lowest line ratio; where the line is
ill-posed (the robot alone costs the wearer at least ``max_effort`` × the effort of doing it alone), the lowest
tracking RMS of those. When none is within the effort cap, the same without the cap. A row is a dict with
``tracking_rmse_m``, ``voluntary_effort``, ``effort_vs_voluntary``, ``line_ratio`` (None where undefined), the
pooled ``saw_correlation`` / ``saw_amplitude_ratio`` and, where known, ``saws_by_trial`` (per trial: None
without cutting, else whether it saws), ``saws_by_episode`` (per trial: whether it saws in each of its cutting
episodes, in time order) and ``by_trial`` (per trial: RMS, effort, control steps).
:func:`criterion` returns the winner and the reason as a record (:func:`criterion`'s fields), never words.
:func:`predicted` is what the choice predicts of the chosen rule; :func:`cross_validated` the same predicted
leave one trial out (the rule chosen on the other trials, scored on the one left out).
"""

from __future__ import annotations

import math
from typing import Any

from mpcshare.line_ratio import line_ratio
from sim.task import EATING, Task

__all__ = ["criterion", "cross_validated", "episode_pairs", "mix_winner", "predicted", "saws",
           "saws_where_the_wearer_saws", "second_stage", "wearer_saws"]


def saws(row: dict[str, Any], task: Task = EATING) -> bool:
    """Whether ``row`` meets ``task``'s criterion (:meth:`sim.task.Task.done`; eating's: the knife sawed while
    cutting, :func:`sim.task.eating.saws`)."""
    return bool(task.done(row))


def wearer_saws(voluntary: dict[str, Any], task: Task = EATING) -> bool:
    """Whether the wearer alone meets ``task``'s criterion in at least one cutting episode (``saws_by_episode``;
    without it, in one trial, ``saws_by_trial``; without that, the pooled figures' :func:`saws`)."""
    episodes, alone = voluntary.get("saws_by_episode"), voluntary.get("saws_by_trial")
    if episodes is not None and any(len(e or ()) for e in episodes):
        return any(bool(a) for e in episodes for a in (e or ()))
    return any(bool(a) for a in alone) if alone is not None else saws(voluntary, task)


def saws_where_the_wearer_saws(row: dict[str, Any], voluntary: dict[str, Any], task: Task = EATING,
                               by_episode: bool = True) -> bool:
    """Whether ``row`` saws (:func:`saws`) in every cutting episode in which the wearer alone (``voluntary``)
    saws; an episode where the wearer alone does not saw does not count. The episodes are ``saws_by_episode``'s
    where both rows have them, trial by trial, in the same number (the same trials and seconds: the same
    labelled episodes) and ``by_episode``; else each trial's cutting as a whole (``saws_by_trial``); without
    those on both (or of different lengths), :func:`saws` of the pooled figures."""
    pairs = episode_pairs(row, voluntary) if by_episode else None
    if pairs is not None:
        return all(bool(m) for m, a in pairs if a)
    mine, alone = row.get("saws_by_trial"), voluntary.get("saws_by_trial")
    if mine is None or alone is None or len(mine) != len(alone):
        return saws(row, task)
    return all(bool(m) for m, a in zip(mine, alone) if a)


def episode_pairs(row: dict[str, Any], voluntary: dict[str, Any]) -> list[tuple[bool, bool]] | None:
    """(``row`` saws, the wearer alone saws) per cutting episode, over the trials in order; None where the two
    rows' ``saws_by_episode`` are missing, hold no episode or do not line up trial by trial."""
    mine, alone = row.get("saws_by_episode"), voluntary.get("saws_by_episode")
    if (mine is None or alone is None or len(mine) != len(alone)
            or any(len(m or ()) != len(a or ()) for m, a in zip(mine, alone)) or not any(len(a or ()) for a in alone)):
        return None
    return [(bool(m), bool(a)) for ms, As in zip(mine, alone) for m, a in zip(ms or (), As or ())]


def criterion(rows: list[dict[str, Any]], vol: dict[str, Any], rea: dict[str, Any],
              max_effort: float, task: Task = EATING) -> tuple[dict[str, Any], dict[str, Any]]:
    """The chosen row and the reason (module docstring), by ``task``'s criterion. The reason is a JSON record:
    ``within_cap`` (some candidate has effort <= ``max_effort`` × voluntary), ``n_within`` of ``n_candidates``,
    ``max_effort``, ``by`` (``"line_ratio"`` or ``"tracking_rmse_m"``: what ranked the pool), the winner's
    ``line_ratio`` (None where undefined) and ``tracking_rmse_m`` [m], ``ill_posed`` (within the cap: reactive
    alone costs >= ``max_effort`` × voluntary), ``reactive_effort_vs_voluntary``, ``task_filter`` (False, or the
    pool was narrowed to the rows that meet the task's criterion where the wearer alone does: ``"episode"`` in
    every episode, or, where no candidate does, ``"trial"`` over each trial's episodes as a whole) and
    ``stroke_mode`` (``task.stroke_mode``: whose episodes)."""
    within = [r for r in rows if r["effort_vs_voluntary"] <= max_effort]
    capped = bool(within)
    candidates = within if capped else rows
    level: str | bool = False
    pool = candidates
    for by in ("episode", "trial") if wearer_saws(vol, task) else ():
        sawing = [r for r in candidates if saws_where_the_wearer_saws(r, vol, task, by == "episode")]
        if sawing:
            level, pool = by, sawing
            break
    posed = rea["voluntary_effort"] < max_effort * vol["voluntary_effort"]
    ranked = [r for r in pool if r["line_ratio"] is not None]
    if ranked and (posed or not capped):
        best, by = min(ranked, key=lambda r: r["line_ratio"]), "line_ratio"
    else:
        best, by = min(pool, key=lambda r: r["tracking_rmse_m"]), "tracking_rmse_m"
    return best, {"within_cap": capped, "n_within": len(within), "n_candidates": len(rows),
                  "max_effort": float(max_effort), "by": by, "line_ratio": best["line_ratio"],
                  "tracking_rmse_m": float(best["tracking_rmse_m"]), "ill_posed": capped and not posed,
                  "reactive_effort_vs_voluntary": (float(rea["voluntary_effort"] / vol["voluntary_effort"])
                                                   if vol["voluntary_effort"] else None),
                  "task_filter": level, "stroke_mode": task.stroke_mode}


def second_stage(rows: list[dict[str, Any]], vol: dict[str, Any], rea: dict[str, Any], max_effort: float,
                 top: int, task: Task = EATING) -> list[dict[str, Any]]:
    """The first stage's ``top`` rows in the criterion's order (:func:`criterion` applied again to what
    is left), and the empty set's row (the robot leading every mode) where it is not among them."""
    left, picked = list(rows), []
    while left and len(picked) < top:
        best, _ = criterion(left, vol, rea, max_effort, task)
        picked.append(best)
        left = [r for r in left if r is not best]
    picked += [r for r in left if not r["wearer_modes"]][:1]
    return picked


def predicted(row: dict[str, Any], voluntary: dict[str, Any], task: Task = EATING) -> dict[str, Any]:
    """What the choice predicts of its rule from ``row``'s figures on the choice trials: ``line_ratio`` (None where
    undefined), ``effort_vs_voluntary``, ``tracking_rmse_m`` [m], ``saw_correlation`` (mean over the cutting
    episodes; None without cutting) and ``saws`` (:func:`saws_where_the_wearer_saws`)."""
    return {"line_ratio": row["line_ratio"], "effort_vs_voluntary": row["effort_vs_voluntary"],
            "tracking_rmse_m": row["tracking_rmse_m"], "saw_correlation": row.get("saw_correlation"),
            "saws": saws_where_the_wearer_saws(row, voluntary, task)}


def mix_winner(best: dict[str, Any], mixes: list[dict[str, Any]], vol: dict[str, Any], rea: dict[str, Any],
               max_effort: float, task: Task = EATING) -> dict[str, Any] | None:
    """None unless a constant mixture's row (``mixes``, each with its ``strategy``) would win the criterion over the
    candidates' ``best``; then that mixture's ``strategy``, ``line_ratio`` (None where undefined) and
    ``effort_vs_voluntary`` (the gate's rule cannot be a constant mixture: the default strategy would have to become
    that mixture, without the gate's overrides)."""
    if not mixes:
        return None
    winner, _ = criterion([best, *mixes], vol, rea, max_effort, task)
    if winner is best:
        return None
    return {"strategy": winner["strategy"], "line_ratio": winner["line_ratio"],
            "effort_vs_voluntary": float(winner["effort_vs_voluntary"])}


def _subset(row: dict[str, Any], keep: list[int]) -> dict[str, Any]:
    """``row`` re-pooled over the trials ``keep`` (:func:`mpcshare.evaluation.pool_metrics`' weights: RMS as
    √(Σ n_k·rms_k² / Σ n_k), effort as the n_k-weighted mean); the pooled stroke figures are dropped (the
    per-trial sawing stays)."""
    per = [row["by_trial"][k] for k in keep]
    n = sum(t["steps"] for t in per)
    out = {k: v for k, v in row.items() if k not in ("saw_correlation", "saw_amplitude_ratio", "by_trial")}
    out["tracking_rmse_m"] = math.sqrt(sum(t["steps"] * t["tracking_rmse_m"] ** 2 for t in per) / n)
    out["voluntary_effort"] = sum(t["steps"] * t["voluntary_effort"] for t in per) / n
    out["by_trial"] = per
    for key in ("saws_by_trial", "saws_by_episode"):
        if row.get(key) is not None:
            out[key] = [row[key][k] for k in keep]
    return out


def _scored(row: dict[str, Any], vol: dict[str, Any], rea: dict[str, Any]) -> dict[str, Any]:
    """``row`` with its line ratio and effort against ``vol`` and ``rea`` (the same trials)."""
    return {**row, "line_ratio": line_ratio(row["tracking_rmse_m"], row["voluntary_effort"],
                                            (vol["voluntary_effort"], vol["tracking_rmse_m"]),
                                            (rea["voluntary_effort"], rea["tracking_rmse_m"])),
            "effort_vs_voluntary": row["voluntary_effort"] / vol["voluntary_effort"]}


def cross_validated(rows: list[dict[str, Any]], vol: dict[str, Any], rea: dict[str, Any],
                    max_effort: float, task: Task = EATING) -> dict[str, Any] | None:
    """The choice's prediction left one trial out: for each trial k, :func:`criterion` on the other trials
    chooses a row, whose figures on trial k are kept; the kept figures pooled over k (as :func:`_subset`) give
    ``line_ratio`` (against the parties pooled over all trials), ``effort_vs_voluntary`` and ``tracking_rmse_m``
    [m], and ``chosen`` the index into ``rows`` chosen for each trial left out. No simulation. None with fewer
    than 2 trials or without per-trial figures (``by_trial``)."""
    n = len(vol.get("by_trial") or [])
    if n < 2 or any(len(r.get("by_trial") or []) != n for r in [rea, *rows]):
        return None
    held: list[dict[str, Any]] = []
    chosen: list[int] = []
    for k in range(n):
        rest = [i for i in range(n) if i != k]
        v, r = _subset(vol, rest), _subset(rea, rest)
        fold = [_scored(_subset(row, rest), v, r) for row in rows]
        best, _ = criterion(fold, v, r, max_effort, task)
        i = fold.index(best)
        chosen.append(i)
        held.append(rows[i]["by_trial"][k])
    pooled = _scored(_subset({"by_trial": held}, list(range(n))), vol, rea)
    return {"line_ratio": pooled["line_ratio"], "effort_vs_voluntary": pooled["effort_vs_voluntary"],
            "tracking_rmse_m": pooled["tracking_rmse_m"], "chosen": chosen}
