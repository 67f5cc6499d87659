"""The ``tune`` subcommand: the closed-loop sweep of K × β × strategy with paired seeds.

``mpcshare tune DATA --out DIR`` trains one bundle per percentile (the HMM and quotients
fitted once), simulates every setting and the baselines (``voluntary``, ``reactive``,
``random_handover`` matched to each setting, ``oracle_preview``) on held-out trials × seeds
(:mod:`mpcshare.tuning`), and writes ``tune.json``, ``tune.md`` and ``pareto.png``. Episodes
run in a local process pool (``--workers``) or on Ray (``--backend ray``, the optional extra
``pip install -e .[ray]``); an interrupted sweep started again with the same arguments resumes.
"""

from __future__ import annotations

import argparse
import math
import sys

from mpcshare.commands import base
from mpcshare.commands.base import Command, CommandError, load_or_fail, prepare_output_folder
from mpcshare.commands.data import DATA_HELP
from mpcshare.commands.sim import add_wearer_argument
from sim.demonstrator import MODE_NAMES

__all__ = ["TUNE_COMMAND"]

_STRATEGIES = ("gate", "blend")


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
    p.add_argument("--percentiles", type=_percentile, nargs="+", default=[100.0, 90.0, 80.0, 70.0, 60.0, 50.0],
                   help="K = these percentiles of the within-mode quotients, one bundle each (default 100 .. 50)")
    p.add_argument("--betas", type=_beta, nargs="+", default=[0.0, 0.5, 1.0], help="β values (default 0 0.5 1)")
    p.add_argument("--strategies", nargs="+", choices=_STRATEGIES, default=list(_STRATEGIES),
                   help="strategies swept (default gate blend); each gets a matched random_handover")
    p.add_argument("--trials", type=base.positive_int, default=4, help="held-out trials (default 4)")
    p.add_argument("--duration", type=base.positive_float, default=30.0, help="seconds per trial (default 30)")
    p.add_argument("--seeds", type=base.positive_int, default=1, help="paired seeds 0..N-1 (default 1)")
    p.add_argument("--workers", type=base.positive_int, default=1, help="local worker processes (default 1)")
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
    from mpcshare.training.config import TrainConfig
    from mpcshare.tuning.report import build_result, chance_sentences, recommendation_line, write_tune
    from mpcshare.tuning.runner import RayMissing, run_tune

    if args.backend == "ray":
        try:
            import ray  # noqa: F401
        except ImportError:
            return _usage_error("--backend ray needs Ray: pip install -e .[ray] (or --backend local)")
    out = prepare_output_folder(args.out)
    load_or_fail(args.data)  # a clear message before any training
    seeds = list(range(args.seeds))
    try:
        run = run_tune(args.data, out, percentiles=sorted(set(args.percentiles), reverse=True),
                       betas=sorted(set(args.betas)), strategies=list(dict.fromkeys(args.strategies)),
                       n_trials=args.trials, seeds=seeds, duration_s=args.duration, wearer=args.wearer,
                       config=TrainConfig(max_epochs=args.epochs), backend=args.backend, workers=args.workers,
                       address=args.address, progress=not args.quiet, mode_names=MODE_NAMES)
    except RayMissing as exc:
        return _usage_error(str(exc))
    except ValueError as exc:
        if "--trials" in str(exc):
            return _usage_error(str(exc))
        raise CommandError(str(exc)) from None
    result = build_result(run["rows"], trials=run["trials"], seeds=seeds, duration_s=args.duration,
                          wearer=args.wearer, bundles=run["bundles"])
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
