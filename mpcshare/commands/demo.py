"""The ``demo`` subcommand: the main job on the default data set, from data to closed loop.

1. generate the default demonstrations (3 subjects × 10 min, seed 0) → ``demos.npz``;
2. data summary and a plot of a trial;
3. the predictability analysis → ``analysis/`` (see ``mpcshare analyze``);
4. train the gates and the reactive predictor → the bundle ``model/`` (``mpcshare train``);
5. the K trade-off → ``sweep/`` (``mpcshare train --sweep``; ``--no-sweep`` skips it);
6. the closed-loop comparison of strategies in MuJoCo → ``sim/`` (``mpcshare sim``),
   with a short video of the gate when offscreen OpenGL works;

then one report: ``report.md``, ``report.html`` (self-contained) and ``report.json``.
"""

from __future__ import annotations

import argparse
import time
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import replace
from functools import partial
from pathlib import Path
from typing import Any, Callable

from learning.atomic import atomic_open, write_json
from learning.data import Demonstrations, save
from mpcshare.calibration.trials import STROKE_SEEN_S
from mpcshare.commands.analysis import add_analysis_arguments, analysis_config, print_headline, run_analysis
from mpcshare.commands.base import (
    Command,
    CommandError,
    human_bytes,
    percentile,
    positive_float,
    positive_int,
    prepare_output_folder,
)
from mpcshare.commands.data import format_summary
from mpcshare.commands.sim import add_wearer_argument, cutting_steps
from mpcshare.evaluation.episode_pool import MAX_DEFAULT_WORKERS, EpisodePool, default_workers
from mpcshare.training.config import RULE_DURATION_S, TrainConfig
from sim.demonstrator import DEFAULT_MINUTES, DEFAULT_SUBJECTS, GeneratorConfig, generate_demonstrations
from sim.task import EATING

__all__ = ["DEMO_COMMAND"]

_STAGES = 6
#: the task of the demonstrations stage 1 generates (sim.demonstrator's), so the demo's task
_TASK = EATING


def _demo_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", default="mpcshare-out", help="output folder (default ./mpcshare-out)")
    p.add_argument("--subjects", type=positive_int, default=DEFAULT_SUBJECTS,
                   help=f"subjects in the default data (default {DEFAULT_SUBJECTS})")
    p.add_argument("--minutes", type=positive_float, default=DEFAULT_MINUTES,
                   help=f"minutes per subject (default {DEFAULT_MINUTES:g})")
    p.add_argument("--data-seed", type=int, default=0, help="seed of the default data (default 0)")
    p.add_argument("--percentile", type=percentile, default=TrainConfig.percentile,
                   help=f"K at this percentile of the within-mode quotients (default {TrainConfig.percentile:g})")
    p.add_argument("--no-sweep", action="store_true", help="skip the K trade-off sweep")
    p.add_argument("--sim-trials", type=positive_int, default=2, help="held-out trials to simulate (default 2)")
    p.add_argument("--sim-duration", type=positive_float, default=30.0,
                   help="seconds simulated per trial and strategy (default 30)")
    p.add_argument("--no-video", action="store_true", help="do not render the video of the gate")
    p.add_argument("--rule-duration", type=positive_float, default=None,
                   help=f"seconds of each held-out trial the hand-over rule is chosen on (default: "
                        f"{RULE_DURATION_S:g} as `mpcshare train`, at most twice --sim-duration; up to twice that "
                        f"where a trial shows less than {STROKE_SEEN_S:g} s of the stroke in them)")
    p.add_argument("--workers", type=positive_int, default=default_workers(),
                   help="processes that run the closed-loop episodes of the rule choice and the comparison "
                        f"(default {default_workers()}: the CPU count, at most {MAX_DEFAULT_WORKERS}); the "
                        "figures are the same with any number")
    add_wearer_argument(p)
    add_analysis_arguments(p)


def training_config(args: argparse.Namespace) -> TrainConfig:
    """The demo trains with the analysis's choices (modes, window, rate, seed) and ``--percentile``."""
    return TrainConfig(percentile=args.percentile, n_modes=args.modes, window_s=args.window,
                       model_hz=args.rate, seed=args.seed)


def _stage(k: int, text: str) -> None:
    print(f"[{k}/{_STAGES}] {text}", flush=True)


