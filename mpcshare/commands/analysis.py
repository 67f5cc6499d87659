"""The ``analyze`` subcommand and the analysis options it shares with ``demo``.

``--task NAME`` (:mod:`mpcshare.commands.task_option`) names the data's mode labels in the report.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Sequence

from learning.analysis.config import AnalysisConfig
from learning.analysis.report import AnalysisReport
from learning.data import Demonstrations
from mpcshare.commands.base import (
    Command,
    CommandError,
    load_or_fail,
    nonnegative_float,
    positive_float,
    positive_int,
    prepare_output_folder,
)
from mpcshare.commands.data import DATA_HELP
from mpcshare.commands.task_option import add_task_argument, chosen_task

__all__ = ["ANALYZE_COMMAND", "add_analysis_arguments", "analysis_config", "run_analysis", "print_headline"]


def _listed(values) -> str:
    return " ".join(f"{v:g}" for v in values)


def add_analysis_arguments(p: argparse.ArgumentParser) -> None:
    """Options of the predictability analysis (shared by ``analyze`` and ``demo``); every default
    is :class:`~learning.analysis.AnalysisConfig`'s, written once there."""
    d = AnalysisConfig()
    g = p.add_argument_group("analysis")
    g.add_argument("--rate", type=positive_float, default=d.target_hz,
                   help=f"rate after downsampling [Hz] (default {d.target_hz:g})")
    g.add_argument("--window", type=nonnegative_float, default=d.window_s,
                   help=f"causal window [s] (default {d.window_s:g})")
    g.add_argument("--scope", choices=["sensor", "channel"], default=d.scope,
                   help="standardise per sensor to unit RMS magnitude (the paper) or per channel "
                        f"(default {d.scope})")
    g.add_argument("--modes", type=positive_int, default=d.n_modes,
                   help=f"number of HMM task modes (default {d.n_modes})")
    g.add_argument("-K", "--K", dest="K", type=positive_float, nargs="+", default=list(d.K),
                   help=f"thresholds K for the voluntary share (default {_listed(d.K)})")
    g.add_argument("--n-random", type=positive_int, default=d.n_random,
                   help=f"random segmentations to compare the HMM against (default {d.n_random})")
    g.add_argument("--search-windows", type=nonnegative_float, nargs="*", default=list(d.search_windows),
                   help="window lengths [s] for the search for missing information "
                        f"(default {_listed(d.search_windows)})")
    g.add_argument("--search-modes", type=positive_int, nargs="*", default=list(d.search_modes),
                   help=f"numbers of modes for the search (default {_listed(d.search_modes)})")
    g.add_argument("--no-search", action="store_true", help="skip the search for missing information")
    g.add_argument("--select-modes", action="store_true",
                   help="also choose the number of modes by held-out likelihood over trials (+BIC)")
    g.add_argument("--seed", type=int, default=d.seed, help=f"seed of everything random (default {d.seed})")


def analysis_config(args: argparse.Namespace) -> AnalysisConfig:
    """The :class:`learning.analysis.AnalysisConfig` of parsed arguments."""
    return AnalysisConfig(
        target_hz=args.rate, window_s=args.window, scope=args.scope, n_modes=args.modes,
        K=tuple(args.K), n_random=args.n_random,
        search_windows=() if args.no_search else tuple(args.search_windows),
        search_modes=() if args.no_search else tuple(args.search_modes),
        select_modes=args.select_modes, seed=args.seed)


def run_analysis(demos: Demonstrations, config: AnalysisConfig, out: Path,
                 mode_names: Sequence[str] | None = None, progress: bool = True) -> AnalysisReport:
    """Run the analysis with ``config`` (:func:`analysis_config` of the command line; progress output unless
    ``progress`` is False) and write report.json, report.md and plots into ``out``.

    Raises :class:`CommandError` when the data cannot be analysed with these
    settings (``learning.analysis.AnalysisError``: rate, trials shorter than the window).
    """
    from learning.analysis import AnalysisError, analyze
    from mpcshare.reports.analysis import write_analysis_report

    try:
        result = analyze(demos, config, progress=progress)
    except AnalysisError as exc:
        raise CommandError(f"cannot analyse the data: {exc}") from exc
    write_analysis_report(result, out, mode_names=mode_names,
                          channel_names=(list(demos.obs_names), list(demos.act_names)))
    return result.summary


def print_headline(report: AnalysisReport) -> None:
    """The few lines a person reads first: quotients, modes, the two tests."""
    from mpcshare.reports.analysis import fmt, fmt_p
    from mpcshare.reports.claims import claim_sentences, mixture_advice

    q = report.quotients
    print(f"quotients without modes: median {fmt(q.p50)}, p90 {fmt(q.p90)}, max {fmt(q.max)}")
    m = report.modes
    if m.agreement is not None:
        print(f"HMM modes: {m.n_modes}, agreement with labels {100 * m.agreement:.1f} %, ARI {m.ari:.3f}")
    t = report.segmentation_test
    print(f"median q over all windows: {t.hmm_median_q:.2f} within HMM modes, {t.reference_median_q:.2f} "
          f"within the {t.reference} reference, {t.random_median_q:.2f} within random groups")
    seg = t.to_dict()
    for line in claim_sentences(seg):
        print(line)
    advice = mixture_advice(seg)
    if advice:
        print(advice)
    for K, v in report.voluntary_share.items():
        print(f"voluntary share at K = {K}: {100 * v.without_modes:.1f} % without modes, "
              f"{100 * v.with_modes:.1f} % with modes, {100 * v.reference:.1f} % within the reference "
              f"(paired over trials {fmt_p(v.p_value)})")


def _analyze_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("data", help=DATA_HELP)
    p.add_argument("--out", required=True, help="output folder for report.json, report.md and plots")
    add_task_argument(p)
    add_analysis_arguments(p)


def _analyze(args: argparse.Namespace) -> int:
    out = prepare_output_folder(args.out)
    demos = load_or_fail(args.data)
    report = run_analysis(demos, analysis_config(args), out, mode_names=chosen_task(args).mode_names)
    print_headline(report)
    print(f"report: {out / 'report.md'}")
    return 0


ANALYZE_COMMAND = Command("analyze", "predictability analysis: Lipschitz quotients, HMM modes, report",
                          _analyze_args, _analyze)
