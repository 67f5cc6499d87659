"""The default gate's wearer modes chosen in the closed loop on held-out trials of the user's own data.

:func:`choose_rule` simulates (:func:`mpcshare.evaluation.simulate_episode`, a simulated wearer) on the trials:

1. ``voluntary`` and ``reactive``, read as each mode's price ρ_j [m²/rad]
   (:func:`mpcshare.calibration.mode_cost.mode_costs`);
2. the candidates (:func:`candidate_sets`): the wearer leads the top 1, 2, … modes by price, each also with the
   labelled cutting modes, or none (the robot leads every mode); each non-empty set with each hand-over timing
   of :data:`HANDOVER_TIMINGS`, the robot at full share while it leads; a set the per-mode costs put at no
   less effort and error than the wearer alone is not simulated (:func:`mpcshare.calibration.mode_cost.prune_sets`);
3. the best :data:`SECOND_STAGE_TOP` of those and the empty set with the other shares of :data:`ROBOT_ALPHAS`.

Each candidate's score is its line ratio r = RMS / RMS_line(e) (:func:`line_ratio`; below 1: better than mixing
the two parties at the same effort e). The criterion (:mod:`mpcshare.calibration.choice_criterion`): within
``max_effort`` × the voluntary effort, those that saw in every cutting episode where the wearer alone saws, and of
those the lowest r (the lowest RMS where the line is ill-posed); if none is within the cap, the same without it.
Returns the choice, every candidate's figures (the constant mixtures :data:`MIXES` as comparators), the per-mode
costs, the reason (a record) and its words (:mod:`mpcshare.reports.rule_choice`), and what it predicts of the
chosen rule; raises ValueError without a mode model or a trial. Why these candidates and this criterion:
docs/design.md, "Chosen in the closed loop, by what each mode costs".
"""

from __future__ import annotations

import time
from contextlib import nullcontext
from typing import Any, Callable, Mapping, Sequence

import numpy as np

from learning.data import Demonstrations
from mpcshare.bundle.rule import CalibratedRule
from mpcshare.calibration.choice_criterion import (
    criterion,
    cross_validated,
    mix_winner,
    predicted,
    saws,
    saws_where_the_wearer_saws,
    second_stage,
    wearer_saws,
)
from mpcshare.calibration.mode_cost import cutting_effort, cutting_modes, mode_costs, price_order, prune_sets
from mpcshare.calibration.trials import STROKE_SEEN_S, choice_seconds, choice_trials
from mpcshare.control.strategies import by_role
from mpcshare.control.strategies.gate import GateSettings
from mpcshare.control.types import ControllerConfig
from mpcshare.evaluation import StrategyRun, pool_metrics, simulate_episode
from mpcshare.evaluation.distinct import map_distinct, trace_key
from mpcshare.evaluation.episode import Seconds, trial_seconds
from mpcshare.evaluation.episode_pool import EpisodeJob, EpisodePool, default_workers
from mpcshare.evaluation.frontend_replay import simulate_cached
from mpcshare.line_ratio import line_ratio as _line_ratio
from mpcshare.reports.rule_choice import candidate_line, criterion_words, pruned_line, ran_line, why_words
from mpcshare.training.config import RULE_DURATION_S
from sim.task import EATING, Task
from sim.wearer import WearerConfig

__all__ = ["EARLY_HANDOVER_SETTINGS", "HANDOVER_SETTINGS", "HANDOVER_TIMINGS", "MIXES", "ROBOT_ALPHAS",
           "SECOND_STAGE_TOP", "candidate_sets", "choose_for_bundle", "choose_rule", "line_ratio", "pooled_run",
           "pooled_runs", "predicted", "saws", "saws_where_the_wearer_saws", "wearer_saws"]

#: the gate's thresholds on s = the forecast probability of a wearer mode within lead_s (with hysteresis)
HANDOVER_SETTINGS = {"share_on": 0.5, "share_off": 0.3, "lead_s": GateSettings().lead_s,
                     "hold_s": GateSettings().hold_s}
