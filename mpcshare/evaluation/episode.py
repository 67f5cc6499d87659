"""One closed-loop episode of a strategy on a held-out trial, with its metrics: :func:`simulate_episode`.

What :func:`mpcshare.evaluation.runs.compare_strategies`, the rule choice and ``tune`` run per episode:
the controller built from the bundle (:meth:`SharedController.from_bundle` by default), the trial
simulated by :func:`sim.closed_loop.run_episode`, and the metrics of :mod:`sim.metrics`,
the task's (:meth:`sim.task.Task.episode_metrics`) and :mod:`sim.keepout_metrics`.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any, Callable, Mapping, Sequence

import numpy as np
from threadpoolctl import threadpool_limits

from learning.data import Demonstrations
from mpcshare.channel_map import bundle_wearer
from mpcshare.run_table import StrategyRun
from sim.closed_loop import run_episode
from sim.keepout_metrics import episode_keepout_metrics
from sim.metrics import episode_metrics
from sim.scene import SceneConfig
from sim.task import EATING, Task
from sim.wearer import WearerConfig

if TYPE_CHECKING:  # annotations only: importing the bundle module pulls in torch
    from mpcshare.bundle import ModelBundle

__all__ = ["Seconds", "intent_preview", "simulate_episode", "trial_seconds"]

#: how much of each trial an episode simulates [s]: one figure for every trial, or one per trial id (a trial
#: missing from the mapping: whole); None: whole trials
Seconds = float | Mapping[int, float | None] | None


def trial_seconds(duration_s: Seconds, trial_id: int) -> float | None:
    """The seconds ``duration_s`` gives the trial ``trial_id`` (:data:`Seconds`; None: the whole trial)."""
    if isinstance(duration_s, Mapping):
        return duration_s.get(int(trial_id))
    return duration_s


def _from_bundle(bundle: ModelBundle, **options: Any) -> Any:
    """The default controller factory: :meth:`SharedController.from_bundle` (imported when first used)."""
    from mpcshare.control.controller import SharedController

    return SharedController.from_bundle(bundle, **options)


def intent_preview(trial: Any, act_names: Sequence[str], wearer: WearerConfig | None = None) -> Any:
    """The wearer's true intent as a known tip trajectory (the ``oracle_preview`` run's preview):
    the trial's knife tip smoothed as :class:`sim.wearer.SimulatedWearer` smooths its intent."""
    from mpcshare.control.forecast import KnownTrajectory
    from sim.closed_loop import TIP_CHANNELS
    from sim.wearer import smooth_intent

    names = list(act_names)
    missing = [c for c in TIP_CHANNELS if c not in names]
    if missing:
        raise ValueError(f"oracle_preview needs the knife tip channels {missing} in the act names {names}")
    rate = 1.0 / float(np.median(np.diff(trial.t)))
    cutoff = (wearer or WearerConfig()).intent_cutoff_hz
    positions, _ = smooth_intent(trial.act[:, [names.index(c) for c in TIP_CHANNELS]], rate, cutoff)
    return KnownTrajectory(positions, 1.0 / rate)


def simulate_episode(bundle: Any, demos: Demonstrations, trial: Any, run: StrategyRun, options: dict[str, Any],
                     *, beta: float, duration_s: Seconds, seed: int, wearer: WearerConfig | None,
                     mode_names: Sequence[str] | None,
                     make_controller: Callable[..., Any] | None = None,
                     scene: SceneConfig | None = None, scenario: Any = None, task: Task = EATING
                     ) -> tuple[Any, dict[str, Any]]:
    """One episode of ``run`` on ``trial`` (controller ``options`` added, e.g. a ``schedule``) and
    its metrics: :func:`sim.metrics.episode_metrics`, the figures of ``task`` (:meth:`sim.task.Task.episode_metrics`)
    and the keep-out figures of :mod:`sim.keepout_metrics`, over ``duration_s`` of the trial
    (:func:`trial_seconds`). ``scene``: the world and its arm (default
    ``SceneConfig()``, the SuperLimb), with ``task``'s body zones; the controller is given the scene's arm
    (``robot=``) and keeps out the body zones of its bundle's task.
    ``scenario``: a :class:`mpcshare.conflicts.Scenario` that transforms the trial (and the bundle's
    predictor) first."""
    make_controller = make_controller or _from_bundle
    duration_s = trial_seconds(duration_s, trial.trial_id)
    fork_truth = None
    if scenario is not None:
        st = scenario.apply(trial, duration_s)
        trial, fork_truth = st.trial, st.fork_truth
        bundle = scenario.wrap_bundle(bundle, st, demos.act_names)
    if run.oracle:
        options = {**options, "preview": intent_preview(trial, demos.act_names, wearer)}
    if scene is not None:
        options = {**options, "robot": scene.robot}
    wearer = bundle_wearer(bundle, wearer)
    controller = make_controller(bundle, strategy=run.strategy, use_mpc=run.use_mpc, beta=beta, **options)
    # one BLAS thread: faster for the controller's dense products than OpenBLAS's threads (docs/design.md)
    with threadpool_limits(limits=1, user_api="blas"):
        episode = run_episode(controller, trial, scene=scene, duration_s=duration_s, seed=seed, wearer=wearer,
                              obs_names=list(demos.obs_names), act_names=list(demos.act_names),
                              fork_truth=fork_truth, task=task)
    m = episode_metrics(episode)
    true_mode = trial.mode[:len(episode.t)] if trial.mode is not None else None
    m.update(task.episode_metrics(episode.tip, episode.tip_intent, float(np.median(np.diff(episode.t))),
                                  true_mode, tuple(mode_names) if mode_names else None, alpha=episode.alpha))
    m.update(episode_keepout_metrics(episode))
    return episode, m
