"""The episodes of a closed-loop sweep: what each one is (:class:`EpisodeTask`), the plan of a
sweep (:func:`plan_tasks`), and one episode run in any process (:func:`run_task`).

A sweep over percentiles p (one bundle per K_p), β and strategies S ⊆ the registry's tunable ones
(:data:`mpcshare.run_table.TUNABLE`: ``gate``, ``paper_gate``, ``blend``) runs on
held-out trials × paired seeds (for each seed every setting sees the same trial, torso sway
and wearer noise: ``run_episode(seed=seed)``):

* phase 1 — every setting (S, p, β); the parties ``voluntary`` (once: no K, no β) and
  ``reactive`` (per K: the predictor differs), what the line ratio needs; with ``oracle``, also
  ``oracle_preview`` (once: the true intent; an upper bound no test needs);
* phase 2 — ``random_handover`` matched to each setting (``matched_to`` = S), from the
  setting's schedule on the same trial and seed (:func:`mpcshare.evaluation.handover.schedule_record`),
  ``draws`` draws (default :data:`mpcshare.run_table.RANDOM_DRAWS`), draw j seeded by (seed, trial,
  p, β, S, j); the pair's placebo figure is the mean over its draws (:mod:`mpcshare.evaluation.tuning.stats`).

A row is a JSON-able dict: ``percentile``, ``beta``, ``strategy``, ``matched_to``, ``trial``,
``seed``, ``draw`` (0 but for the placebo's draws), the metrics of :mod:`sim.metrics` and
:mod:`sim.task.eating`; rows of a setting also hold its ``schedule`` record. :data:`TIMING_KEYS`
depend on wall time, nothing else does.
"""

from __future__ import annotations

import functools
from dataclasses import asdict, dataclass
from typing import Any, Sequence

from mpcshare.run_table import RANDOM_DRAWS, TUNABLE, strategy_code
from sim.task import DEFAULT_TASK, task_named

__all__ = ["BASELINES", "SETTING_STRATEGIES", "TIMING_KEYS", "EpisodeTask", "bundle_of", "episode_setup", "identity",
           "load_inputs", "plan_tasks", "random_tasks", "run_task", "run_task_seen", "task_key"]

#: Strategies that can be swept (each gets a matched ``random_handover``): the registry's tunable ones.
SETTING_STRATEGIES: tuple[str, ...] = TUNABLE
BASELINES: tuple[str, ...] = ("voluntary", "reactive", "oracle_preview", "random_handover")
#: Row keys that depend on wall time (the same seeds give the same rows except these).
TIMING_KEYS: tuple[str, ...] = ("step_p50_ms", "step_p99_ms", "realtime_factor")


@dataclass(frozen=True)
class EpisodeTask:
    """One episode: the setting, the trial, the seed and where the bundle and data are (paths, so
    that a worker process or a Ray node loads them itself)."""

    strategy: str
    percentile: float | None
    beta: float | None
    trial: int
    seed: int
    bundle_dir: str
    data_path: str
    duration_s: float | None
    wearer: str
    mode_names: tuple[str, ...] | None = None
    matched_to: str | None = None
    schedule: tuple[tuple[str, Any], ...] | None = None  # the matched setting's schedule record (items)
    draw: int = 0  # the placebo's draw
    task: str = DEFAULT_TASK  # the task's name (sim.task.task_named), whose figures the row holds


def task_key(row_or_task: Any) -> str:
    """The identity of an episode in the sweep: strategy, matched_to, percentile, β, trial, seed, draw."""
    get = row_or_task.get if isinstance(row_or_task, dict) else functools.partial(getattr, row_or_task)
    return "|".join(str(get(k, 0) if k == "draw" else get(k))
                    for k in ("strategy", "matched_to", "percentile", "beta", "trial", "seed", "draw"))


def plan_tasks(percentiles: Sequence[float], betas: Sequence[float], strategies: Sequence[str],
               trials: Sequence[int], seeds: Sequence[int], bundles: dict[float, str], data_path: str,
               duration_s: float | None, wearer: str,
               mode_names: Sequence[str] | None = None, oracle: bool = False,
               task: str = DEFAULT_TASK) -> list[EpisodeTask]:
    """Phase 1 of the sweep (module docstring), in a fixed order; ``task``: the task's name."""
    first = bundles[percentiles[0]]
    common = dict(data_path=data_path, duration_s=duration_s, wearer=wearer,
                  mode_names=tuple(mode_names) if mode_names else None, task=task)
    tasks = []
    for seed in seeds:
        for trial in trials:
            tasks.append(EpisodeTask("voluntary", None, None, trial, seed, first, **common))
            if oracle:
                tasks.append(EpisodeTask("oracle_preview", None, None, trial, seed, first, **common))
            for p in percentiles:
                tasks.append(EpisodeTask("reactive", p, None, trial, seed, bundles[p], **common))
                for s in strategies:
                    for b in betas:
                        tasks.append(EpisodeTask(s, p, b, trial, seed, bundles[p], **common))
    return tasks