#: the early timing: the wearer takes the lead at a forecast probability of 0.2 within 1.5 s and keeps it
#: for 1 s after it falls below 0.1, while the robot still tracks, before the knife's intent jumps into a wearer
#: mode (the pick-up it avoids: docs/design.md)
EARLY_HANDOVER_SETTINGS = {"share_on": 0.2, "share_off": 0.1, "lead_s": 1.5, "hold_s": 1.0}
#: the hand-over timings each non-empty wearer-mode set is tried with: name → the gate's settings
HANDOVER_TIMINGS = {"prompt": HANDOVER_SETTINGS, "early": EARLY_HANDOVER_SETTINGS}
#: the robot's shares α while the wearer leads (the gate's ``wearer_alpha``) each non-empty wearer-mode set is
#: tried with: only 0, the wearer alone (why: docs/design.md, "The robot's share while the wearer leads");
#: pass ``wearer_alphas`` to try others
WEARER_ALPHAS = (0.0,)
#: the robot's shares α while it leads (the gate's ``robot_alphas``, the same in every mode): the first with
#: every candidate, the others in the second stage (why: docs/design.md, "The robot's share while it leads")
ROBOT_ALPHAS = (1.0, 0.5)
#: the constant mixtures (``mix`` strategies) run on the choice trials beside the parties: comparators in the
#: choice's table and its why, not candidates (the default strategy runs the gate with the bundle's rule)
MIXES = ("mix25", "mix50", "mix75")
#: how many of the first stage's candidates (at the first robot share) the other shares are tried on, beside
#: the empty set (the robot leading every mode)
SECOND_STAGE_TOP = 2


def line_ratio(rms: float, effort: float, voluntary: dict[str, float], reactive: dict[str, float]) -> float | None:
    """RMS / RMS_line(effort) of :func:`mpcshare.line_ratio.line_ratio` (the one definition: the line
    held at its ends, never extrapolated), from the parties' pooled metrics; None where undefined."""
    return _line_ratio(rms, effort, (voluntary["voluntary_effort"], voluntary["tracking_rmse_m"]),
                       (reactive["voluntary_effort"], reactive["tracking_rmse_m"]))


def candidate_sets(order: Sequence[int], cutting: Sequence[int], n_modes: int) -> list[list[int]]:
    """The wearer-mode sets to try (module docstring): the prefixes of ``order`` (modes by price), each
    also joined with the ``cutting`` modes, the cutting modes alone, and last the empty set (the robot
    leads every mode); never all ``n_modes`` (that is ``voluntary``); sorted sets, no repeats."""
    sets: list[list[int]] = []
    prefixes = [list(order[:i]) for i in range(1, len(order) + 1)]
    for base in prefixes + ([[]] if cutting else []):
        for s in (base, sorted(set(base) | set(cutting))):
            s = sorted(int(j) for j in s)
            if s and len(s) < n_modes and s not in sets:
                sets.append(s)
    return sets + [[]]


def _variants(sets: list[list[int]], timings: Sequence[str], wearer_alphas: Sequence[float],
              robot_alphas: Sequence[float] = (1.0,)) -> list[tuple[list[int], str, float, float]]:
    """Each wearer-mode set with each hand-over timing, each robot share while the wearer leads
    (``wearer_alphas``) and each robot share while the robot leads (``robot_alphas``); the empty set, with
    no hand-over, with the first timing and wearer share 0 only."""
    return [(m, h, float(a), float(r)) for m in sets for h in (timings if m else timings[:1])
            for a in (wearer_alphas if m else (0.0,)) for r in robot_alphas]