def _summarise(demos: Demonstrations, out: Path) -> tuple[dict, str]:
    """Stage 2: ``data_summary.json``, ``data_summary.md`` and ``data_trial.png``; (summary, its Markdown)."""
    from mpcshare.reports.analysis import plot_demonstrations

    summary = demos.summary()
    summary["mode_names"] = list(_TASK.mode_names)
    write_json(summary, out / "data_summary.json", non_finite="raise")
    summary_md = ("# Demonstrations\n\n```\n" + format_summary(demos, _TASK.mode_names)
                  + "\n```\n\n![a trial](data_trial.png)\n")
    with atomic_open(out / "data_summary.md") as f:
        f.write(summary_md)
    plot_demonstrations(demos, out / "data_trial.png", mode_names=_TASK.mode_names)
    return summary, summary_md


def _fit(demos: Demonstrations, config: TrainConfig) -> Any:
    """Stage 4: the gates and the reactive predictor (:func:`mpcshare.training.train_bundle`)."""
    from mpcshare.training import TrainingError, train_bundle

    try:
        return train_bundle(demos, config, progress=True)
    except TrainingError as exc:
        raise CommandError(f"cannot train on the demonstrations: {exc}") from None


def _start_choice(bundle: Any, demos: Demonstrations, wearer_name: str, rule_duration_s: float,
                  pool: EpisodePool) -> Callable[[], None]:
    """The bundle's hand-over rule chosen in the closed loop as ``mpcshare train`` chooses it (on the last
    held-out trials, ``rule_duration_s`` each, beside the wearer ``wearer_name``; recorded as
    ``bundle.rule``) but without the constant mixtures as comparators (the comparison runs them on the
    evaluation trials; a sixth of the choice's episodes) and without the second stage (the robot's share 0.5
    while it leads, on the first stage's best two and the empty set: a quarter of its episodes; the robot at
    full share while it leads, as the first stage), its episodes in ``pool``: with workers, in a thread that
    waits for them while this process goes on (its lines printed at the end); else at once. Returns what ends it
    and prints it."""
    from mpcshare.calibration.rule_choice import ROBOT_ALPHAS, choose_for_bundle

    lines: list[str] = []
    choose = partial(choose_for_bundle, bundle, demos, duration_s=rule_duration_s, wearer_name=wearer_name,
                     mode_names=_TASK.mode_names, pool=pool, task=_TASK, mixes=(), robot_alphas=ROBOT_ALPHAS[:1])
    print("the demo's rule choice leaves out the constant mixtures beside its candidates and its second stage "
          f"(the robot's share {', '.join(f'{a:g}' for a in ROBOT_ALPHAS[1:])} while it leads): `mpcshare train` "
          "runs both; the closed loop below runs the mixtures on the evaluation trials", flush=True)
    if pool.workers > 1:
        print(f"choosing the hand-over rule in the closed loop on held-out trials ({pool.workers} workers, "
              "beside the training and the K sweep)", flush=True)
        thread = ThreadPoolExecutor(max_workers=1)
        future = thread.submit(choose, log=lines.append)
        thread.shutdown(wait=False)
    else:
        print("choosing the hand-over rule in the closed loop on held-out trials", flush=True)
        future = Future()
        try:
            future.set_result(choose(log=print))
        except ValueError as exc:
            future.set_exception(exc)

    def finish() -> None:
        try:
            choice = future.result()
        except ValueError as exc:
            print(f"hand-over rule: its defaults ({exc})")
            return
        if lines:
            print("the hand-over rule's candidates in the closed loop:")
            print("\n".join(lines))
        print(f"hand-over rule: the wearer leads modes {choice['wearer_modes']} ({choice['why']})")
    return finish


def _mixture(demos: Demonstrations, config: TrainConfig, analysis: Any) -> Any:
    """The gates trained on the time-free mixture's modes where the analysis advises them (else None): a
    :class:`mpcshare.training.GateFit` (the comparison needs no predictor)."""
    from mpcshare.reports.claims import mixture_advice
    from mpcshare.training import TrainingError, train_gates

    if not mixture_advice(analysis.segmentation_test.to_dict()):  # modes help, the temporal model adds nothing
        return None
    print("training the gates on the time-free mixture's modes too, to compare (--modes-from mixture)", flush=True)
    try:
        return train_gates(demos, replace(config, modes_from="mixture"))
    except TrainingError as exc:
        raise CommandError(f"cannot train on the mixture's modes: {exc}") from None