def random_tasks(setting_rows: Sequence[dict[str, Any]], tasks: Sequence[EpisodeTask],
                 draws: int = RANDOM_DRAWS) -> list[EpisodeTask]:
    """Phase 2: ``draws`` ``random_handover`` episodes per row of a setting, matched to it (module docstring)."""
    if draws < 1:
        raise ValueError(f"draws must be >= 1, got {draws!r}")
    by_key = {task_key(t): t for t in tasks}
    out = []
    for row in setting_rows:
        t = by_key[task_key(row)]
        out += [EpisodeTask("random_handover", t.percentile, t.beta, t.trial, t.seed, t.bundle_dir, t.data_path,
                            t.duration_s, t.wearer, t.mode_names, matched_to=t.strategy,
                            schedule=tuple(sorted(row["schedule"].items())), draw=j, task=t.task)
                for j in range(draws)]
    return out


@functools.lru_cache(maxsize=8)
def _bundle(path: str) -> Any:
    from mpcshare.bundle import load_bundle

    return load_bundle(path)


@functools.lru_cache(maxsize=2)
def _demos(path: str) -> Any:
    from learning.data import load

    return load(path)


def load_inputs(task: EpisodeTask) -> None:
    """Load ``task``'s bundle and data into this process's caches (what a worker does once, not per episode)."""
    _bundle(task.bundle_dir)
    _demos(task.data_path)


def episode_setup(task: EpisodeTask) -> tuple[Any, dict[str, Any], float]:
    """(the :class:`~mpcshare.evaluation.StrategyRun`, the controller's options, β) of ``task``'s episode."""
    from mpcshare.evaluation import StrategyRun
    from mpcshare.evaluation.handover import random_schedules_from

    options: dict[str, Any] = {}
    run = StrategyRun(task.strategy, task.strategy)
    if task.strategy == "oracle_preview":
        run = StrategyRun(task.strategy, "reactive", oracle=True)
    elif task.strategy == "random_handover":
        run = StrategyRun(task.strategy, "schedule")
        seed = [task.seed, task.trial, round(1000 * (task.percentile or 0)), round(1000 * (task.beta or 0)),
                strategy_code(task.matched_to or "gate")]
        options["schedule"] = random_schedules_from(dict(task.schedule or ()), task.draw + 1, seed)[task.draw]
    return run, options, 0.5 if task.beta is None else task.beta


def bundle_of(task: EpisodeTask) -> Any:
    """``task``'s bundle, loaded once per process."""
    return _bundle(task.bundle_dir)


def run_task_seen(task: EpisodeTask) -> tuple[dict[str, Any], Any, float, int]:
    """Simulate one episode (any process: the bundle and data are loaded once per process, and the front end of
    a bundle and trial computed once, :func:`mpcshare.evaluation.frontend_replay.simulate_cached`) → (its row,
    the arbitration's observation-only inputs it saw (:func:`~mpcshare.evaluation.frontend_replay.decisions`;
    None where not known), its wall time [s] after loading the bundle and data, the process id)."""
    import os
    import time

    import torch

    from mpcshare.evaluation.frontend_replay import simulate_cached
    from mpcshare.evaluation.handover import schedule_record
    from sim.wearer_presets import wearer_preset

    demos = _demos(task.data_path)
    bundle = _bundle(task.bundle_dir)
    t0 = time.perf_counter()  # the episode, not the loading
    threads = torch.get_num_threads()
    torch.set_num_threads(1)  # the same arithmetic in every process, whatever the pool
    try:
        trial = next(tr for tr in demos.trials if tr.trial_id == task.trial)
        run, options, beta = episode_setup(task)
        episode, metrics, seen = simulate_cached(bundle, demos, trial, run, options, beta=beta,
                                                 duration_s=task.duration_s, seed=task.seed,
                                                 wearer=wearer_preset(task.wearer), mode_names=task.mode_names,
                                                 task=task_named(task.task))
    finally:
        torch.set_num_threads(threads)
    row = identity(task)
    row.update(metrics)
    if task.strategy in SETTING_STRATEGIES:
        row["schedule"] = schedule_record(episode)
    return row, seen, time.perf_counter() - t0, os.getpid()


def run_task(task: EpisodeTask) -> dict[str, Any]:
    """The row of one episode (:func:`run_task_seen`)."""
    return run_task_seen(task)[0]


def identity(task: EpisodeTask) -> dict[str, Any]:
    """The fields of a row that name its episode: percentile, β, strategy, matched_to, trial, seed, draw."""
    return {k: v for k, v in asdict(task).items()
            if k in ("percentile", "beta", "strategy", "matched_to", "trial", "seed", "draw")}