def pooled_runs(bundle: Any, demos: Demonstrations, trials: Sequence[int],
                specs: Sequence[tuple[str, dict | None]], duration_s: Seconds, wearer: WearerConfig | None,
                seed: int, mode_names: Sequence[str] | None = None,
                pool: EpisodePool | None = None,
                seen: dict[int, np.ndarray] | None = None,
                ran: list[int] | None = None, task: Task = EATING,
                known: dict[Any, tuple[Any, dict[str, Any]]] | None = None) -> list[tuple[dict[str, float], list[Any]]]:
    """:func:`pooled_run` of each (strategy, gate options) in ``specs``, every episode in one batch of
    ``pool`` (default: this process), in the order of ``specs``. With ``seen`` (trial → what its arbitration
    sees, :func:`mpcshare.evaluation.frontend_replay.decisions`) the front end is computed once per process and
    trial and replayed; empty, it is filled; filled, the episodes whose arbitration decides the same on it run
    once (:func:`~mpcshare.evaluation.distinct.map_distinct`), and with ``known`` (filled by the first batch: its
    episodes by :func:`~mpcshare.evaluation.distinct.trace_key`) a later episode that decides as one of the first
    batch's at every step is that episode. The figures are the same either way.
    ``ran``: the number of episodes simulated is appended to it. ``task``: whose figures and criterion."""
    jobs = [EpisodeJob(int(tid), StrategyRun(strategy, strategy),
                       {"config": ControllerConfig(strategy_settings=dict(options))} if options else {})
            for strategy, options in specs for tid in trials]
    settings = {"beta": 0.5, "duration_s": duration_s, "seed": seed, "wearer": wearer, "mode_names": mode_names,
                "task": task}
    pool = pool or EpisodePool(demos)
    n_run = len(jobs)
    if seen is None:
        done = pool.map(simulate_episode, bundle, jobs, **settings)
    elif not seen:  # the first batch: what each trial's arbitration sees
        first = pool.map(simulate_cached, bundle, jobs, **settings)
        for job, (_, _, inputs) in zip(jobs, first):
            if inputs is not None:
                seen.setdefault(int(job.trial), inputs)
        done = [r[:2] for r in first]
        for job, (episode, metrics, inputs) in zip(jobs, first) if known is not None else ():
            key = trace_key(bundle, job, seen, settings["beta"]) if _same(inputs, seen.get(int(job.trial))) else None
            if key is not None:
                known.setdefault(key, (episode, metrics))
    else:
        done, n_run = map_distinct(pool, bundle, jobs, seen, known, **settings)
    if ran is not None:
        ran.append(n_run)
    n = len(trials)
    return [_pooled(done[i * n:(i + 1) * n], task) for i in range(len(specs))]


def _same(a: np.ndarray | None, b: np.ndarray | None) -> bool:
    """Whether two recorded decision inputs are present and the same to the bit."""
    return a is not None and b is not None and a.shape == b.shape and a.tobytes() == b.tobytes()


def pooled_run(bundle: Any, demos: Demonstrations, trials: Sequence[int], strategy: str, options: dict | None,
               duration_s: Seconds, wearer: WearerConfig | None, seed: int,
               mode_names: Sequence[str] | None = None,
               pool: EpisodePool | None = None, task: Task = EATING) -> tuple[dict[str, float], list[Any]]:
    """Pooled figures of ``strategy`` on ``trials`` (RMS, effort, limit violations, mean stroke correlation
    while cutting or None) and the episodes."""
    return pooled_runs(bundle, demos, trials, [(strategy, options)], duration_s, wearer, seed, mode_names, pool,
                       task=task)[0]


