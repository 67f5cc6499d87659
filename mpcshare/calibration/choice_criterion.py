"""The closed-loop rule choice's criterion: which candidate wins, from the figures on the choice trials.

Criterion (:data:`CRITERION`, :func:`criterion_words`): among the candidates whose effort is at most
``max_effort`` × the voluntary effort, those that meet the task's criterion (:func:`saws`: ``task.done``; eating's:
the knife saws) in every episode of its stroke mode (one per trial) where the wearer alone does
(:func:`saws_where_the_wearer_saws`; an episode where the wearer alone does not does not count against a
candidate), and of those the lowest line ratio; where the line is
ill-posed (the robot alone costs the wearer at least ``max_effort`` × the effort of doing it alone), the lowest
tracking RMS of those. When none is within the effort cap, the same without the cap. A row is a dict with
``tracking_rmse_m``, ``voluntary_effort``, ``effort_vs_voluntary``, ``line_ratio`` (None where undefined), the
pooled ``saw_correlation`` / ``saw_amplitude_ratio`` and, where known, ``saws_by_trial`` (per trial: None
without cutting, else whether it saws) and ``by_trial`` (per trial: RMS, effort, control steps).
:func:`predicted` is what the choice predicts of the chosen rule; :func:`cross_validated` the same predicted
leave one trial out (the rule chosen on the other trials, scored on the one left out).
"""

from __future__ import annotations

import math
from typing import Any

from mpcshare.line_ratio import line_ratio
from sim.task import EATING, Task

__all__ = ["CRITERION", "criterion", "criterion_words", "cross_validated", "mix_note", "predicted", "saws",
           "saws_where_the_wearer_saws", "second_stage", "wearer_saws"]


def _sawed(task: Task, trial: str = "") -> str:
    """Who passes ``task``'s criterion, in words: eating's "that saw in every cutting episode where the wearer
    alone saws" (a task with a stroke mode: sawing in that mode; without one: the criterion met)."""
    if task.stroke_mode is None:
        return f"that meet the task's criterion in every episode{trial} where the wearer alone meets it"
    return f"that saw in every {task.stroke_mode} episode{trial} where the wearer alone saws"


def criterion_words(task: Task = EATING) -> str:
    """The criterion in ``task``'s words (eating's: :data:`CRITERION`)."""
    passed = "that saw" if task.stroke_mode is not None else "that meet it"
    return (f"among the candidates with effort <= max_effort x voluntary, those {_sawed(task, ' (trial)')}, the "
            "lowest line ratio (the lowest tracking RMS where reactive itself costs >= max_effort x voluntary); if "
            f"none is within the cap, the same without the cap (the lowest line ratio of those {passed})")


#: the criterion in eating's words
CRITERION = criterion_words(EATING)


def saws(row: dict[str, Any], task: Task = EATING) -> bool:
    """Whether ``row`` meets ``task``'s criterion (:meth:`sim.task.Task.done`; eating's: the knife sawed while
    cutting, :func:`sim.task.eating.saws`)."""
    return bool(task.done(row))


def wearer_saws(voluntary: dict[str, Any], task: Task = EATING) -> bool:
    """Whether the wearer alone meets ``task``'s criterion in at least one episode (``saws_by_trial``; without
    it, the pooled figures' :func:`saws`)."""
    alone = voluntary.get("saws_by_trial")
    return any(bool(a) for a in alone) if alone is not None else saws(voluntary, task)


def saws_where_the_wearer_saws(row: dict[str, Any], voluntary: dict[str, Any], task: Task = EATING) -> bool:
    """Whether ``row`` saws (:func:`saws`) in every cutting episode, one per trial (``saws_by_trial``), in which
    the wearer alone (``voluntary``) saws; an episode where the wearer alone does not saw does not count. Without
    per-trial figures on both (or of different lengths), :func:`saws` of the pooled figures."""
    mine, alone = row.get("saws_by_trial"), voluntary.get("saws_by_trial")
    if mine is None or alone is None or len(mine) != len(alone):
        return saws(row, task)
    return all(bool(m) for m, a in zip(mine, alone) if a)


