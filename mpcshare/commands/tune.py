"""The ``tune`` subcommand: the closed-loop sweep of K × β × strategy with paired seeds.

``mpcshare tune DATA --out DIR`` trains one bundle per percentile (the HMM and quotients
fitted once), simulates every setting and what its comparison needs (the parties ``voluntary`` and
``reactive``, ``random_handover`` matched to each setting, :data:`DEFAULT_DRAWS` draw per pair;
``oracle_preview`` only with ``--oracle-preview``) on held-out trials × seeds (defaults: ≥ 10 pairs, tests
Holm-corrected across settings) (:mod:`mpcshare.evaluation.tuning`), episodes that decide alike once, and writes
``tune.json``, ``tune.md`` and ``pareto.png``. It says first how many episodes it plans and, after its first
ones, about how long the rest will take. Episodes run in a local process pool (``--workers``, default the CPU count, at
most 2) or on Ray (``--backend ray``, the optional extra ``pip install -e .[ray]``); an interrupted sweep
started again with the same arguments resumes.
"""

from __future__ import annotations

import argparse
import math
import sys

from mpcshare.commands import base
from mpcshare.commands.base import Command, CommandError, load_or_fail, prepare_output_folder
from mpcshare.commands.data import DATA_HELP
from mpcshare.commands.sim import add_wearer_argument
from mpcshare.commands.task_option import add_task_argument, chosen_task
from mpcshare.evaluation.episode_pool import MAX_DEFAULT_WORKERS, default_workers
from mpcshare.run_table import RANDOM_DRAWS, TUNABLE

__all__ = ["TUNE_COMMAND"]

#: Defaults: up to 5 held-out trials x enough paired seeds for >= 10 pairs per setting (the default
#: data's 4 held-out trials x 3 seeds = 12), so that one-sided p < 0.01 is reachable after Holm's
#: correction across the 6 settings (exact Wilcoxon floor 0.5^10 ≈ 0.001); 2 percentiles x 1 β x
#: 3 strategies; per pair 1 + 2 x (1 + 3) = 9 episodes and 6 placebo draws.
DEFAULT_PERCENTILES = (100.0, 70.0)
DEFAULT_BETAS = (0.5,)
DEFAULT_TRIALS, MIN_PAIRS = 5, 10
#: Placebo draws per pair: the pairs (trial x seed) give the test its power; with one draw the setting's and the
#: placebo's episode are exchangeable under the null, so d is symmetric and the signed-rank test exact (the mean
#: of several draws is not: benchmarks/tune_null_rate.py), and 3 percentiles x 2 β x 3 strategies x 10 pairs at
#: 30 s plan 400 episodes, where 2 draws plan 580.
DEFAULT_DRAWS = 1


def default_trials_and_seeds(n_heldout: int, trials: int | None, seeds: int | None) -> tuple[int, int]:
    """(trials, seeds): ``trials`` or min(5, held-out trials); ``seeds`` or ⌈10 / trials⌉ (≥ 10 pairs)."""
    t = trials if trials is not None else max(1, min(DEFAULT_TRIALS, n_heldout))
    return t, seeds if seeds is not None else math.ceil(MIN_PAIRS / t)


def _percentile(text: str) -> float:
    """argparse type: a percentile in (0, 100]."""
    try:
        v = float(text)
    except ValueError:
        v = math.nan
    if not (0.0 < v <= 100.0):
        raise argparse.ArgumentTypeError(f"expected a number above 0 and at most 100, got {text!r}")
    return v


def _beta(text: str) -> float:
    """argparse type: β in [0, 1]."""
    try:
        v = float(text)
    except ValueError:
        v = math.nan
    if not (0.0 <= v <= 1.0):
        raise argparse.ArgumentTypeError(f"expected a number from 0 to 1, got {text!r}")
    return v