def _pooled(done: Sequence[tuple[Any, dict[str, Any]]], task: Task = EATING) -> tuple[dict[str, float], list[Any]]:
    """The figures of :func:`pooled_run` from (episode, metrics) per trial, and the episodes."""
    ms = [m for _, m in done]
    episodes = [ep for ep, _ in done]
    steps = [np.asarray(ep.step_time, dtype=float) for ep in episodes]
    secs = [float(ep.t[-1] - ep.t[0]) for ep in episodes]
    p = pool_metrics(ms, steps, secs)
    out = {k: p[k] for k in ("tracking_rmse_m", "voluntary_effort", "limit_violations")}
    for key in ("saw_correlation", "saw_amplitude_ratio"):
        vals = [m[key] for m in ms if m.get(key) is not None]
        out[key] = float(np.mean(vals)) if vals else None
    # per trial: whether it meets the task's criterion; None for a trial without the stroke mode
    out["saws_by_trial"] = [None if task.stroke_mode is not None and m.get("saw_correlation") is None
                            else saws(m, task) for m in ms]
    # per trial: whether it meets the criterion in each cutting episode (sim.task.metrics.sawing_by_episode)
    out["saws_by_episode"] = None if task.stroke_mode is None else [
        [saws(e, task) for e in (m.get("saw_by_episode") or ())] for m in ms]
    out["by_trial"] = [{"tracking_rmse_m": float(m["tracking_rmse_m"]),
                        "voluntary_effort": float(m["voluntary_effort"]), "steps": int(len(s))}
                       for m, s in zip(ms, steps)]
    return out, episodes


def _n_modes(bundle: Any) -> int:
    """The mode model's number of modes; ValueError when the bundle has none."""
    modes = getattr(bundle, "modes", None)
    A = getattr(modes, "transmat_", None)
    if A is None:
        raise ValueError("the bundle has no mode model (modes.transmat_) whose modes the wearer could lead")
    return int(np.shape(A)[0])


def _cutting(bundle_episodes: list[Any], demos: Demonstrations, trials: Sequence[int],
             mode_names: Sequence[str] | None, n_modes: int, task: Task = EATING) -> list[int]:
    """The controller's modes that carry the labelled stroke mode of ``task`` (eating's: cutting; none without
    labels or that name)."""
    if not mode_names or task.stroke_mode not in mode_names:
        return []
    by_id = {tr.trial_id: tr for tr in demos.trials}
    labels = [by_id[int(t)].mode for t in trials]
    if any(lab is None for lab in labels):
        return []
    return cutting_modes(bundle_episodes, labels, list(mode_names).index(task.stroke_mode), n_modes)


def _check_variants(timings: Sequence[str], robot_alphas: Sequence[float]) -> None:
    """ValueError naming an unknown hand-over timing or a robot share outside [0.5, 1]."""
    unknown = sorted(set(timings) - set(HANDOVER_TIMINGS))
    if unknown or not timings:
        raise ValueError(f"unknown hand-over timing(s) {unknown or timings!r}; valid: {', '.join(HANDOVER_TIMINGS)}")
    bad = [a for a in robot_alphas if not 0.5 <= float(a) <= 1.0]
    if bad or not robot_alphas:
        raise ValueError(f"robot_alphas must be shares in [0.5, 1] (the robot leads from 0.5), got {robot_alphas!r}")


def _check_mixes(mixes: Sequence[str]) -> None:
    """ValueError naming the ``mixes`` that are not registered constant mixtures."""
    unknown = sorted(set(mixes) - set(by_role("mix")))
    if unknown:
        raise ValueError(f"mixes {unknown} are not constant mixtures; valid: {', '.join(by_role('mix'))}")


def _mix_rows(names: Sequence[str], figures: Sequence[dict[str, Any]], vol: dict[str, Any],
              rea: dict[str, Any]) -> list[dict[str, Any]]:
    """The constant mixtures' rows: their pooled ``figures`` with the strategy's name, line ratio and effort."""
    return [{"strategy": name, **m, "line_ratio": line_ratio(m["tracking_rmse_m"], m["voluntary_effort"], vol, rea),
             "effort_vs_voluntary": m["voluntary_effort"] / vol["voluntary_effort"]} for name, m in zip(names, figures)]


