"""Running a closed-loop sweep: bundles per K, episodes on a backend, rows kept as they finish.

:func:`run_tune` trains one bundle per percentile on one data preparation
(:func:`mpcshare.training.train.train_bundles`: the HMM and quotients are fitted once) into
``out/bundles/p<P>``, runs phase 1 of :mod:`mpcshare.evaluation.tuning.episodes` and each setting's phase 2
as soon as the setting is done on a backend, episodes that decide alike once
(:mod:`mpcshare.evaluation.tuning.dispatch`), and appends each finished row at once to ``out/episodes.jsonl``.
Started again with the same arguments (``out/sweep_args.json``) it reuses the bundles and the rows already there
and runs only the rest; with other arguments it starts over.

Backends (:func:`open_backend`, one for the whole sweep): ``local`` — in this process (``workers`` = 1) or a
``concurrent.futures`` process pool (spawned workers); ``ray`` — one Ray task per episode on
the cluster at ``address`` (None: a local Ray). Each episode is deterministic given its task,
so the rows are the same whatever the backend and the number of workers (but
:data:`~mpcshare.evaluation.tuning.episodes.TIMING_KEYS`).
"""

from __future__ import annotations

import json
import multiprocessing
from collections import deque
from concurrent.futures import FIRST_COMPLETED, Future, ProcessPoolExecutor, wait
from pathlib import Path
from typing import Any, Callable, Sequence

from learning.atomic import write_json
from mpcshare.errors import MpcshareError
from mpcshare.evaluation.tuning.dispatch import dispatch
from mpcshare.evaluation.tuning.episodes import EpisodeTask, plan_tasks, random_tasks, run_task_seen, task_key
from mpcshare.run_table import RANDOM_DRAWS
from sim.task import DEFAULT_TASK

__all__ = ["BACKENDS", "RayMissing", "estimate_line", "open_backend", "run_tune"]

BACKENDS: tuple[str, ...] = ("local", "ray")


class RayMissing(MpcshareError, ImportError):
    """``--backend ray`` without Ray installed."""


class _LocalPool:
    """This process (``workers`` = 1) or one spawned process pool kept for the whole sweep."""

    def __init__(self, workers: int) -> None:
        self.workers = workers
        self.capacity = 1 if workers <= 1 else workers + 1  # one queued per free worker: no idle turn
        self.pool: ProcessPoolExecutor | None = None
        self.queue: deque[EpisodeTask] = deque()
        self.futures: dict[Future, EpisodeTask] = {}

    def submit(self, task: EpisodeTask) -> None:
        if self.workers <= 1:
            self.queue.append(task)
            return
        if self.pool is None:
            ctx = multiprocessing.get_context("spawn")  # torch and fork do not mix
            self.pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=ctx)
        self.futures[self.pool.submit(run_task_seen, task)] = task

    def next_done(self) -> tuple[EpisodeTask, Any]:
        if self.workers <= 1:
            task = self.queue.popleft()
            return task, run_task_seen(task)
        done, _ = wait(self.futures, return_when=FIRST_COMPLETED)
        fut = next(iter(done))
        return self.futures.pop(fut), fut.result()

    def close(self) -> None:
        if self.pool is not None:
            self.pool.shutdown(cancel_futures=True)


class _RayCluster:
    """One Ray task per episode on the cluster at ``address`` (None: a local Ray)."""

    def __init__(self, address: str | None) -> None:
        try:
            import ray
        except ImportError:
            raise RayMissing("--backend ray needs Ray: pip install -e .[ray] (or choose --backend local)") from None
        if not ray.is_initialized():
            ray.init(address=address, include_dashboard=False, log_to_driver=False)
        self.ray = ray
        self.remote = ray.remote(num_cpus=1)(run_task_seen)
        self.workers = max(1, int(ray.cluster_resources().get("CPU", 1)))
        self.capacity = self.workers + 1
        self.refs: dict[Any, EpisodeTask] = {}

    def submit(self, task: EpisodeTask) -> None:
        self.refs[self.remote.remote(task)] = task

    def next_done(self) -> tuple[EpisodeTask, Any]:
        (ref,), _ = self.ray.wait(list(self.refs), num_returns=1)
        return self.refs.pop(ref), self.ray.get(ref)

    def close(self) -> None:
        pass


