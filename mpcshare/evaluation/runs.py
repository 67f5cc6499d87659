"""Closed-loop comparison of arbitration strategies on held-out demonstrations.

Each *run* is a row of the run table :mod:`mpcshare.run_table` (every strategy of the registry
:data:`mpcshare.control.strategies.REGISTRY`: ``voluntary``, ``reactive``, the constant mixtures
``mix25``/``mix50``/``mix75``, ``gate``, ``paper_gate``, ``blend``; and ``gate_mpc``, the upper
bound ``oracle_preview``: ``reactive`` given the wearer's true intent as its preview, and the
replayed hand-over schedules ``random_handover``, the placebo: the gate's share and hand-overs
at random times, the mean over 5 draws, and ``oracle_handover``, the best closed-loop replay of
error-minimising schedules at several hand-over costs or of the pure runs: an upper bound never
worse than the better party); ``line_ratio`` (:mod:`mpcshare.line_ratio`) is added to every
run's metrics, pooled and per trial. Each is simulated on the
same held-out trials, with the same wearer (a :class:`sim.wearer.WearerConfig`, by
default the preset ``hemiparetic_mild``) and the same seed, by
:func:`sim.closed_loop.run_episode`. Per run the episode metrics of
:func:`sim.metrics.episode_metrics` are pooled over trials (:func:`mpcshare.evaluation.pooling.pool_metrics`) and
written to ``comparison.json`` (top-level ``strategies``: name → metrics; ``trials``;
``duration_s``; ``run_files``; ``wearer``: the preset's name, or None, and the
settings), ``comparison.md`` and ``comparison.png``.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Sequence

import numpy as np

from learning.data import Demonstrations
from mpcshare.channel_map import bundle_wearer
from mpcshare.control.types import DEFAULT_BETA
from mpcshare.evaluation.choice_check import choice_check
from mpcshare.evaluation.episode import _from_bundle, intent_preview, simulate_episode
from mpcshare.evaluation.episode_pool import EpisodeJob, EpisodePool
from mpcshare.evaluation.frontend_replay import simulate_cached
from mpcshare.evaluation.handover import (
    LINE_ORACLE_MAX_EFFORT,
    SCHEDULE_SOURCES,
    line_oracle_schedules,
    oracle_handover_schedules,
    random_handover_schedules,
)
from mpcshare.evaluation.pooling import pool_keepout_metrics, pool_metrics, pool_task_metrics
from mpcshare.line_ratio import add_line_ratios
from mpcshare.run_table import DEFAULT_RUNS, StrategyRun
from sim.closed_loop import run_episode
from sim.keepout_metrics import KEEPOUT_KEYS
from sim.run_mcap import fork_poses, write_run_mcap
from sim.scene import SceneConfig
from sim.task import EATING, Task
from sim.wearer import WearerConfig
from sim.wearer_presets import wearer_preset_name

if TYPE_CHECKING:  # annotations only: importing the bundle module pulls in torch
    from mpcshare.bundle import ModelBundle

__all__ = ["DEFAULT_RUNS", "METRIC_KEYS", "Comparison", "StrategyRun", "compare_strategies", "describe_wearer",
           "output_size", "pool_keepout_metrics", "pool_metrics", "pool_task_metrics", "render_clip",
           "intent_preview", "simulate_episode"]

METRIC_KEYS: tuple[str, ...] = ("tracking_rmse_m", "tracking_p95_m", "voluntary_effort", "reactive_share",
                                "handovers", "conflict_share", "limit_violations", "step_p50_ms",
                                "step_p99_ms", "realtime_factor")


@dataclass
class Comparison:
    """Pooled metrics per run, per-trial metrics and the run files written."""

    strategies: dict[str, dict[str, float]]
    per_trial: dict[str, dict[str, dict[str, float]]]
    trials: list[int]
    duration_s: float | None
    runs: list[dict[str, Any]]
    run_files: dict[str, list[str]] = field(default_factory=dict)
    video: str | None = None
    offline_wearer_share_by_mode: dict[str, float] | None = None  # the bundle's held-out voluntary share per mode
    wearer: dict[str, Any] | None = None  # {"preset": name or None, "settings": WearerConfig.to_dict()}
    scenario: str | None = None  # the conflict scenario (mpcshare.conflicts), None: the trials as they are
    keepout: bool = True  # whether the controllers kept the wearer's body zones out
    rule_check: dict[str, Any] | None = None  # the rule choice's prediction beside these figures (choice_check)

    def to_dict(self) -> dict[str, Any]:
        return {"strategies": self.strategies, "trials": self.trials, "duration_s": self.duration_s,
                "runs": self.runs, "per_trial": self.per_trial, "run_files": self.run_files, "video": self.video,
                "wearer": self.wearer, "offline_wearer_share_by_mode": self.offline_wearer_share_by_mode,
                "scenario": self.scenario, "keepout": self.keepout, "rule_check": self.rule_check}


def compare_strategies(bundle: ModelBundle, demos: Demonstrations, trial_ids: Sequence[int], *,
                       runs: Sequence[StrategyRun] = DEFAULT_RUNS, duration_s: float | None = None,
                       out: str | Path | None = None, seed: int = 0, beta: float = DEFAULT_BETA,
                       make_controller: Callable[..., Any] | None = None,
                       log: Callable[[str], None] | None = print,
                       mode_names: Sequence[str] | None = None, mcap: bool = False,
                       wearer: WearerConfig | None = None, scene: SceneConfig | None = None,
                       mcap_rate_hz: float | None = None, scenario: Any = None,
                       controller_options: dict[str, Any] | None = None,
                       pool: EpisodePool | None = None, task: Task = EATING) -> Comparison:
    """Simulate every run on every trial in ``trial_ids`` and pool the metrics.

    ``bundle``: a loaded :class:`mpcshare.bundle.ModelBundle`; ``demos``: raw data (the
    bundle's channels and rate) holding those trials; ``duration_s``: simulate only the
    first seconds of each trial (None: whole trials). With ``out``, each episode's run
    file is written to ``out/runs/<run>_trial<id>.npz`` (and, with ``mcap``, the same run as
    ``.mcap`` beside it: :func:`sim.run_mcap.write_run_mcap`). ``make_controller(bundle,
    strategy=..., use_mpc=..., beta=...)`` builds a controller (default:
    :meth:`SharedController.from_bundle`). ``mode_names``: the names of the data's mode labels;
    with them (and labels in the data) each run also gets the figures of ``task`` (default the eating task's:
    lag, sawing while ``cutting``, RMS per mode; :meth:`sim.task.Task.episode_metrics`). ``wearer``: the
    simulated wearer's settings (default ``WearerConfig()``, the preset ``hemiparetic_mild``);
    the comparison records them and the preset's name. ``scene``: the arm's world (:func:`simulate_episode`).
    ``mcap_rate_hz``: the MCAP's joint states at about this rate (default: every physics step).
    ``scenario``: a conflict scenario (:class:`mpcshare.conflicts.Scenario`) applied to every trial;
    ``controller_options``: added to every controller's options (e.g. ``config``). ``pool``: where the
    episodes run (:class:`mpcshare.evaluation.episode_pool.EpisodePool`; default: this process, one torch
    thread); the figures are the same whatever its number of workers.
    """
    make_controller = make_controller or _from_bundle
    extra = dict(controller_options or {})
    _check_request(demos, trial_ids, runs)
    settings = dict(beta=beta, duration_s=duration_s, seed=seed, wearer=wearer, mode_names=mode_names,
                    make_controller=make_controller, scene=scene, scenario=scenario, task=task)
    runner = _Runner(bundle, demos, pool or EpisodePool(demos), settings, extra, seed,
                     Path(out) if out is not None else None, mcap, mcap_rate_hz)
    tids = [int(t) for t in trial_ids]
    runner.run_all(runs, tids)
    pooled: dict[str, dict[str, float]] = {}
    per_trial: dict[str, dict[str, dict[str, float]]] = {}
    for run in runs:
        metrics, steps, seconds = [], [], []
        per_trial[run.name] = {}
        for tid in tids:
            trial_metrics, trial_steps, trial_seconds, wall = runner.trial(run, tid)
            metrics, steps, seconds = metrics + trial_metrics, steps + trial_steps, seconds + trial_seconds
            m = trial_metrics[0] if len(trial_metrics) == 1 else \
                {**pool_metrics(trial_metrics, trial_steps, trial_seconds),
                 **pool_task_metrics(trial_metrics, trial_steps, task), **pool_keepout_metrics(trial_metrics)}
            per_trial[run.name][str(tid)] = {k: m.get(k) for k in METRIC_KEYS + task.metric_keys + KEEPOUT_KEYS}
            if log is not None:
                log(f"  {run.name:12s} trial {tid}: tracking RMS {m['tracking_rmse_m'] * 1e3:.1f} mm, "
                    f"effort {m['voluntary_effort']:.3f}, reactive {m['reactive_share']:.0%}, "
                    f"violations {m['limit_violations']} ({wall:.0f} s)")
        pooled[run.name] = {**pool_metrics(metrics, steps, seconds), **pool_task_metrics(metrics, steps, task),
                            **pool_keepout_metrics(metrics)}
    add_line_ratios(pooled)
    for tid in (str(t) for t in tids):
        add_line_ratios({name: per_trial[name][tid] for name in per_trial})
    run_dicts = [asdict(r) for r in runs]
    options = getattr(extra.get("config"), "strategy_settings", None)  # given settings replace the rule's
    return Comparison(strategies=pooled, per_trial=per_trial, trials=tids,
                      duration_s=duration_s, runs=run_dicts, run_files=runner.files,
                      rule_check=None if options else choice_check(getattr(bundle, "rule", None), pooled, run_dicts),
                      wearer=describe_wearer(wearer),
                      offline_wearer_share_by_mode=_offline_share(bundle, mode_names),
                      scenario=getattr(scenario, "name", None),
                      keepout=getattr(extra.get("config"), "keepout", True) is not None)


def _check_request(demos: Demonstrations, trial_ids: Sequence[int], runs: Sequence[StrategyRun]) -> None:
    """ValueError unless every trial is in the data (and there is one) and the run names are unique."""
    known = set(demos.trial_ids)
    missing = [int(t) for t in trial_ids if int(t) not in known]
    if missing or not len(trial_ids):
        raise ValueError(f"trials {missing or list(trial_ids)} not in the data (it has {sorted(known)[:20]})")
    names = [r.name for r in runs]
    if len(set(names)) != len(names):
        raise ValueError(f"run names must be unique, got {names}")


class _Runner:
    """The episodes of :func:`compare_strategies` in two batches of ``pool`` (:meth:`run_all`): the runs
    without a schedule and the schedule sources, then the scheduled runs' draws built from the sources;
    each run file written under ``out/runs`` as its batch ends (``files``: run name → paths relative to
    ``out``); per (run, trial) the metrics, step times, simulated seconds and wall time kept."""

    def __init__(self, bundle: Any, demos: Demonstrations, pool: EpisodePool, settings: dict[str, Any],
                 extra: dict[str, Any], seed: int, out: Path | None, mcap: bool, mcap_rate_hz: float | None) -> None:
        self.bundle, self.demos, self.pool, self.settings = bundle, demos, pool, settings
        self.extra, self.seed = extra, seed
        self.out, self.mcap, self.mcap_rate_hz = out, mcap, mcap_rate_hz
        self.by_id = {tr.trial_id: tr for tr in demos.trials}
        self.runs_dir = out / "runs" if out is not None else None
        if self.runs_dir is not None:
            self.runs_dir.mkdir(parents=True, exist_ok=True)
        self.files: dict[str, list[str]] = {}
        self.cache: dict[tuple[str, int], tuple[Any, dict[str, Any]]] = {}  # episodes the scheduled runs use
        self.done: dict[tuple[str, int], list[tuple[Any, dict[str, Any]]]] = {}

    def _batch(self, wanted: list[tuple[StrategyRun, int, dict[str, Any]]], save: set[str]) -> None:
        """Simulate ``wanted`` (run, trial, options) in one batch; runs named in ``save`` get run files. Each
        process computes a trial's front end once and replays it (:func:`simulate_cached`: the same episodes)."""
        jobs = [EpisodeJob(tid, run, {**self.extra, **options}) for run, tid, options in wanted]
        results = [r[:2] for r in self.pool.map(simulate_cached, self.bundle, jobs, **self.settings)]
        counts: dict[tuple[str, int], int] = {}
        for run, tid, _ in wanted:
            counts[(run.name, tid)] = counts.get((run.name, tid), 0) + 1
        for (run, tid, _), (episode, m) in zip(wanted, results):
            if run.name in _SOURCES:
                self.cache[(run.name, tid)] = (episode, m)
            if run.name in save:
                done = self.done.setdefault((run.name, tid), [])
                best_only = run.schedule in _BEST_ONLY  # one kept replay: only it gets a run file (:meth:`trial`)
                if not best_only:
                    self._save(run, tid, len(done), counts[(run.name, tid)], episode)
                done.append((episode if run.name in _SOURCES or best_only else _Kept(episode), m))

    def run_all(self, runs: Sequence[StrategyRun], tids: Sequence[int]) -> None:
        """Every episode of ``runs`` on ``tids`` (class docstring)."""
        names = {r.name for r in runs}
        for run in runs:
            self.files[run.name] = []
        sources = [next(r for r in DEFAULT_RUNS if r.name == n) for n in sorted(_needed_sources(runs) - names)]
        plain = sorted((r for r in runs if r.schedule is None), key=lambda r: not r.use_mpc)  # the slowest first
        self._batch([(r, tid, {}) for r in plain + sources for tid in tids], names)
        self._batch([(r, tid, options) for r in runs if r.schedule is not None for tid in tids
                     for options in _draw_options(r, tid, self.seed, self.source)], names)

    def source(self, name: str, tid: int) -> tuple[Any, dict[str, Any]]:
        return self.cache[(name, tid)]

    def _save(self, run: StrategyRun, tid: int, j: int, n_draws: int, episode: Any) -> None:
        if self.runs_dir is None or self.out is None:
            return
        path = self.runs_dir / f"{run.name}_trial{tid}{f'_draw{j}' if n_draws > 1 else ''}.npz"
        episode.save(path)
        if self.mcap:
            fork = None if episode.fork_pose is not None else fork_poses(self.by_id[tid], self.demos.obs_names)
            write_run_mcap(episode, path.with_suffix(".mcap"), fork=fork,
                           joint_stride=_joint_stride(episode, self.mcap_rate_hz))
        self.files[run.name].append(str(path.relative_to(self.out)))

    def trial(self, run: StrategyRun, tid: int) -> tuple[list[dict[str, Any]], list[np.ndarray], list[float], float]:
        """``run`` on trial ``tid`` (every draw; ``oracle``: the best replay only): (metrics, step times [s],
        simulated seconds) per episode kept, and the wall time of its episodes [s]."""
        done = list(self.done[(run.name, tid)])
        wall = sum(float(e.info.get("wall_time_s", 0.0)) for e, _ in done)
        if run.schedule == "oracle":  # the best replay, the pure runs' own episodes included
            done.append(min(done + [self.source(n, tid) for n in SCHEDULE_SOURCES["oracle"]],
                            key=lambda em: em[1]["tracking_rmse_m"]))
            done = done[-1:]
        elif run.schedule == "oracle_line":  # the lowest line ratio within the effort cap, the pure runs included
            pure = [self.source(n, tid) for n in SCHEDULE_SOURCES["oracle_line"]]
            done = [best_on_line(done + pure, pure[0][1], pure[1][1])]
        if run.schedule in _BEST_ONLY:
            self._save(run, tid, 0, 1, done[0][0])
        steps = [np.asarray(e.step_time, dtype=float) for e, _ in done]
        seconds = [float(e.t[-1] - e.t[0]) + float(np.median(np.diff(e.t))) for e, _ in done]
        return [m for _, m in done], steps, seconds, wall


class _Kept:
    """What the pooling reads of an episode whose run file is written: its times, step times and info."""

    def __init__(self, episode: Any) -> None:
        self.t, self.step_time, self.info = episode.t, episode.step_time, episode.info


def _needed_sources(runs: Sequence[StrategyRun]) -> set[str]:
    """The runs whose episodes the scheduled runs among ``runs`` are built from."""
    return {n for r in runs if r.schedule is not None for n in SCHEDULE_SOURCES.get(r.schedule, ())}


def best_on_line(done: Sequence[tuple[Any, dict[str, Any]]], voluntary: dict[str, Any], reactive: dict[str, Any],
                 max_effort: float = LINE_ORACLE_MAX_EFFORT) -> tuple[Any, dict[str, Any]]:
    """Of the (episode, metrics) ``done`` (the replays and the pure runs' own episodes, at line ratio 1), the
    one with the lowest line ratio against the pure runs' metrics among those with effort <= ``max_effort`` ×
    voluntary (of all, when none is)."""
    from mpcshare.line_ratio import line_ratio

    v = (voluntary["voluntary_effort"], voluntary["tracking_rmse_m"])
    r = (reactive["voluntary_effort"], reactive["tracking_rmse_m"])
    rows = []
    for ep, m in done:
        lr = line_ratio(m["tracking_rmse_m"], m["voluntary_effort"], v, r)
        if lr is not None:
            rows.append((lr, m["voluntary_effort"] <= max_effort * v[0], (ep, m)))
    within = [row for row in rows if row[1]] or rows
    return min(within, key=lambda row: row[0])[2] if within else done[0]


def _joint_stride(episode: Any, rate_hz: float | None) -> int:
    """Every how many physics steps the MCAP keeps a joint state, for about ``rate_hz`` (None: all)."""
    if rate_hz is None or len(episode.t_physics) < 2:
        return 1
    physics_hz = 1.0 / float(np.median(np.diff(episode.t_physics)))
    return max(1, int(round(physics_hz / rate_hz)))


def output_size(runs: Sequence[StrategyRun], demos: Demonstrations, trial_ids: Sequence[int],
                duration_s: float | None, mcap: bool = False,
                mcap_rate_hz: float | None = None, scene: SceneConfig | None = None) -> tuple[float, float]:
    """(run files, MCAP files) [bytes] that :func:`compare_strategies` will write, about (measured sizes of
    :func:`sim.episode.run_file_bytes_estimate` and :func:`sim.run_mcap.mcap_bytes_estimate`); MCAP 0 without it.
    ``scene``: the arm's world (its joints and rates; default the SuperLimb's)."""
    from sim.episode import run_file_bytes_estimate
    from sim.run_mcap import mcap_bytes_estimate

    sc = scene or SceneConfig()
    physics_hz, control_hz = 1.0 / sc.timestep, 1.0 / sc.control_period
    n_joints = int(sc.robot.n)
    by_id = {tr.trial_id: tr for tr in demos.trials}
    seconds = sum(min(float(by_id[int(t)].t[-1] - by_id[int(t)].t[0]), duration_s or math.inf) for t in trial_ids)
    episodes = sum(r.draws for r in runs)
    npz = episodes * run_file_bytes_estimate(seconds, physics_hz, control_hz, n_joints)
    joint_hz = physics_hz if mcap_rate_hz is None else physics_hz / max(1, round(physics_hz / mcap_rate_hz))
    return npz, (episodes * mcap_bytes_estimate(seconds, control_hz, joint_hz) if mcap else 0.0)


_SOURCES = {name for names in SCHEDULE_SOURCES.values() for name in names}
_BEST_ONLY = ("oracle", "oracle_line")  # schedules whose best replay alone is kept


def _draw_options(run: StrategyRun, tid: int, seed: int,
                  source: Callable[[str, int], tuple[Any, Any]]) -> list[dict[str, Any]]:
    """The controller options of each episode of ``run`` on trial ``tid``: one empty dict, or one
    ``{"schedule": ...}`` per draw of a scheduled run (:mod:`mpcshare.evaluation.handover`)."""
    if run.schedule is None:
        return [{}]
    if run.schedule == "random":
        schedules = random_handover_schedules(source(SCHEDULE_SOURCES["random"][0], tid)[0], run.draws, [seed, tid])
    elif run.schedule == "oracle":
        schedules = oracle_handover_schedules(source("voluntary", tid)[0], source("reactive", tid)[0])
    elif run.schedule == "oracle_line":
        schedules = line_oracle_schedules(source("voluntary", tid)[0], source("reactive", tid)[0])
    else:
        raise ValueError(f"unknown schedule {run.schedule!r} of run {run.name!r}; valid choices: "
                         f"{', '.join(SCHEDULE_SOURCES)}")
    return [{"schedule": s} for s in schedules]


def _offline_share(bundle: Any, mode_names: Sequence[str] | None) -> dict[str, float] | None:
    """The bundle's held-out voluntary share per true mode label, by mode name (None if not recorded)."""
    by_label = (getattr(bundle, "metrics", None) or {}).get("voluntary_share_by_label")
    if not by_label:
        return None
    names = list(mode_names or [])
    return {names[int(k)] if int(k) < len(names) else k: float(v) for k, v in by_label.items()}


def describe_wearer(wearer: WearerConfig | None) -> dict[str, Any]:
    """``{"preset": name or None, "settings": {...}}`` of the wearer (None: ``WearerConfig()``)."""
    wc = wearer or WearerConfig()
    return {"preset": wearer_preset_name(wc), "settings": wc.to_dict()}


def render_clip(bundle: ModelBundle, demos: Demonstrations, trial_id: int, path: str | Path, *, seconds: float = 10.0,
                strategy: str = "gate", use_mpc: bool = False, seed: int = 0, beta: float = DEFAULT_BETA,
                make_controller: Callable[..., Any] | None = None, wearer: WearerConfig | None = None,
                scene: SceneConfig | None = None, scenario: Any = None,
                controller_options: dict[str, Any] | None = None,
                task: Task = EATING) -> tuple[str | None, str | None]:
    """Render the first ``seconds`` of ``strategy`` (with or without MPC) on one trial (offscreen OpenGL), in
    ``scene`` with ``task``'s body zones.

    Returns ``(video_path, message)``: the file written (an .mp4, or a .gif beside it
    when no MP4 encoder is installed) or None, and why not.
    """
    make_controller = make_controller or _from_bundle
    trial = next((tr for tr in demos.trials if tr.trial_id == int(trial_id)), None)
    if trial is None:
        raise ValueError(f"trial {trial_id} not in the data (it has {demos.trial_ids[:20]})")
    fork_truth = None
    if scenario is not None:  # the scenario's events fall in the clip: they are placed by its length
        st = scenario.apply(trial, seconds)
        trial, fork_truth = st.trial, st.fork_truth
        bundle = scenario.wrap_bundle(bundle, st, demos.act_names)
    robot = {} if scene is None else {"robot": scene.robot}
    wearer = bundle_wearer(bundle, wearer)
    controller = make_controller(bundle, strategy=strategy, use_mpc=use_mpc, beta=beta, **robot,
                                 **(controller_options or {}))
    with warnings.catch_warnings():  # the message is returned, for the caller to say once
        warnings.filterwarnings("ignore", message="no video", category=RuntimeWarning)
        episode = run_episode(controller, trial, scene=scene, duration_s=seconds, seed=seed, render=path,
                              record=False, wearer=wearer, obs_names=list(demos.obs_names),
                              act_names=list(demos.act_names), fork_truth=fork_truth, task=task)
    return episode.info.get("video"), episode.info.get("render_message")