def _task_effort(task_effort: float | None, cutting: Sequence[int], best: dict[str, Any], vol: dict[str, Any],
                 max_effort: float, task: Task = EATING) -> dict[str, Any] | None:
    """None unless leading the ``cutting`` modes costs more than ``max_effort`` (``task_effort``) and the chosen
    ``best`` does not both saw and stay within it (no such rule can); then ``cutting_modes``,
    ``effort_vs_voluntary`` (``task_effort``) and ``max_effort``."""
    if task_effort is None or task_effort <= max_effort or (saws_where_the_wearer_saws(best, vol, task) and
                                                             best["effort_vs_voluntary"] <= max_effort):
        return None
    return {"cutting_modes": [int(j) for j in cutting], "effort_vs_voluntary": float(task_effort),
            "max_effort": float(max_effort)}


def _log_ran(log: Callable[[str], None] | None, ran: int, planned: int) -> None:
    """Say how many of the choice's episodes were simulated, where some were not (they repeat one)."""
    if log is not None and ran < planned:
        log(ran_line(ran, planned))


def choose_rule(bundle: Any, demos: Demonstrations, trials: Sequence[int], *,
                duration_s: Seconds = RULE_DURATION_S,
                max_effort: float = 0.75, wearer: WearerConfig | None = None, seed: int = 0,
                mode_names: Sequence[str] | None = None, wearer_alphas: Sequence[float] = WEARER_ALPHAS,
                timings: Sequence[str] = tuple(HANDOVER_TIMINGS), robot_alphas: Sequence[float] = ROBOT_ALPHAS,
                log: Callable[[str], None] | None = None, pool: EpisodePool | None = None,
                prune: bool = True, mixes: Sequence[str] = MIXES, task: Task = EATING) -> dict[str, Any]:
    """Choose the gate's wearer modes in the closed loop (module docstring). ``duration_s``: the seconds of each
    trial simulated (:data:`~mpcshare.evaluation.episode.Seconds`); ``mode_names``: the names of the demonstrations'
    mode labels (the one named ``task.stroke_mode`` is the task's stroke; None: no sawing figures); ``timings``:
    the names of :data:`HANDOVER_TIMINGS` each wearer-mode set is tried with; ``wearer_alphas``: the robot's shares
    while the wearer leads that each wearer-mode set is tried with (:data:`WEARER_ALPHAS`); ``robot_alphas``: the
    robot's shares while it leads, in [0.5, 1] (:data:`ROBOT_ALPHAS`): the first with every candidate, the others
    with the second stage's (module docstring); ``pool``: where the episodes run (default: this process; each
    stage's episodes are one batch); ``prune``: leave out the wearer-mode sets the per-mode costs put at no
    less effort and error than the wearer alone (:func:`mpcshare.calibration.mode_cost.prune_sets`; listed under
    ``"pruned"``); ``mixes``: the constant mixtures run beside the parties as comparators (:data:`MIXES`; rows under
    ``"mixes"``; the why says so where one would win the criterion); ``task``: whose figures and criterion.
    Returns ``{"settings", "wearer_modes", "reason" (``criterion``: :func:`~mpcshare.calibration.choice_criterion.
    criterion`'s record; ``mixture``: :func:`~mpcshare.calibration.choice_criterion.mix_winner`'s; ``task_effort``:
    None, or the cutting modes whose lead costs more than ``max_effort``), "why" (the reason in words:
    :func:`mpcshare.reports.rule_choice.why_words`), "criterion", "predicted", "cross_validated", "candidates",
    "mixes", "pruned", "voluntary", "reactive", "mode_costs", "price_order", "cutting_modes",
    "cutting_effort_vs_voluntary" (:func:`mpcshare.calibration.mode_cost.cutting_effort`), "robot_alphas" (the
    shares tried), "trials", "duration_s" (the longest of a trial's; None: whole trials), "duration_by_trial"
    ([trial, seconds] each, where per trial), "episodes_run" (an episode that decides as another at every step
    is that episode), "seconds"}``. ValueError without a mode model or a trial.
    """
    if not len(trials):
        raise ValueError("choose_rule needs at least one held-out trial")
    n_modes = _n_modes(bundle)
    t0 = time.perf_counter()

    seen: dict[int, np.ndarray] = {}  # what each trial's arbitration sees (the first batch)
    known: dict[Any, tuple[Any, dict[str, Any]]] = {}  # the first batch's episodes by how they decide
    ran: list[int] = []  # episodes simulated
    def run(specs: list[tuple[str, dict | None]]) -> list[tuple[dict[str, float], list[Any]]]:
        return pooled_runs(bundle, demos, trials, specs, duration_s, wearer, seed, mode_names, pool, seen=seen, ran=ran,
                           task=task, known=known)

    _check_mixes(mixes)
    (vol, vol_eps), (rea, rea_eps), *mixed = run([("voluntary", None), ("reactive", None), *((m, None) for m in mixes)])
    mix_rows = _mix_rows(mixes, [m for m, _ in mixed], vol, rea)
    costs = mode_costs(vol_eps, rea_eps, n_modes)
    order = price_order(costs)
    cutting = _cutting(vol_eps, demos, trials, mode_names, n_modes, task)
    rows: list[dict[str, Any]] = []
    _check_variants(timings, robot_alphas)

    def evaluate(variants: list[tuple[list[int], str, float, float]]) -> None:
        # each candidate's settings replace a bundle's earlier rule as a whole
        settings = [{"wearer_modes": modes, **HANDOVER_TIMINGS[timing], "wearer_alpha": a_w,
                     "robot_alphas": [a_r] * n_modes} for modes, timing, a_w, a_r in variants]
        for (modes, timing, a_w, a_r), st, (m, _) in zip(variants, settings, run([("gate", x) for x in settings])):
            rows.append({"wearer_modes": modes, "timing": timing, "wearer_alpha": a_w, "robot_alpha": a_r,
                         "settings": st, **m,
                         "line_ratio": line_ratio(m["tracking_rmse_m"], m["voluntary_effort"], vol, rea),
                         "effort_vs_voluntary": m["voluntary_effort"] / vol["voluntary_effort"]})
            if log is not None:
                log(candidate_line(rows[-1]))

    sets, pruned = prune_sets(costs, candidate_sets(order, cutting, n_modes), vol["voluntary_effort"], prune)
    for r in pruned if log is not None else []:
        log(pruned_line(r))
    evaluate(_variants(sets, list(timings), wearer_alphas, robot_alphas[:1]))
    evaluate([(r["wearer_modes"], r["timing"], r["wearer_alpha"], float(a_r))
              for r in second_stage(rows, vol, rea, max_effort, SECOND_STAGE_TOP, task) for a_r in robot_alphas[1:]])
    best, by_criterion = criterion(rows, vol, rea, max_effort, task)
    _log_ran(log, sum(ran), len(trials) * (2 + len(mixes) + len(rows)))
    task_effort = cutting_effort(costs, cutting)
    reason = {"criterion": by_criterion, "mixture": mix_winner(best, mix_rows, vol, rea, max_effort, task),
              "task_effort": _task_effort(task_effort, cutting, best, vol, max_effort, task)}
    return {"settings": best["settings"], "wearer_modes": best["wearer_modes"], "reason": reason,
            "why": why_words(reason), "criterion": criterion_words(task), "predicted": predicted(best, vol, task),
            "cross_validated": cross_validated(rows, vol, rea, max_effort, task),
            "cutting_effort_vs_voluntary": task_effort, "max_effort": max_effort, "candidates": rows,
            "mixes": mix_rows, "voluntary": vol, "reactive": rea, "mode_costs": costs, "price_order": order,
            "cutting_modes": cutting, "pruned": pruned, "robot_alphas": [float(a) for a in robot_alphas],
            "trials": [int(t) for t in trials], **_duration_record(duration_s, trials), "episodes_run": sum(ran),
            "seconds": round(time.perf_counter() - t0, 1)}