def open_backend(backend: str = "local", workers: int = 1, address: str | None = None) -> _LocalPool | _RayCluster:
    """A backend with ``workers``, ``capacity`` (episodes kept in flight), ``submit(task)``, ``next_done()`` → (a
    task, :func:`~mpcshare.evaluation.tuning.episodes.run_task_seen` of it), one at a time as they finish, and
    ``close()`` (module docstring)."""
    if backend == "local":
        return _LocalPool(workers)
    if backend == "ray":
        return _RayCluster(address)
    raise ValueError(f"unknown backend {backend!r}; valid choices: {', '.join(BACKENDS)}")


class _Store:
    """Rows by task key, appended to ``episodes.jsonl`` one line per finished episode."""

    def __init__(self, out: Path, signature: dict[str, Any]) -> None:
        self.path = out / "episodes.jsonl"
        args = out / "sweep_args.json"
        self.rows: dict[str, dict[str, Any]] = {}
        if args.exists() and json.loads(args.read_text()) == signature and self.path.exists():
            for line in self.path.read_text().splitlines():
                try:
                    row = json.loads(line)
                except json.JSONDecodeError:  # a line cut by an interruption
                    continue
                self.rows[task_key(row)] = row
        else:
            self.path.write_text("")
            write_json(signature, args, indent=1)

    def add(self, row: dict[str, Any]) -> None:
        self.rows[task_key(row)] = row
        with self.path.open("a") as f:
            f.write(json.dumps(row) + "\n")


def _bundles(data: Any, config: Any, percentiles: Sequence[float], out: Path, progress: bool) -> dict[float, str]:
    """``out/bundles/p<P>`` per percentile, trained once on one data preparation (kept when present)."""
    from mpcshare.bundle import is_bundle, save_bundle
    from mpcshare.training.train import train_bundles

    paths = {p: out / "bundles" / f"p{p:g}" for p in percentiles}
    todo = [p for p in percentiles if not is_bundle(paths[p])]
    if todo:
        for p, bundle in train_bundles(data, config, todo, progress=progress).items():
            save_bundle(bundle, paths[p])
    return {p: str(paths[p]) for p in percentiles}


def estimate_line(seconds: float, n_left: int, workers: int, first_s: float, replay_s: float) -> str:
    """``about M min for the N episodes left on W worker(s)``: ``seconds`` [s] of wall time projected
    (:meth:`mpcshare.evaluation.tuning.dispatch.Costs.estimate`) from ``first_s`` [s], a bundle and trial's
    first episode in a worker (it records the front end), and ``replay_s`` [s], the others."""
    return (f"about {seconds / 60:.1f} min for the {n_left} episodes left on {workers} worker(s) (measured: a "
            f"bundle and trial's first episode in a worker {first_s:.1f} s, the others {replay_s:.1f} s)")