def _save(bundle: Any, mixture: Any, out: Path) -> tuple[Any, dict | None]:
    """The bundle in ``out/model``, read back as ``mpcshare sim --model`` would, and the comparison of the
    two mode sources where the mixture was trained (else None)."""
    from mpcshare.bundle import load_bundle, save_bundle
    from mpcshare.reports.mode_sources import mode_source_comparison, mode_source_sentence

    bundle.config["data_path"] = str((out / "demos.npz").resolve())
    bundle.config["task"] = _TASK.name
    save_bundle(bundle, out / "model")
    bundle = load_bundle(out / "model")
    if mixture is None:
        return bundle, None
    mode_sources = mode_source_comparison({"hmm": bundle, "mixture": mixture})
    print(mode_source_sentence(mode_sources))
    return bundle, mode_sources


def _run_sweep(_bundle: Any, demos: Demonstrations, config: TrainConfig, folder: Path,
               progress: bool) -> tuple[dict, float]:
    """The K sweep into ``folder`` (:func:`mpcshare.training.sweep.run_sweep`): its rows and conclusion, and its
    seconds; in any process (an :meth:`EpisodePool.call`, the bundle unused)."""
    from threadpoolctl import threadpool_limits

    from mpcshare.reports.sweep import trend_sentence, write_sweep
    from mpcshare.training.sweep import run_sweep

    t0 = time.perf_counter()
    with threadpool_limits(limits=1, user_api="blas"):  # the same figures in this process and in a worker
        result = run_sweep(demos, config, progress=progress)
        write_sweep(result, folder)
    return {"rows": result.rows, "conclusion": trend_sentence(result.rows)}, time.perf_counter() - t0


def _start_sweep(args: argparse.Namespace, demos: Demonstrations, config: TrainConfig, out: Path,
                 pool: EpisodePool) -> Callable[[], tuple[dict | None, float | None]]:
    """Stage 5: the trade-off between accuracy and effort as K moves, with workers in one of them beside the
    analysis and the training (it needs neither), else when its result is asked for. Returns what waits for it
    and prints it: (rows and conclusion, its seconds), or (None, None) with ``--no-sweep``."""
    if args.no_sweep:
        def skipped() -> tuple[None, None]:
            _stage(5, "K sweep skipped (--no-sweep)")
            return None, None
        return skipped
    folder = prepare_output_folder(out / "sweep")
    if pool.workers > 1:
        print("the K sweep (stage 5) runs in a worker process beside the analysis and the training", flush=True)
        future = pool.call(_run_sweep, None, config, folder, False)

    def finish() -> tuple[dict, float]:
        _stage(5, "the trade-off between accuracy and effort (K sweep)")
        sweep, seconds = future.result() if pool.workers > 1 else _run_sweep(None, demos, config, folder, True)
        print(sweep["conclusion"])
        return sweep, seconds
    return finish


def _closed_loop(args: argparse.Namespace, bundle: Any, demos: Demonstrations, out: Path, pool: EpisodePool) -> dict:
    """Stage 6: every run of the run table on the held-out trials (episodes in ``pool``), the video,
    ``sim/comparison.*``."""
    from mpcshare.calibration.trials import bundle_evaluation_trials
    from mpcshare.evaluation import DEFAULT_RUNS, compare_strategies, output_size, render_clip
    from mpcshare.reports.comparison import write_comparison
    from sim.wearer_presets import wearer_preset

    ids = bundle_evaluation_trials(bundle)[:args.sim_trials]  # those the choice did not see first
    _stage(6, f"closed loop in MuJoCo: {len(DEFAULT_RUNS)} strategies x {len(ids)} held-out trial(s) "
              f"x {args.sim_duration:g} s")
    sim_out = prepare_output_folder(out / "sim")
    npz_bytes, _ = output_size(DEFAULT_RUNS, demos, ids, args.sim_duration)
    print(f"writing about {human_bytes(npz_bytes)} of run files into {sim_out / 'runs'} "
          "(fewer with --sim-trials or --sim-duration)", flush=True)
    wearer = wearer_preset(args.wearer)
    # with workers the video renders beside the comparison's first episodes, else after them
    render = partial(pool.call, render_clip, bundle, ids[0], sim_out / "gate_trial.mp4", seconds=8.0,
                     seed=args.seed, wearer=wearer)
    clip = render() if pool.workers > 1 and not args.no_video else None
    comp = compare_strategies(bundle, demos, ids, duration_s=args.sim_duration, out=sim_out, seed=args.seed,
                              mode_names=_TASK.mode_names, wearer=wearer, pool=pool, task=_TASK)
    if not args.no_video:
        video, message = (clip or render()).result()
        comp.video = None if video is None else str(Path(video).relative_to(sim_out))
        print(f"video: {video}" if video else f"no video: {message}")
    return write_comparison(comp, sim_out, cutting=cutting_steps(demos, ids[0], _TASK), task=_TASK)