def _duration_record(duration_s: Seconds, trials: Sequence[int]) -> dict[str, Any]:
    """The choice record's ``duration_s`` (the longest; None where a trial runs whole) and, for seconds per trial,
    ``duration_by_trial``."""
    if not isinstance(duration_s, Mapping):
        return {"duration_s": duration_s}
    by_trial = [[int(t), trial_seconds(duration_s, t)] for t in trials]
    whole = any(s is None for _, s in by_trial)
    return {"duration_s": None if whole else max(float(s) for _, s in by_trial), "duration_by_trial": by_trial}


def choose_for_bundle(bundle: Any, demos: Demonstrations, *, n_trials: int | None = None,
                      duration_s: float | None = RULE_DURATION_S, wearer_name: str | None = None,
                      mode_names: Sequence[str] | None = None,
                      log: Callable[[str], None] | None = None, pool: EpisodePool | None = None,
                      workers: int | None = None, task: Task = EATING,
                      mixes: Sequence[str] = MIXES, robot_alphas: Sequence[float] = ROBOT_ALPHAS,
                      by_subject: bool = True, stroke_seen_s: float | None = STROKE_SEEN_S) -> dict[str, Any]:
    """:func:`choose_rule` on ``n_trials`` held-out trials of ``bundle`` (:func:`choice_trials`: default half of
    them, 1 to 2, dealt round the demonstrations' subjects; ``by_subject`` False: the last ones), ``duration_s``
    of each, longer for a trial that shows less than ``stroke_seen_s`` of the task's stroke in them
    (:func:`choice_seconds`, logged; None: ``duration_s`` whatever the trials show), with the wearer
    preset ``wearer_name`` (default the default preset), the demonstrations' ``mode_names`` (for ``task``'s
    stroke modes), the comparators ``mixes`` and the robot's shares ``robot_alphas`` (:func:`choose_rule`),
    recorded as the bundle's rule (``bundle.rule``, a :class:`~mpcshare.bundle.rule.CalibratedRule` for
    ``gate``) so that the saved bundle's ``gate`` uses it; returns the choice. The episodes run in ``pool``,
    else in a pool of ``workers`` processes (default :func:`mpcshare.evaluation.episode_pool.default_workers`)
    closed afterwards; the choice is the same whatever the number. What ``mpcshare train``, ``mpcshare demo``
    and the benchmarks call."""
    from sim.wearer_presets import DEFAULT_WEARER_PRESET, wearer_preset

    name = wearer_name or DEFAULT_WEARER_PRESET
    subjects = {int(tr.trial_id): tr.subject for tr in demos.trials} if by_subject else None
    trials = choice_trials(bundle.heldout_trials, n_trials, subjects)
    stroke = list(mode_names).index(task.stroke_mode) if mode_names and task.stroke_mode in mode_names else None
    by_id = {int(tr.trial_id): tr for tr in demos.trials}
    own = {} if stroke_seen_s is None else choice_seconds(
        [by_id[t] for t in trials if t in by_id], duration_s, demos.rate_hz, stroke, stroke_seen_s)
    longer = {t: s for t, s in own.items() if s != duration_s}
    seconds: Seconds = {t: own.get(t, duration_s) for t in trials} if longer else duration_s
    if log is not None and longer:
        log(f"the choice runs {', '.join(f'{s:g} s of trial {t}' for t, s in longer.items())} (the others "
            f"{duration_s:g} s): less than {stroke_seen_s:g} s of the stroke ({task.stroke_mode}) in the first "
            f"{duration_s:g} s")
    with EpisodePool(demos, workers or default_workers()) if pool is None else nullcontext(pool) as episodes:
        choice = choose_rule(bundle, demos, trials, duration_s=seconds, log=log, wearer=wearer_preset(name),
                             mode_names=mode_names, pool=episodes, task=task, mixes=mixes,
                             robot_alphas=robot_alphas)
    choice["wearer"] = name
    bundle.rule = CalibratedRule("gate", choice["settings"], choice)
    return choice
