"""``mpcshare train``: fit a model bundle, or run the K trade-off sweep.

- ``mpcshare train DATA --percentile 90 --out MODEL_DIR`` writes a bundle
  (:mod:`mpcshare.bundle`) and prints a summary of the held-out metrics;
- ``mpcshare train DATA --sweep --out DIR`` writes ``sweep.json``, ``sweep.md`` and
  ``sweep.png`` (:mod:`mpcshare.training.sweep`, :mod:`mpcshare.reports.sweep`).

``--task NAME`` (:mod:`mpcshare.commands.task_option`): the task the bundle is trained for, recorded in it
(``config["task"]``); the closed-loop choice judges by its criterion. ``--map NAME=CHANNEL`` renames the data's
channels first (:mod:`mpcshare.channel_map`: the knife tip, the fork, the shoulder), recorded in the bundle for
``mpcshare sim``. Data that cannot drive the simulator still gives a bundle: the closed-loop choice of the
hand-over rule is skipped, in one line saying why and which ``--map`` enables it.

Unusable data (too few or too short trials, no act channels, a rate that cannot be
downsampled to the model rate) gives one message and exit status 1; bad option values
exit with 2 (argparse). The output path is checked before any training starts.
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

from mpcshare.calibration.trials import STROKE_SEEN_S
from mpcshare.channel_map import apply_map, parse_map, simulator_gaps
from mpcshare.commands.base import (
    Command,
    CommandError,
    load_or_fail,
    nonnegative_float,
    percentile,
    positive_float,
    positive_int,
    prepare_output_folder,
)
from mpcshare.commands.data import DATA_HELP
from mpcshare.commands.task_option import add_task_argument, chosen_task
from mpcshare.evaluation.episode_pool import MAX_DEFAULT_WORKERS, default_workers
from mpcshare.training.config import DEFAULT_PERCENTILES, MODES_FROM, RULE_DURATION_S, TrainConfig
from sim.wearer_presets import DEFAULT_WEARER_PRESET, WEARER_PRESETS

__all__ = ["TRAIN_COMMAND"]


def _fraction(text: str) -> float:
    value = positive_float(text)
    if value >= 1:
        raise argparse.ArgumentTypeError(f"expected a fraction in (0, 1), got {text!r}")
    return value


def _add_arguments(p: argparse.ArgumentParser) -> None:
    d = TrainConfig()
    p.add_argument("data", help=DATA_HELP)
    p.add_argument("--out", required=True,
                   help="bundle folder (absent, empty or an older bundle); with --sweep the folder "
                        "for sweep.json, sweep.md, sweep.png")
    p.add_argument("--map", nargs="+", default=(), metavar="NAME=CHANNEL",
                   help="use the data's CHANNEL as the channel NAME, e.g. knife_x=u4 (roles: docs/design.md, "
                        "'Data format'); recorded in the bundle for `mpcshare sim`")
    add_task_argument(p)
    p.add_argument("--percentile", type=percentile, default=d.percentile,
                   help=f"K = this percentile of the within-mode quotients (default {d.percentile:g})")
    p.add_argument("--sweep", action="store_true",
                   help="the trade-off sweep over --percentiles instead of one bundle")
    p.add_argument("--percentiles", type=percentile, nargs="+", default=list(DEFAULT_PERCENTILES),
                   help=f"percentiles of the sweep (default {' '.join(f'{x:g}' for x in DEFAULT_PERCENTILES)})")
    g = p.add_argument_group("training")
    g.add_argument("--modes", type=positive_int, default=d.n_modes, help=f"HMM task modes (default {d.n_modes})")
    g.add_argument("--modes-from", choices=MODES_FROM, default=d.modes_from,
                   help=f"hmm: the HMM task modes; mixture: the time-free Gaussian mixture of the same "
                        f"observations (where the analysis finds that modes help but the temporal model "
                        f"adds nothing) (default {d.modes_from})")
    g.add_argument("--window", type=nonnegative_float, default=d.window_s,
                   help=f"causal window [s] (default {d.window_s:g})")
    g.add_argument("--rate", type=positive_float, default=d.model_hz, help=f"model rate [Hz] (default {d.model_hz:g})")
    g.add_argument("--heldout", type=_fraction, default=d.heldout_fraction,
                   help=f"share of trials held out for evaluation (default {d.heldout_fraction:g})")
    g.add_argument("--epochs", type=positive_int, default=d.max_epochs,
                   help=f"maximum LSTM epochs (default {d.max_epochs})")
    g.add_argument("--hmm-restarts", type=positive_int, default=d.hmm_restarts,
                   help=f"EM restarts (default {d.hmm_restarts})")
    g.add_argument("--baselines", action="store_true",
                   help="also train the LSTM on all points as a baseline (the sweep always does)")
    g.add_argument("--device", choices=["cpu", "cuda", "auto"], default=d.device,
                   help=f"torch device of the LSTM (default {d.device}; auto = CUDA when present)")
    g.add_argument("--forecast", type=nonnegative_float, default=d.forecast_s,
                   help=f"forecast horizon of the predictor [s] (default {d.forecast_s:g}; 0: the present only)")
    g.add_argument("--seed", type=int, default=d.seed, help=f"seed of everything random (default {d.seed})")
    r = p.add_argument_group("hand-over rule (the default gate's settings, chosen in the closed loop)")
    r.add_argument("--rule-trials", type=positive_int, default=None,
                   help="held-out trials the choice simulates, dealt round the subjects (default: half of them, 1 "
                        "to 2)")
    r.add_argument("--rule-duration", type=positive_float, default=RULE_DURATION_S,
                   help=f"seconds simulated per trial for the choice (default {RULE_DURATION_S:g}; up to twice that "
                        f"where a trial shows less than {STROKE_SEEN_S:g} s of the task's stroke in them)")
    r.add_argument("--rule-wearer", choices=list(WEARER_PRESETS), default=DEFAULT_WEARER_PRESET,
                   help=f"the simulated wearer of the choice (default {DEFAULT_WEARER_PRESET})")
    r.add_argument("--no-rule-choice", action="store_true",
                   help="keep the rule's default settings (no closed-loop choice)")
    r.add_argument("--workers", type=positive_int, default=default_workers(),
                   help=f"processes that run the choice's closed-loop episodes (default {default_workers()}: the "
                        f"CPU count, at most {MAX_DEFAULT_WORKERS}; 1: this process); the choice is the same with any")
    p.add_argument("--quiet", action="store_true", help="no progress bars")


def _config(args: argparse.Namespace) -> TrainConfig:
    return TrainConfig(percentile=args.percentile, model_hz=args.rate, window_s=args.window,
                       n_modes=args.modes, modes_from=args.modes_from, hmm_restarts=args.hmm_restarts,
                       heldout_fraction=args.heldout,
                       max_epochs=args.epochs, lstm_baseline=args.baselines, device=args.device,
                       forecast_s=args.forecast, seed=args.seed)


def _fmt(x) -> str:
    if x is None:
        return "–"
    return "inf" if isinstance(x, float) and math.isinf(x) else f"{x:#.3g}"


def print_metrics(metrics: dict) -> None:
    """A few lines on the held-out metrics of a bundle."""
    t = metrics["training"]
    pred = metrics["predictor"]
    print(f"K = {_fmt(t['K'])} (percentile {t['percentile']:g}); reactive share: training "
          f"{100 * t['reactive_share_train']:.1f} %, held-out {100 * metrics['heldout_reactive_share']:.1f} %")
    print(f"predictor RMSE (standardised): on R {_fmt(pred['rmse_reactive'])}, all {_fmt(pred['rmse_all'])}, "
          f"where the gate acts {_fmt(pred.get('rmse_gated'))}")
    for name, b in metrics["baselines"].items():
        print(f"  baseline {name}: on R {_fmt(b['rmse_reactive'])}, all {_fmt(b['rmse_all'])}")
    g = metrics["gate"]["overall"]
    print(f"gate: accuracy {_fmt(g['accuracy'])}, F1 {_fmt(g['f1'])}, Brier {_fmt(g['brier'])}; "
          f"voluntary share {100 * metrics['voluntary_share']:.1f} %, effort "
          f"{_fmt(metrics['voluntary_effort'])} {metrics['effort_units']}")
    consts = t["gates"]["constant_modes"]
    for mode, c in consts.items():
        print(f"  mode {mode}: constant gate {c['value']} ({c['reason']})")
    print(f"time: {t['total_s']:.1f} s")


def _run(args: argparse.Namespace) -> int:
    from mpcshare.bundle import BundleError, check_bundle_target
    from mpcshare.training import TrainingError

    if args.sweep:
        out = prepare_output_folder(args.out)
    else:
        try:
            prepare_output_folder(Path(args.out).absolute().parent)  # created here: removed if the command fails
            out = check_bundle_target(args.out)
        except BundleError as exc:
            raise CommandError(f"--out {exc}") from None
    demos = load_or_fail(args.data)
    try:
        config = _config(args)
        mapping = parse_map(args.map)
        demos = apply_map(demos, mapping)
    except ValueError as exc:
        raise CommandError(str(exc)) from None
    try:
        if args.sweep:
            from mpcshare.reports.sweep import trend_sentence, write_sweep
            from mpcshare.training.sweep import run_sweep
            result = run_sweep(demos, config, percentiles=args.percentiles, progress=not args.quiet)
            write_sweep(result, out)
            print(trend_sentence(result.rows))
            print(f"sweep: {out / 'sweep.md'}")
            return 0
        from mpcshare.training import train_bundle
        bundle = train_bundle(demos, config, progress=not args.quiet)  # stage 1: training (no simulator)
        bundle.config["data_path"] = str(Path(args.data).resolve())  # `mpcshare sim`'s default --data
        bundle.config["channel_map"] = mapping  # applied again by `mpcshare sim`
        bundle.config["task"] = args.task  # `mpcshare sim`'s task
    except TrainingError as exc:
        raise CommandError(f"cannot train on {args.data}: {exc}") from None
    choice = _calibrate(bundle, demos, args)  # stage 2: calibration, in the closed loop
    skipped = None if bundle.rule is None else bundle.rule.skipped
    from mpcshare.bundle import save_bundle
    try:
        save_bundle(bundle, out)
    except BundleError as exc:
        raise CommandError(f"cannot write the bundle: {exc}") from None
    from mpcshare.reports.rule_choice import rule_markdown, skipped_markdown
    from mpcshare.reports.training import write_training_md

    extra = rule_markdown(choice) if choice is not None else \
        skipped_markdown(skipped) if skipped else ""
    md = write_training_md(bundle.metrics, Path(out) / "training.md", extra=extra)
    print_metrics(bundle.metrics)
    if choice is not None:
        print(f"hand-over rule: the wearer leads modes {choice['wearer_modes']} ({choice['why']})")
    elif skipped:
        print(f"hand-over rule: the {skipped}")
    print(f"bundle: {out} (summary: {md})")
    return 0


def _calibrate(bundle, demos, args: argparse.Namespace) -> dict | None:
    """The gate's settings chosen in the closed loop (:mod:`mpcshare.calibration.rule_choice`), recorded in
    ``bundle.rule``, or None. Skipped with ``--no-rule-choice`` (no rule) and where the data cannot drive the
    simulator (then ``bundle.rule`` says why: :func:`~mpcshare.bundle.rule.skipped_rule`)."""
    if args.no_rule_choice:
        return None
    task = chosen_task(args)
    gaps = simulator_gaps(demos.obs_names, demos.act_names, demos.vol_names if demos.has_voluntary else (),
                          demos.rate_hz, task)
    if gaps:
        from mpcshare.bundle.rule import skipped_rule

        why = ("closed-loop choice was skipped (the gate keeps its default settings): the data cannot drive the "
               "simulator: " + "; ".join(gaps))
        bundle.rule = skipped_rule(why)
        return None
    from mpcshare.calibration.rule_choice import choose_for_bundle

    return choose_for_bundle(bundle, demos, n_trials=args.rule_trials, duration_s=args.rule_duration,
                             wearer_name=args.rule_wearer, mode_names=task.mode_names, task=task,
                             log=None if args.quiet else print, workers=args.workers)


TRAIN_COMMAND = Command("train", "train gates and the reactive predictor into a model bundle, "
                                 "or sweep the threshold K (--sweep)", _add_arguments, _run)
