"""A sweep's episodes on a backend: alike ones run once, each setting's placebo draws as soon as it is done.

:func:`dispatch` keeps ``backend.capacity`` episodes in flight. It submits first an episode of each bundle and
trial whose arbitration inputs are not yet known (it records the front end and shows the inputs), then episodes of
known bundles and trials, each under its :meth:`~mpcshare.evaluation.tuning.alike.Alike.key`: an episode whose key
is already run or in flight waits for that one and takes its figures (:mod:`mpcshare.evaluation.tuning.alike`);
where that run did not see the inputs its key came from, it runs itself. ``follow(task, row)`` gives the episodes
a finished one calls for (a setting's placebo draws), queued at once.

:class:`Costs` measures what an episode costs: the first of a bundle and trial in a worker records the front end,
the rest replay it (:mod:`mpcshare.evaluation.frontend_replay`), and :meth:`Costs.estimate` projects the wall time
left from the two means, the distinct episodes left and the recordings still to come.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable, Sequence

from mpcshare.evaluation.tuning.alike import Alike, where
from mpcshare.evaluation.tuning.episodes import SETTING_STRATEGIES, EpisodeTask, identity, task_key

__all__ = ["Costs", "dispatch"]


@dataclass
class Costs:
    """Wall times [s] of the episodes run so far: recordings (the first of a bundle and trial in a process) and
    replays; which (process, bundle and trial) have recorded."""

    recorded: list[float] = field(default_factory=list)
    replayed: list[float] = field(default_factory=list)
    seen: set[tuple[Any, ...]] = field(default_factory=set)

    def add(self, task: EpisodeTask, seconds: float, pid: int) -> None:
        """Count one episode run in process ``pid``."""
        key = (pid, *where(task))
        (self.replayed if key in self.seen else self.recorded).append(seconds)
        self.seen.add(key)

    def means(self) -> tuple[float, float]:
        """(the recordings' mean, the replays' mean (the recordings' without one)) [s]."""
        rec = sum(self.recorded) / len(self.recorded)
        return rec, sum(self.replayed) / len(self.replayed) if self.replayed else rec

    def ready(self, workers: int) -> bool:
        """Whether both means are measured (a recording and ``workers`` replays at least)."""
        return bool(self.recorded) and len(self.replayed) >= workers

    def estimate(self, distinct_left: int, wheres: int, workers: int) -> float:
        """Wall time [s] of ``distinct_left`` episodes on ``workers`` processes: each process records each of the
        ``wheres`` bundles and trials once (those not yet recorded cost the recordings' mean), the rest replay
        (the replays' mean)."""
        rec, rep = self.means()
        to_record = min(distinct_left, max(0, workers * wheres - len(self.seen)))
        return (to_record * rec + (distinct_left - to_record) * rep) / max(1, workers)


def _distinct(tasks: Iterable[EpisodeTask], keyof: Callable[[EpisodeTask], Any], reps: dict[Any, str],
              keys: set[Any] | None = None) -> int:
    """How many of ``tasks`` will run: those without a key, and one per key not in ``reps`` nor ``keys`` (the keys
    counted are added to ``keys``)."""
    keys = set(reps) if keys is None else keys
    n = 0
    for t in tasks:
        k = keyof(t)
        if k is None or k not in keys:
            n += 1
            if k is not None:
                keys.add(k)
    return n


def _next(pending: deque[EpisodeTask], alike: Alike, flying: set[Any]) -> EpisodeTask:
    """The next episode to submit: one of a bundle and trial whose inputs are unknown with nothing of it in flight
    (it shows them), else one with known inputs, else the first."""
    pick = next((t for t in pending if not alike.known(t) and where(t) not in flying), None) or \
        next((t for t in pending if alike.known(t)), None) or pending[0]
    pending.remove(pick)
    return pick


class _Dispatch:
    """The state of one :func:`dispatch`."""

    def __init__(self, backend: Any, done: dict[str, dict[str, Any]], add: Callable[[dict[str, Any]], None],
                 follow: Callable[[EpisodeTask, dict[str, Any]], list[EpisodeTask]]) -> None:
        self.backend, self.done, self.add, self.follow = backend, done, add, follow
        self.alike, self.costs = Alike(), Costs()
        self.memo: dict[str, Any] = {}  # task key -> its alike key, once its inputs are known (they stay)
        self.pending: deque[EpisodeTask] = deque()
        self.reps: dict[Any, str] = {}  # alike key -> the task key of the episode that runs for it
        self.waiting: dict[str, list[EpisodeTask]] = {}  # that task key -> the episodes waiting for its figures
        self.alone: set[str] = set()  # episodes that run themselves
        self.shown: dict[str, dict[str, Any] | None] = {}  # finished task key -> its row if it saw its key's inputs
        self.flying: dict[Any, int] = {}  # where -> episodes in flight
        self.running: dict[str, EpisodeTask] = {}  # task key -> an episode in flight
        self.counts = {"run": 0, "shared": 0}
        self.finished = len(done)

    def keyof(self, t: EpisodeTask) -> Any:
        tk = task_key(t)
        if tk in self.alone or not self.alike.known(t):
            return None
        if tk not in self.memo:
            self.memo[tk] = self.alike.key(t)
        return self.memo[tk]

    def finish(self, task: EpisodeTask, row: dict[str, Any]) -> None:
        self.add(row)
        self.finished += 1
        self.pending.extend(t for t in self.follow(task, row) if task_key(t) not in self.done)

    def share(self, task: EpisodeTask, rep_row: dict[str, Any] | None) -> None:
        """Give ``task`` the figures of its key's episode, or run it itself where that one did not see the inputs."""
        if rep_row is not None:
            self.counts["shared"] += 1
            self.finish(task, {**rep_row, **identity(task)})
        else:
            self.alone.add(task_key(task))
            self.pending.appendleft(task)

    def fill(self) -> None:
        """Submit until ``capacity`` episodes are in flight (or none is pending)."""
        while self.pending and sum(self.flying.values()) < self.backend.capacity:
            t = _next(self.pending, self.alike, set(self.flying))
            k = self.keyof(t)
            if k is not None and k in self.reps:
                rep = self.reps[k]
                if rep in self.shown:
                    self.share(t, self.shown[rep])
                else:  # in flight: wait for it
                    self.waiting.setdefault(rep, []).append(t)
                continue
            if k is not None:
                self.reps[k] = task_key(t)
            self.backend.submit(t)
            self.running[task_key(t)] = t
            self.flying[where(t)] = self.flying.get(where(t), 0) + 1

    def collect(self) -> None:
        """Take one finished episode: its row, its costs, its inputs, and the episodes that waited for it."""
        t, (row, seen, seconds, pid) = self.backend.next_done()
        del self.running[task_key(t)]
        self.flying[where(t)] -= 1
        if not self.flying[where(t)]:
            del self.flying[where(t)]
        self.counts["run"] += 1
        self.costs.add(t, seconds, pid)
        self.alike.learn(t, seen)
        self.finish(t, row)
        self.shown[task_key(t)] = row if self.alike.saw(t, seen) else None
        for f in self.waiting.pop(task_key(t), []):
            self.share(f, self.shown[task_key(t)])

    def left(self) -> int:
        """The distinct episodes left: the pending ones by key, those in flight, and the placebos the settings not
        yet finished call for, by the keys their expected schedules give (:meth:`Alike.schedule`)."""
        keys = set(self.reps)
        n = sum(self.flying.values()) + _distinct(self.pending, self.keyof, self.reps, keys)
        for s in [*self.pending, *self.running.values(), *(t for ts in self.waiting.values() for t in ts)]:
            expected = self.alike.schedule(s) if s.strategy in SETTING_STRATEGIES else None
            follows = self.follow(s, {**identity(s), "schedule": expected or {}})
            n += len(follows) if expected is None else _distinct(follows, self.alike.key, {}, keys)
        return n


def dispatch(backend: Any, tasks: Sequence[EpisodeTask], done: dict[str, dict[str, Any]],
             add: Callable[[dict[str, Any]], None], follow: Callable[[EpisodeTask, dict[str, Any]], list[EpisodeTask]],
             on_ready: Callable[[float, int, Costs], None] | None = None) -> dict[str, int]:
    """Run ``tasks`` and what ``follow`` adds (module docstring) on ``backend`` (``capacity``, ``workers``,
    ``submit(task)``, ``next_done()`` → (task, (row, seen, seconds, pid))), passing each row to ``add``; ``done``:
    the rows already there by task key (not run again). ``on_ready(seconds, distinct_left, costs)``: called once,
    when the costs are measured and every bundle and trial's inputs known, with the projected wall time of the
    distinct episodes left (:meth:`_Dispatch.left`). Returns the counts ``run`` and ``shared``."""
    d = _Dispatch(backend, done, add, follow)
    for t in tasks:
        if task_key(t) in done:
            d.pending.extend(x for x in follow(t, done[task_key(t)]) if task_key(x) not in done)
        else:
            d.pending.append(t)
    wheres, said = {where(t) for t in tasks}, on_ready is None
    while d.pending or d.flying:
        d.fill()
        if not said and d.costs.ready(backend.workers) and wheres <= set(d.alike.inputs):  # the workers busy
            said = True
            left = d.left()
            on_ready(d.costs.estimate(left, len(wheres), backend.workers), left, d.costs)
        if d.flying:
            d.collect()
    return d.counts
