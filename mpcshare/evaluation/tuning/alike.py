"""Episodes of a sweep that decide alike run once: :class:`Alike`.

Two episodes of a sweep on the same bundle, trial, length, seed, wearer and mode names differ only in their
arbitration (the strategy, β, a placebo's schedule): the rest of the controller and the world do not read them
(:mod:`mpcshare.evaluation.distinct`). The arbitration's inputs on a trial are observation-only, the same in every
episode of that bundle and trial (:func:`mpcshare.evaluation.frontend_replay.decisions`), so once one episode has
shown them, each planned episode's α, β at every step follow without the closed loop
(:func:`~mpcshare.evaluation.distinct.decision_trace`). Episodes with the same key (:meth:`Alike.key`: the rest of
the episode and that trace) are the same episode; the sweep runs one and gives its figures to the others, once that
run is shown to have seen exactly the inputs the traces were computed from (:meth:`Alike.saw`), else the others
run too. Settings share only with settings, placebos with placebos (a setting's row carries its schedule).
"""

from __future__ import annotations

import hashlib
from typing import Any

import numpy as np

from mpcshare.evaluation.distinct import decision_trace
from mpcshare.evaluation.tuning.episodes import SETTING_STRATEGIES, EpisodeTask, bundle_of, episode_setup

__all__ = ["Alike", "where"]


def where(task: EpisodeTask) -> tuple[str, int, float | None]:
    """What the arbitration's observation-only inputs depend on: (bundle folder, trial, length [s])."""
    return task.bundle_dir, int(task.trial), task.duration_s


def _kind(task: EpisodeTask) -> str:
    if task.strategy in SETTING_STRATEGIES:
        return "setting"
    return "placebo" if task.strategy == "random_handover" else "party"


class Alike:
    """The inputs seen per :func:`where` and the key of each episode (module docstring)."""

    def __init__(self) -> None:
        self.inputs: dict[tuple[str, int, float | None], np.ndarray] = {}
        self.traces: dict[EpisodeTask, bytes | None] = {}  # once the inputs are known (they do not change)

    def learn(self, task: EpisodeTask, seen: np.ndarray | None) -> None:
        """Keep the inputs ``task``'s episode saw (the first ones known for its bundle and trial)."""
        if seen is not None:
            self.inputs.setdefault(where(task), np.asarray(seen, dtype=float))

    def known(self, task: EpisodeTask) -> bool:
        """Whether the inputs of ``task``'s bundle and trial are known."""
        return where(task) in self.inputs

    def trace(self, task: EpisodeTask) -> bytes | None:
        """The α, β the episode's arbitration gives at each step (:func:`decision_trace`, float64 pairs); None where
        the inputs are not known yet or the arbitration is not predictable (an MPC, a known preview, a strategy
        that reads the closed loop's commands)."""
        inputs = self.inputs.get(where(task))
        if inputs is None or task.strategy == "oracle_preview":
            return None
        if task not in self.traces:
            from mpcshare.control.controller import SharedController

            run, options, beta = episode_setup(task)
            self.traces[task] = None
            if not (run.use_mpc or run.oracle):
                controller = SharedController.from_bundle(bundle_of(task), strategy=run.strategy, beta=beta,
                                                          use_mpc=False, **options)
                self.traces[task] = decision_trace(controller.arbiter, inputs)
        return self.traces[task]

    def key(self, task: EpisodeTask) -> tuple[Any, ...] | None:
        """The episode's identity but for its arbitration, and the digest of its :meth:`trace`; None without one."""
        trace = self.trace(task)
        if trace is None:
            return None
        return (*where(task), task.seed, task.wearer, task.mode_names, task.task, _kind(task),
                hashlib.sha256(trace).hexdigest())

    def schedule(self, task: EpisodeTask) -> dict[str, Any] | None:
        """The :func:`~mpcshare.evaluation.handover.schedule_record` a setting's episode is expected to give, from
        its :meth:`trace` (the α the controller applies at each step but where the fork sensor goes stale); for an
        estimate of its placebos, never for their figures. None without a trace."""
        from types import SimpleNamespace

        from mpcshare.evaluation.handover import schedule_record

        trace = self.trace(task)
        if trace is None:
            return None
        alpha = np.frombuffer(trace, dtype=float).reshape(-1, 2)[:, 0]
        return schedule_record(SimpleNamespace(alpha=alpha, t=self.inputs[where(task)][:, 0]))

    def saw(self, task: EpisodeTask, seen: np.ndarray | None) -> bool:
        """Whether ``task``'s episode saw exactly the inputs the keys of its bundle and trial came from."""
        inputs = self.inputs.get(where(task))
        return seen is not None and inputs is not None and np.shape(seen) == inputs.shape and \
            np.asarray(seen, dtype=float).tobytes() == inputs.tobytes()
