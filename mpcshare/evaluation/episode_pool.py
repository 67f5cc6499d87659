"""Closed-loop episodes of one data set, run in this process or spread over worker processes.

:class:`EpisodePool` runs batches of calls ``simulate(bundle, demos, trial, run, options, **settings)``
(:func:`mpcshare.evaluation.runs.simulate_episode`; one :class:`EpisodeJob` each: a trial, a run, the
controller's options) for a bundle and shared settings.
With ``workers`` = 1 they run here, one after the other; with more, in a spawned process pool kept until
:meth:`EpisodePool.close` (the data are sent once per worker, the bundle once per worker and bundle).
Every episode runs with one torch thread (and one BLAS thread, :func:`simulate_episode`) wherever it
runs, so the figures are the same whatever the number of workers; results come back in the jobs' order.

:func:`default_workers`: the CPU count, at most :data:`MAX_DEFAULT_WORKERS`.
"""

from __future__ import annotations

import hashlib
import multiprocessing
import os
import pickle
from concurrent.futures import Future, ProcessPoolExecutor
from dataclasses import dataclass, field
from typing import Any, Callable, Sequence

from learning.data import Demonstrations
from mpcshare.run_table import StrategyRun

#: ``simulate(bundle, demos, trial, run, options, **settings)`` → (episode, metrics)
Simulate = Callable[..., tuple[Any, dict[str, Any]]]

__all__ = ["MAX_DEFAULT_WORKERS", "EpisodeJob", "EpisodePool", "default_workers"]

#: the default number of workers is the CPU count, capped here (the project's machines have 2 cores)
MAX_DEFAULT_WORKERS = 2


def default_workers() -> int:
    """The CPU count available to this process, 1 to :data:`MAX_DEFAULT_WORKERS`."""
    try:
        n = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        n = os.cpu_count() or 1
    return max(1, min(MAX_DEFAULT_WORKERS, n))


@dataclass(frozen=True)
class EpisodeJob:
    """One episode: ``run`` on the trial ``trial`` with the controller's ``options`` added."""

    trial: int
    run: StrategyRun
    options: dict[str, Any] = field(default_factory=dict)


# --- the worker side: the data set once per process, the bundle cached by its digest ---
_DEMOS: Demonstrations | None = None
_BUNDLE: tuple[str, Any] | None = None


def _init_worker(demos: Demonstrations) -> None:
    global _DEMOS
    import torch

    torch.set_num_threads(1)
    _DEMOS = demos


def _call_in_worker(fn: Callable[..., Any], digest: str, bundle_bytes: bytes, args: tuple, kwargs: dict) -> Any:
    global _BUNDLE
    if _BUNDLE is None or _BUNDLE[0] != digest:
        _BUNDLE = (digest, pickle.loads(bundle_bytes))
    assert _DEMOS is not None, "the worker was started without its data set"
    return fn(_BUNDLE[1], _DEMOS, *args, **kwargs)


def _simulate(bundle: Any, demos: Demonstrations, simulate: Simulate, job: EpisodeJob,
              settings: dict[str, Any]) -> tuple[Any, Any]:
    trial = next((tr for tr in demos.trials if tr.trial_id == int(job.trial)), None)
    if trial is None:
        raise ValueError(f"trial {job.trial} not in the data (it has {demos.trial_ids[:20]})")
    return simulate(bundle, demos, trial, job.run, dict(job.options), **settings)


class EpisodePool:
    """Episodes of ``demos`` in this process (``workers`` = 1) or in ``workers`` spawned processes."""

    def __init__(self, demos: Demonstrations, workers: int = 1) -> None:
        if int(workers) < 1:
            raise ValueError(f"workers must be >= 1, got {workers!r}")
        self.demos, self.workers = demos, int(workers)
        self._pool: ProcessPoolExecutor | None = None

    def __enter__(self) -> EpisodePool:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()

    def map(self, simulate: Simulate, bundle: Any, jobs: Sequence[EpisodeJob],
            **settings: Any) -> list[tuple[Any, dict[str, Any]]]:
        """(episode, metrics) = ``simulate(bundle, demos, trial, job.run, job.options, **settings)`` of each
        job, in the jobs' order. With workers, ``simulate``, the bundle and the settings must pickle (functions
        defined at module level); ValueError names what does not."""
        if self.workers == 1:
            from learning.torch_threads import torch_threads

            with torch_threads(1):
                return [_simulate(bundle, self.demos, simulate, job, settings) for job in jobs]
        pickled = self._pickled(bundle)
        futures = [self._submit(_simulate, pickled, (simulate, job, settings), {}) for job in jobs]
        return [f.result() for f in futures]

    def call(self, fn: Callable[..., Any], bundle: Any, *args: Any, **kwargs: Any) -> Future:
        """``fn(bundle, demos, *args, **kwargs)`` in a worker process (started on first use), or at once in
        this process with ``workers`` = 1; its future. ``fn`` (defined at module level), the bundle and the
        arguments must pickle; ValueError names what does not."""
        if self.workers == 1:
            done: Future = Future()
            try:
                done.set_result(fn(bundle, self.demos, *args, **kwargs))
            except Exception as exc:  # handed to the caller through the future, as from a worker
                done.set_exception(exc)
            return done
        return self._submit(fn, self._pickled(bundle), args, kwargs)

    def _submit(self, fn: Callable[..., Any], pickled: tuple[str, bytes], args: tuple, kwargs: dict) -> Future:
        try:
            pickle.dumps((fn, args, kwargs))
        except (pickle.PicklingError, AttributeError, TypeError) as exc:
            raise ValueError(f"work on {self.workers} workers needs functions defined at module level and "
                             f"arguments that pickle: {exc}") from None
        if self._pool is None:
            ctx = multiprocessing.get_context("spawn")  # torch and fork do not mix
            self._pool = ProcessPoolExecutor(max_workers=self.workers, mp_context=ctx, initializer=_init_worker,
                                             initargs=(self.demos,))
        return self._pool.submit(_call_in_worker, fn, *pickled, args, kwargs)

    def _pickled(self, bundle: Any) -> tuple[str, bytes]:
        """(digest, bytes) of the pickled bundle: a worker unpickles a bundle once per digest."""
        try:
            data = pickle.dumps(bundle)
        except (pickle.PicklingError, AttributeError, TypeError) as exc:
            raise ValueError(f"work on {self.workers} workers needs a bundle that pickles: {exc}") from None
        return hashlib.sha1(data).hexdigest(), data

    def close(self) -> None:
        """Stop the worker processes (a later :meth:`map` starts new ones)."""
        if self._pool is not None:
            self._pool.shutdown(cancel_futures=True)
            self._pool = None