def criterion(rows: list[dict[str, Any]], vol: dict[str, Any], rea: dict[str, Any],
              max_effort: float, task: Task = EATING) -> tuple[dict[str, Any], str]:
    """The chosen row and why (module docstring), by ``task``'s criterion."""
    within = [r for r in rows if r["effort_vs_voluntary"] <= max_effort]
    sawed = " of those " + _sawed(task)
    if not within:
        sawing = [r for r in rows if saws_where_the_wearer_saws(r, vol, task)]
        pool, task_words = (sawing, sawed) if wearer_saws(vol, task) and sawing else (rows, "")
        ranked = [r for r in pool if r["line_ratio"] is not None]
        if ranked:
            best = min(ranked, key=lambda r: r["line_ratio"])
            return best, (f"no candidate has effort <= {max_effort:g}x voluntary; the lowest line ratio "
                          f"({best['line_ratio']:.3f}){task_words}")
        best = min(pool, key=lambda r: r["tracking_rmse_m"])
        return best, (f"no candidate has effort <= {max_effort:g}x voluntary and none a line ratio; the lowest "
                      f"tracking RMS ({best['tracking_rmse_m'] * 1e3:.1f} mm){task_words}")
    sawing = [r for r in within if saws_where_the_wearer_saws(r, vol, task)]
    pool, task_words = (sawing, "," + sawed) if wearer_saws(vol, task) and sawing else (within, "")
    posed = rea["voluntary_effort"] < max_effort * vol["voluntary_effort"]
    ranked = [r for r in pool if r["line_ratio"] is not None]
    if posed and ranked:
        best = min(ranked, key=lambda r: r["line_ratio"])
        return best, (f"lowest line ratio ({best['line_ratio']:.3f}) among the {len(within)} of {len(rows)} "
                      f"candidates with effort <= {max_effort:g}x voluntary{task_words}")
    best = min(pool, key=lambda r: r["tracking_rmse_m"])
    cause = (f"reactive alone costs {rea['voluntary_effort'] / vol['voluntary_effort']:.2f}x the voluntary effort, "
             "so the line is ill-posed" if not posed else "no line ratio is defined")
    return best, (f"{cause}; the lowest tracking RMS ({best['tracking_rmse_m'] * 1e3:.1f} mm) among the "
                  f"{len(within)} of {len(rows)} candidates with effort <= {max_effort:g}x voluntary{task_words}")


def second_stage(rows: list[dict[str, Any]], vol: dict[str, Any], rea: dict[str, Any], max_effort: float,
                 top: int, task: Task = EATING) -> list[dict[str, Any]]:
    """The first stage's ``top`` rows in the criterion's order (:func:`_criterion` applied again to what
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


def mix_note(best: dict[str, Any], mixes: list[dict[str, Any]], vol: dict[str, Any], rea: dict[str, Any],
             max_effort: float, task: Task = EATING) -> str:
    """"" unless a constant mixture's row (``mixes``, each with its ``strategy``) would win the criterion over the
    candidates' ``best``; then the words that say so (the gate's rule cannot be a constant mixture: the default
    strategy would have to become that mixture, without the gate's overrides)."""
    if not mixes:
        return ""
    winner, _ = criterion([best, *mixes], vol, rea, max_effort, task)
    if winner is best:
        return ""
    lr = "n/a" if winner["line_ratio"] is None else f"{winner['line_ratio']:.3f}"
    return (f"; the constant mixture {winner['strategy']} would win the criterion (line ratio {lr} at "
            f"{winner['effort_vs_voluntary']:.2f}x voluntary), but the gate's rule cannot be a constant mixture")


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
    if row.get("saws_by_trial") is not None:
        out["saws_by_trial"] = [row["saws_by_trial"][k] for k in keep]
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