def _add_arguments(p: argparse.ArgumentParser) -> None:
    from mpcshare.training.config import TrainConfig

    p.add_argument("data", help=DATA_HELP)
    p.add_argument("--out", required=True, help="folder for tune.json, tune.md, pareto.png, the bundles and episodes")
    add_task_argument(p)
    p.add_argument("--percentiles", type=_percentile, nargs="+", default=list(DEFAULT_PERCENTILES),
                   help="K = these percentiles of the within-mode quotients, one bundle each (default "
                        f"{' '.join(f'{v:g}' for v in DEFAULT_PERCENTILES)})")
    p.add_argument("--betas", type=_beta, nargs="+", default=list(DEFAULT_BETAS),
                   help=f"β values (default {' '.join(f'{v:g}' for v in DEFAULT_BETAS)})")
    p.add_argument("--strategies", nargs="+", choices=TUNABLE, default=list(TUNABLE),
                   help=f"strategies swept (default {' '.join(TUNABLE)}: the registry's tunable ones); each gets a "
                        "matched random_handover")
    p.add_argument("--trials", type=base.positive_int, default=None,
                   help=f"held-out trials (default: all, at most {DEFAULT_TRIALS}; trials x seeds = the pairs of "
                        "each test)")
    p.add_argument("--duration", type=base.positive_float, default=30.0, help="seconds per trial (default 30)")
    p.add_argument("--seeds", type=base.positive_int, default=None,
                   help=f"paired seeds 0..N-1 (default: enough for >= {MIN_PAIRS} trial x seed pairs, so that "
                        "p < 0.01 is reachable after Holm's correction)")
    p.add_argument("--draws", type=base.positive_int, default=DEFAULT_DRAWS,
                   help=f"random_handover draws per pair, their mean is the placebo (default {DEFAULT_DRAWS}; "
                        f"the comparison's is {RANDOM_DRAWS})")
    p.add_argument("--oracle-preview", action="store_true",
                   help="also simulate the upper bound oracle_preview (the robot given the true intent)")
    p.add_argument("--workers", type=base.positive_int, default=default_workers(),
                   help=f"local worker processes (default {default_workers()}: the CPU count, at most "
                        f"{MAX_DEFAULT_WORKERS}); the rows are the same with any number")
    p.add_argument("--backend", choices=["local", "ray"], default="local",
                   help="local process pool, or a Ray cluster (optional extra: pip install -e .[ray])")
    p.add_argument("--address", default=None, help="Ray cluster address (default: start a local Ray)")
    p.add_argument("--epochs", type=base.positive_int, default=TrainConfig().max_epochs,
                   help=f"maximum LSTM epochs per bundle (default {TrainConfig().max_epochs})")
    add_wearer_argument(p)
    p.add_argument("--quiet", action="store_true", help="no progress bars")


def _usage_error(message: str) -> int:
    """Print ``message`` as a usage error and return exit status 2."""
    print(f"mpcshare tune: error: {message}", file=sys.stderr)
    return 2


def _run(args: argparse.Namespace) -> int:
    from learning.data import split_by_trial
    from mpcshare.evaluation.tuning.runner import RayMissing, run_tune
    from mpcshare.reports.tune import build_result, chance_sentences, recommendation_line, write_tune
    from mpcshare.training.config import TrainConfig

    if args.backend == "ray":
        try:
            import ray  # noqa: F401
        except ImportError:
            return _usage_error("--backend ray needs Ray: pip install -e .[ray] (or --backend local)")
    out = prepare_output_folder(args.out)
    demos = load_or_fail(args.data)  # a clear message before any training
    from mpcshare.channel_map import simulator_gaps

    if gaps := simulator_gaps(demos.obs_names, demos.act_names, demos.vol_names, demos.rate_hz):
        raise CommandError("the data cannot drive the simulator (tune reads the channels as named: rename them in "
                           "the data, e.g. the import mapping's [map]): " + "; ".join(gaps))
    config = TrainConfig(max_epochs=args.epochs)
    _, held = split_by_trial(demos, config.heldout_fraction, seed=config.seed)  # the split training makes
    n_trials, n_seeds = default_trials_and_seeds(len(held.trial_ids), args.trials, args.seeds)
    seeds = list(range(n_seeds))
    try:
        run = run_tune(args.data, out, percentiles=sorted(set(args.percentiles), reverse=True),
                       betas=sorted(set(args.betas)), strategies=list(dict.fromkeys(args.strategies)),
                       n_trials=n_trials, seeds=seeds, duration_s=args.duration, wearer=args.wearer,
                       config=config, backend=args.backend, workers=args.workers,
                       address=args.address, progress=not args.quiet, mode_names=chosen_task(args).mode_names,
                       draws=args.draws, oracle=args.oracle_preview, task=args.task)
    except RayMissing as exc:
        return _usage_error(str(exc))
    except ValueError as exc:
        if "--trials" in str(exc):
            return _usage_error(str(exc))
        raise CommandError(str(exc)) from None
    result = build_result(run["rows"], trials=run["trials"], seeds=seeds, duration_s=args.duration,
                          wearer=args.wearer, bundles=run["bundles"], draws=args.draws)
    write_tune(result, out)
    for line in chance_sentences(result):
        print(line)
    line = recommendation_line(result)
    if line:
        print(line)
    print(f"tune: {out / 'tune.md'}")
    return 0


TUNE_COMMAND = Command("tune", "sweep K x beta x strategy in the closed loop against matched random hand-overs",
                       _add_arguments, _run)
