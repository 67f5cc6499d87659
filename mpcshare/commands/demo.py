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
from dataclasses import replace
from pathlib import Path
from typing import Any

from learning.atomic import atomic_open, write_json
from learning.data import Demonstrations, save
from mpcshare.commands.analysis import add_analysis_arguments, print_headline, run_analysis
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
from mpcshare.training.config import RULE_DURATION_S, TrainConfig
from sim.demonstrator import DEFAULT_MINUTES, DEFAULT_SUBJECTS, MODE_NAMES, GeneratorConfig, generate_demonstrations

__all__ = ["DEMO_COMMAND"]

_STAGES = 6


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
    summary["mode_names"] = list(MODE_NAMES)
    write_json(summary, out / "data_summary.json", non_finite="raise")
    summary_md = ("# Demonstrations\n\n```\n" + format_summary(demos, MODE_NAMES)
                  + "\n```\n\n![a trial](data_trial.png)\n")
    with atomic_open(out / "data_summary.md") as f:
        f.write(summary_md)
    plot_demonstrations(demos, out / "data_trial.png", mode_names=MODE_NAMES)
    return summary, summary_md


def _train(demos: Demonstrations, config: TrainConfig, out: Path, analysis: Any, wearer_name: str,
           rule_duration_s: float) -> tuple[Any, dict | None]:
    """Stage 4: the bundle in ``out/model`` (read back as ``mpcshare sim --model`` would), its hand-over
    rule chosen in the closed loop as ``mpcshare train`` does (on the last held-out trials, ``rule_duration_s``
    each, beside the wearer ``wearer_name``), and, where the analysis advises the time-free mixture, the
    comparison of the two mode sources (else None)."""
    from mpcshare.bundle import load_bundle, save_bundle
    from mpcshare.reports.claims import mixture_advice
    from mpcshare.reports.mode_sources import mode_source_comparison, mode_source_sentence
    from mpcshare.training import TrainingError, train_bundle

    try:
        bundle = train_bundle(demos, config, progress=True)
    except TrainingError as exc:
        raise CommandError(f"cannot train on the demonstrations: {exc}") from None
    from mpcshare.training.rule_choice import choose_for_bundle

    print("choosing the hand-over rule in the closed loop on held-out trials", flush=True)
    try:
        choice = choose_for_bundle(bundle, demos, duration_s=rule_duration_s, wearer_name=wearer_name,
                                   mode_names=MODE_NAMES, log=print)
        print(f"hand-over rule: the wearer leads modes {choice['wearer_modes']} ({choice['why']})")
    except ValueError as exc:
        print(f"hand-over rule: its defaults ({exc})")
    bundle.config["data_path"] = str((out / "demos.npz").resolve())
    save_bundle(bundle, out / "model")
    bundle = load_bundle(out / "model")
    mode_sources = None
    if mixture_advice(analysis.segmentation_test.to_dict()):  # modes help, the temporal model adds nothing
        print("training on the time-free mixture's modes too, to compare (--modes-from mixture)", flush=True)
        try:
            mixture = train_bundle(demos, replace(config, modes_from="mixture"), progress=False)
        except TrainingError as exc:
            raise CommandError(f"cannot train on the mixture's modes: {exc}") from None
        mode_sources = mode_source_comparison({"hmm": bundle, "mixture": mixture})
        print(mode_source_sentence(mode_sources))
    return bundle, mode_sources


def _sweep(args: argparse.Namespace, demos: Demonstrations, config: TrainConfig, out: Path) -> dict | None:
    """Stage 5: the trade-off between accuracy and effort as K moves (None with ``--no-sweep``)."""
    if args.no_sweep:
        _stage(5, "K sweep skipped (--no-sweep)")
        return None
    from mpcshare.training.sweep import run_sweep

    _stage(5, "the trade-off between accuracy and effort (K sweep)")
    result = run_sweep(demos, config, out=prepare_output_folder(out / "sweep"), progress=True)
    print(result.conclusion)
    return {"rows": result.rows, "conclusion": result.conclusion}


def _closed_loop(args: argparse.Namespace, bundle: Any, demos: Demonstrations, out: Path) -> dict:
    """Stage 6: every run of the run table on the held-out trials, the video, ``sim/comparison.*``."""
    from mpcshare.experiments import DEFAULT_RUNS, compare_strategies, output_size, render_clip
    from mpcshare.reports.comparison import write_comparison
    from sim.wearer_presets import wearer_preset

    ids = bundle.heldout_trials[:args.sim_trials]
    _stage(6, f"closed loop in MuJoCo: {len(DEFAULT_RUNS)} strategies x {len(ids)} held-out trial(s) "
              f"x {args.sim_duration:g} s")
    sim_out = prepare_output_folder(out / "sim")
    npz_bytes, _ = output_size(DEFAULT_RUNS, demos, ids, args.sim_duration)
    print(f"writing about {human_bytes(npz_bytes)} of run files into {sim_out / 'runs'} "
          "(fewer with --sim-trials or --sim-duration)", flush=True)
    wearer = wearer_preset(args.wearer)
    comp = compare_strategies(bundle, demos, ids, duration_s=args.sim_duration, out=sim_out, seed=args.seed,
                              mode_names=MODE_NAMES, wearer=wearer)
    if not args.no_video:
        video, message = render_clip(bundle, demos, ids[0], sim_out / "gate_trial.mp4", seconds=8.0,
                                     seed=args.seed, wearer=wearer)
        comp.video = None if video is None else str(Path(video).relative_to(sim_out))
        print(f"video: {video}" if video else f"no video: {message}")
    return write_comparison(comp, sim_out, cutting=cutting_steps(demos, ids[0]))


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

    t0 = time.perf_counter()
    _stage(3, "predictability analysis")
    analysis = run_analysis(demos, args, prepare_output_folder(out / "analysis"), mode_names=MODE_NAMES)
    print_headline(analysis)
    lap("analysis", t0)

    t0 = time.perf_counter()
    _stage(4, f"training gates and the reactive predictor (K at percentile {args.percentile:g})")
    config = training_config(args)
    rule_s = min(RULE_DURATION_S, 2 * args.sim_duration)  # the choice as `mpcshare train`, shorter in short demos
    bundle, mode_sources = _train(demos, config, out, analysis, args.wearer, rule_s)
    lap("training", t0)

    t0 = time.perf_counter()
    sweep = _sweep(args, demos, config, out)
    if sweep is not None:
        lap("sweep", t0)

    t0 = time.perf_counter()
    comparison = _closed_loop(args, bundle, demos, out)
    lap("closed loop", t0)

    timings["total"] = time.perf_counter() - t_start
    missing = write_demo_report(out, data_summary_md=summary_md, analysis=analysis.to_dict(),
                                training=bundle.metrics, comparison=comparison, timings_s=timings,
                                data_summary=summary, sweep=sweep, mode_sources=mode_sources)
    if missing:
        print(f"report.html: could not embed {missing}")
    from mpcshare.reports.headline import headline_lines, trials_words

    print("\nWhat the robot did:")
    heads = headline_lines(comparison["strategies"], markdown=False, rule_choice=bundle.metrics.get("rule_choice"),
                           trials=trials_words(comparison["trials"], comparison["duration_s"]))
    for line in heads or ["the closed loop was not run"]:
        print(f"  {line}")
    print(f"done in {timings['total']:.0f} s; the figures behind these lines: {out / 'report.html'} (or report.md)")
    return 0


DEMO_COMMAND = Command("demo", "the main job on the default data: generate, analyse, train, simulate, report",
                       _demo_args, _demo)