def _demo(args: argparse.Namespace) -> int:
    from mpcshare.reports.demo import write_demo_report

    out = prepare_output_folder(args.out)
    t_start = time.perf_counter()
    timings: dict[str, float] = {}

    def lap(name: str, t0: float) -> None:
        timings[name] = time.perf_counter() - t0

    t0 = time.perf_counter()
    _stage(1, f"generating {args.subjects} subjects x {args.minutes:g} min of demonstrations")
    demos = generate_demonstrations(args.subjects, args.minutes, seed=args.data_seed,
                                    config=GeneratorConfig(rate_hz=100.0))
    save(demos, out / "demos.npz")
    lap("generate", t0)

    t0 = time.perf_counter()
    _stage(2, "summarising and plotting the data")
    summary, summary_md = _summarise(demos, out)
    lap("data", t0)

    config = training_config(args)
    rule_s = args.rule_duration or min(RULE_DURATION_S, 2 * args.sim_duration)  # shorter in short demos
    # one pool for the K sweep, the rule choice and the comparison; with workers the sweep (it needs the options,
    # not the analysis) runs beside the analysis and the training, and the choice beside the mixture's gates
    with EpisodePool(demos, args.workers) as pool:
        finish_sweep = _start_sweep(args, demos, config, out, pool)

        # the analysis in this process (its search fits the modes' restarts on every core, joblib)
        t0 = time.perf_counter()
        _stage(3, "predictability analysis")
        analysis = run_analysis(demos, analysis_config(args), prepare_output_folder(out / "analysis"),
                                mode_names=_TASK.mode_names)
        print_headline(analysis)
        lap("analysis", t0)

        t0 = time.perf_counter()
        _stage(4, f"training gates and the reactive predictor (K at percentile {args.percentile:g})")
        bundle = _fit(demos, config)
        t_choice = time.perf_counter()
        finish_choice = _start_choice(bundle, demos, args.wearer, rule_s, pool)
        mixture = _mixture(demos, config, analysis)
        lap("training", t0)

        sweep, sweep_s = finish_sweep()
        if sweep_s is not None:
            timings["sweep" if pool.workers == 1 else "sweep (beside analysis and training)"] = sweep_s
        finish_choice()
        if pool.workers > 1:
            lap("rule choice (beside training)", t_choice)
        bundle, mode_sources = _save(bundle, mixture, out)

        t0 = time.perf_counter()
        comparison = _closed_loop(args, bundle, demos, out, pool)
        lap("closed loop", t0)

    timings["total"] = time.perf_counter() - t_start
    rule = {} if bundle.rule is None else {"rule_settings": dict(bundle.rule.settings),
                                           "rule_choice": bundle.rule.choice}
    missing = write_demo_report(out, data_summary_md=summary_md, analysis=analysis.to_dict(),
                                training={**bundle.metrics, **rule}, comparison=comparison, timings_s=timings,
                                data_summary=summary, sweep=sweep, mode_sources=mode_sources, task=_TASK)
    if missing:
        print(f"report.html: could not embed {missing}")
    from mpcshare.reports.headline import headline_lines, trials_words

    print("\nWhat the robot did:")
    heads = headline_lines(comparison["strategies"], markdown=False, rule_choice=rule.get("rule_choice"),
                           trials=trials_words(comparison["trials"], comparison["duration_s"]),
                           rule_check=comparison.get("rule_check"), task=_TASK)
    for line in heads or ["the closed loop was not run"]:
        print(f"  {line}")
    print(f"done in {timings['total']:.0f} s; the figures behind these lines: {out / 'report.html'} (or report.md)")
    return 0


DEMO_COMMAND = Command("demo", "the main job on the default data: generate, analyse, train, simulate, report",
                       _demo_args, _demo)