def run_tune(data_path: str | Path, out: str | Path, *, percentiles: Sequence[float], betas: Sequence[float],
             strategies: Sequence[str], n_trials: int, seeds: Sequence[int], duration_s: float | None,
             wearer: str, config: Any = None, backend: str = "local", workers: int = 1,
             address: str | None = None, progress: bool = True, mode_names: Sequence[str] | None = None,
             log: Callable[[str], None] | None = print, draws: int = RANDOM_DRAWS,
             oracle: bool = False, task: str = DEFAULT_TASK) -> dict[str, Any]:
    """Run the sweep (module docstring; ``draws`` placebo episodes per setting episode; ``oracle``: with the
    ``oracle_preview`` upper bound; ``task``: the name of the task whose figures the rows hold,
    :func:`sim.task.task_named`); returns ``{"rows": [...], "trials": [...], "bundles": {...}}``. Before
    the bundles are trained it logs how many episodes it plans, and once its first episodes have measured what
    an episode costs, about how long the rest will take (:func:`estimate_line`); at the end how many ran.

    Raises ValueError when the data has fewer held-out trials than ``n_trials``.
    """
    from learning.data import load, split_by_trial
    from mpcshare.training.config import TrainConfig

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    config = config or TrainConfig()
    signature = {"data": str(Path(data_path).resolve()), "percentiles": list(percentiles), "betas": list(betas),
                 "strategies": list(strategies), "trials": n_trials, "seeds": list(seeds),
                 "duration_s": duration_s, "wearer": wearer, "config": config.to_dict(), "draws": draws,
                 "oracle": oracle, **({"task": task} if task != DEFAULT_TASK else {})}  # eating's resume as before
    demos = load(data_path)
    _, held = split_by_trial(demos, config.heldout_fraction, seed=config.seed)  # the split training makes
    heldout = [int(t) for t in held.trial_ids]
    if len(heldout) < n_trials:
        raise ValueError(f"--trials {n_trials}: the data has only {len(heldout)} held-out trials {heldout}; "
                         f"valid: 1 to {len(heldout)}")
    trials = heldout[:n_trials]
    store = _Store(out, signature)
    paths = {p: str(out / "bundles" / f"p{p:g}") for p in percentiles}
    tasks = plan_tasks(percentiles, betas, strategies, trials, seeds, paths, str(Path(data_path).resolve()),
                       duration_s, wearer, mode_names, oracle=oracle, task=task)
    n_placebo = draws * sum(t.strategy in strategies for t in tasks)  # phase 2: draws per setting episode
    n_total = len(tasks) + n_placebo
    where = f"{workers} local worker(s)" if backend == "local" else "a Ray cluster"
    if log is not None:
        length = f"{duration_s:g} s" if duration_s else "whole trials"
        log(f"tune plans {n_total} closed-loop episodes of {length}: {len(tasks)} of the "
            f"settings and the parties, {n_placebo} placebo draws ({draws} per setting episode), on {where}"
            + (f"; {len(store.rows)} already done" if store.rows else ""))
    bundles = _bundles(demos, config, percentiles, out, progress)
    bar = None
    if progress:
        from learning.progress import progress_bar
        bar = progress_bar(total=int(n_total), desc="tune", unit="episode", initial=len(store.rows))
    runner = open_backend(backend, workers, address)

    def add(row: dict[str, Any]) -> None:
        store.add(row)
        if bar is not None:
            bar.update(1)

    def said(seconds: float, n_left: int, costs: Any) -> None:
        if log is not None:
            log(estimate_line(seconds, n_left, runner.workers, *costs.means()))

    try:
        counts = dispatch(runner, tasks, dict(store.rows), add,
                          lambda t, row: random_tasks([row], [t], draws) if t.strategy in strategies else [],
                          said)
    finally:
        runner.close()
        if bar is not None:
            bar.close()
    settings = [store.rows[task_key(t)] for t in tasks if t.strategy in strategies and task_key(t) in store.rows]
    phase2 = random_tasks(settings, tasks, draws)
    order = {task_key(t): i for i, t in enumerate(tasks + phase2)}
    rows = sorted((r for k, r in store.rows.items() if k in order), key=lambda r: order[task_key(r)])
    if log is not None:
        log(f"{len(rows)} episodes ({len(tasks) + len(phase2) - len(rows)} missing) in {out / 'episodes.jsonl'}: "
            f"{counts['run']} run, {counts['shared']} given the figures of an episode that decided alike")
    return {"rows": rows, "trials": trials, "bundles": {f"{p:g}": b for p, b in bundles.items()}}
