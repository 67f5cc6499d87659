"""Episodes that decide alike run once: :func:`map_distinct`.

Two controllers that differ only in their strategy give the same episode on a trial where their arbitration
gives the same α, β at every step (the rest of the controller and the world do not read the strategy). Where a
strategy reads only the arbitration's observation-only inputs (:func:`mpcshare.evaluation.frontend_replay.decisions`:
time, gate probability, novelty, prediction finite, fork available, mode posterior; not the wearer's or the
robot's command, which the closed loop moves), its α, β follow from those inputs alone, without the closed
loop (:func:`decision_trace`). :func:`map_distinct` runs one job of each group with the same trace on the same
trial and gives its result to the others, once the episode run is shown to have seen exactly those inputs
(else the others run too).
"""

from __future__ import annotations

from typing import Any, Sequence

import numpy as np

from mpcshare.evaluation.frontend_replay import FrontEndDiverged, simulate_cached

__all__ = ["decision_trace", "map_distinct", "trace_key"]


class _Unknown:
    """A command the prediction does not know: any use raises (the strategy reads the closed loop)."""

    def __getattr__(self, name: str) -> Any:
        raise FrontEndDiverged("the strategy reads the closed loop's commands")

    def __array_ufunc__(self, *args: Any, **kwargs: Any) -> Any:
        raise FrontEndDiverged("the strategy reads the closed loop's commands")

    def __matmul__(self, other: Any) -> Any:
        raise FrontEndDiverged("the strategy reads the closed loop's commands")

    __rmatmul__ = __mul__ = __rmul__ = __add__ = __radd__ = __sub__ = __rsub__ = __matmul__


def decision_trace(arbiter: Any, inputs: np.ndarray) -> bytes | None:
    """The (α, β) that ``arbiter`` (a controller's :class:`~mpcshare.control.arbitration.Arbiter`, reset here)
    gives for each row of ``inputs`` (:func:`decisions`), as bytes; None where its strategy reads the wearer's or
    the robot's command (which the closed loop moves) or it raises. Two controllers that differ only in their
    arbitration and give the same trace on the decisions their episodes see run the same episode."""
    arbiter.reset()
    unknown = _Unknown()
    out = []
    try:
        for row in inputs:
            gate = None if row[5] else float(row[1])
            d = arbiter.decide(float(row[0]), gate, float(row[2]), bool(row[3]), bool(row[4]),
                               mode_proba=None if row[6] else row[7:], u_r=unknown, u_v=unknown)
            out.append((d.alpha, d.beta))
    except Exception:  # noqa: BLE001 — not predictable from the inputs: run it
        return None
    finally:
        arbiter.reset()
    return np.asarray(out, dtype=float).tobytes()


def trace_key(bundle: Any, job: Any, inputs: dict[int, np.ndarray], beta: float) -> Any:
    """(trial, :func:`decision_trace`) of ``job`` on its trial's ``inputs``: the key under which episodes that
    decide alike are one episode; None where the trace is not predictable (no inputs for the trial, the MPC, an
    oracle or a schedule, or a strategy that reads the closed loop)."""
    from mpcshare.control.controller import SharedController

    seen = inputs.get(int(job.trial))
    if seen is None or job.run.use_mpc or job.run.oracle or job.run.schedule is not None:
        return None
    c = SharedController.from_bundle(bundle, strategy=job.run.strategy, beta=beta, use_mpc=False, **job.options)
    trace = decision_trace(c.arbiter, seen)
    return None if trace is None else (int(job.trial), trace)


def map_distinct(pool: Any, bundle: Any, jobs: Sequence[Any], inputs: dict[int, np.ndarray],
                 known: dict[Any, tuple[Any, dict[str, Any]]] | None = None,
                 **settings: Any) -> tuple[list[tuple[Any, dict[str, Any]]], int]:
    """``pool.map`` of :func:`simulate_cached` over ``jobs`` (:class:`~mpcshare.evaluation.episode_pool.EpisodeJob`
    with the same settings and options but the strategy and its ``config.strategy_settings``), where the jobs
    whose arbitration gives the same :func:`decision_trace` for their trial's :func:`decisions` (``inputs``:
    trial → those of an earlier episode) run once and share the result: the rest of the controller and the
    world do not depend on the strategy. That holds where the episode run saw those decisions (its arbitration's
    inputs are the observations'); where it did not, the others run too. ``known``: :func:`trace_key` →
    (episode, metrics) of episodes already run that saw exactly ``inputs`` (e.g. an earlier batch's); a job with
    such a key takes that result and does not run. Returns (episode, metrics) per job, in order, and the number
    of episodes run."""
    known = known or {}
    keys = [trace_key(bundle, job, inputs, settings["beta"]) or ("run", i) for i, job in enumerate(jobs)]
    first: dict[Any, int] = {}
    for i, key in enumerate(keys):
        if key not in known:
            first.setdefault(key, i)
    unique = sorted(set(first.values()))
    done = dict(zip(unique, pool.map(simulate_cached, bundle, [jobs[i] for i in unique], **settings)))
    again = [i for i, key in enumerate(keys)
             if i not in done and key not in known and not _saw(done[first[key]][2], inputs, jobs[i])]
    done.update(zip(again, pool.map(simulate_cached, bundle, [jobs[i] for i in again], **settings)))
    return [done[i][:2] if i in done else known[key] if key in known else done[first[key]][:2]
            for i, key in enumerate(keys)], len(unique) + len(again)


def _saw(seen: np.ndarray | None, inputs: dict[int, np.ndarray], job: Any) -> bool:
    """Whether the episode run for ``job``'s group saw the decisions its trace was predicted from."""
    expected = inputs.get(int(job.trial))
    return seen is not None and expected is not None and seen.shape == expected.shape and \
        seen.tobytes() == expected.tobytes()
