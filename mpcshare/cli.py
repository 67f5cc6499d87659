"""The ``mpcshare`` command line: core subcommands and the registry other layers extend.

``mpcshare`` itself provides the subcommands that need only ``learning`` (``inspect``,
``analyze``). The layer above it, ``sim``, adds the ones that need the simulator
(``generate``, ``demo``) through :func:`main`'s ``commands`` argument; the console
script is :func:`sim.cli.main`. This keeps the layering of DESIGN.md: ``mpcshare``
never imports ``sim``.

Exit status: 0 success, 1 unusable input (a clear message on stderr), 2 usage error.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

from learning.data import DataFormatError, Demonstrations, load

__all__ = ["Command", "CORE_COMMANDS", "main", "format_summary", "load_or_fail", "CommandError",
           "add_analysis_arguments", "run_analysis", "print_headline", "prepare_output_folder",
           "positive_int", "positive_float", "nonnegative_float"]


class CommandError(RuntimeError):
    """A subcommand cannot go on; the message is printed and the exit status is 1."""


# ------------------------------------------------------- argument types
# argparse turns an ArgumentTypeError into "argument --x: <message>" and exit status 2.

def _number(text: str, kind: type, ok, what: str):
    try:
        value = kind(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}") from None
    if (isinstance(value, float) and not math.isfinite(value)) or not ok(value):
        raise argparse.ArgumentTypeError(f"expected {what}, got {text!r}")
    return value


def positive_int(text: str) -> int:
    """argparse type: an integer ≥ 1."""
    return _number(text, int, lambda v: v >= 1, "an integer >= 1")


def positive_float(text: str) -> float:
    """argparse type: a finite number > 0."""
    return _number(text, float, lambda v: v > 0, "a number > 0")


def nonnegative_float(text: str) -> float:
    """argparse type: a finite number ≥ 0."""
    return _number(text, float, lambda v: v >= 0, "a number >= 0")


def prepare_output_folder(path: str | Path) -> Path:
    """Create the output folder (and parents) or raise :class:`CommandError` saying why.

    Checked before any long work starts, so that a typo in ``--out`` does not
    cost a whole analysis.
    """
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise CommandError(f"--out {out}: exists and is not a folder")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CommandError(f"--out {out}: cannot create the folder ({exc.strerror or exc})") from exc
    if not os.access(out, os.W_OK | os.X_OK):
        raise CommandError(f"--out {out}: folder is not writable")
    return out


@dataclass(frozen=True)
class Command:
    """A subcommand: its name, one-line help, how it adds its arguments, and what it runs."""

    name: str
    help: str
    add_arguments: Callable[[argparse.ArgumentParser], None]
    run: Callable[[argparse.Namespace], int]


def load_or_fail(path: str) -> Demonstrations:
    """Load a data set or raise :class:`CommandError` with the loader's clear message."""
    try:
        return load(path)
    except DataFormatError as exc:
        raise CommandError(f"cannot use {path}: {exc}") from exc
    except OSError as exc:
        raise CommandError(f"cannot read {path}: {exc}") from exc


def format_summary(demos: Demonstrations, mode_names: Sequence[str] | None = None) -> str:
    """Human-readable summary of a data set (trials, subjects, duration, rate, channels, modes)."""
    s = demos.summary()
    lines = [
        f"trials:    {s['n_trials']}",
        f"samples:   {s['n_samples']}",
        f"rate:      {s['rate_hz']:g} Hz",
        f"duration:  {s['duration_s'] / 60:.2f} min in all",
        f"subjects:  {len(s['subjects'])} ("
        + ", ".join(f"{k}: {v / 60:.1f} min" for k, v in s["duration_s_per_subject"].items()) + ")",
        f"obs ({len(s['obs_names'])}):  " + ", ".join(s["obs_names"]),
        f"act ({len(s['act_names'])}):  " + ", ".join(s["act_names"]),
        "voluntary: " + (", ".join(s["vol_names"]) if demos.has_voluntary else "none"),
    ]
    if s["mode_counts"] is None:
        lines.append("modes:     no labels")
    else:
        total = sum(s["mode_counts"].values())
        parts = []
        for k, c in s["mode_counts"].items():
            name = mode_names[k] if mode_names is not None and 0 <= k < len(mode_names) else str(k)
            parts.append(f"{name if k >= 0 else 'unknown'} {100 * c / total:.1f}%")
        lines.append("modes:     " + ", ".join(parts))
    return "\n".join(lines)


# ----------------------------------------------------------------- inspect

def _inspect_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("data", help="an NPZ file or a CSV folder (format: DESIGN.md)")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")


def _inspect(args: argparse.Namespace) -> int:
    demos = load_or_fail(args.data)
    if args.json:
        print(json.dumps(demos.summary(), indent=2))
    else:
        print(f"{args.data}: usable")
        print(format_summary(demos))
    return 0


# ----------------------------------------------------------------- analyze

def _analyze_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("data", help="an NPZ file or a CSV folder (format: DESIGN.md)")
    p.add_argument("--out", required=True, help="output folder for report.json, report.md and plots")
    add_analysis_arguments(p)


def add_analysis_arguments(p: argparse.ArgumentParser) -> None:
    """Options of the predictability analysis (shared by ``analyze`` and ``demo``)."""
    g = p.add_argument_group("analysis")
    g.add_argument("--rate", type=positive_float, default=10.0, help="rate after downsampling [Hz] (default 10)")
    g.add_argument("--window", type=nonnegative_float, default=1.0, help="causal window [s] (default 1)")
    g.add_argument("--scope", choices=["sensor", "channel"], default="sensor",
                   help="standardise per sensor to unit RMS magnitude (the paper) or per channel")
    g.add_argument("--modes", type=positive_int, default=4, help="number of HMM task modes (default 4)")
    g.add_argument("-K", "--K", dest="K", type=positive_float, nargs="+", default=[5.0, 10.0],
                   help="thresholds K for the voluntary share (default 5 10)")
    g.add_argument("--n-random", type=positive_int, default=20,
                   help="random segmentations to compare the HMM against (default 20)")
    g.add_argument("--search-windows", type=nonnegative_float, nargs="*", default=[0.5, 1.0, 2.0],
                   help="window lengths [s] for the search for missing information")
    g.add_argument("--search-modes", type=positive_int, nargs="*", default=[2, 3, 4, 5, 6],
                   help="numbers of modes for the search for missing information")
    g.add_argument("--no-search", action="store_true", help="skip the search for missing information")
    g.add_argument("--select-modes", action="store_true",
                   help="also choose the number of modes by held-out likelihood over trials (+BIC)")
    g.add_argument("--seed", type=int, default=0, help="seed of everything random (default 0)")


def analysis_config(args: argparse.Namespace):
    """The :class:`learning.analysis.AnalysisConfig` of parsed arguments."""
    from learning.analysis import AnalysisConfig

    return AnalysisConfig(
        target_hz=args.rate, window_s=args.window, scope=args.scope, n_modes=args.modes,
        K=tuple(args.K), n_random=args.n_random,
        search_windows=() if args.no_search else tuple(args.search_windows),
        search_modes=() if args.no_search else tuple(args.search_modes),
        select_modes=args.select_modes, seed=args.seed)


def run_analysis(demos: Demonstrations, args: argparse.Namespace, out: Path,
                 mode_names: Sequence[str] | None = None) -> dict:
    """Run the analysis with progress output and write report.json, report.md and plots.

    Raises :class:`CommandError` when the data cannot be analysed with these
    settings (``learning.analysis.AnalysisError``: rate, trials shorter than the window).
    """
    from learning.analysis import AnalysisError, analyze
    from mpcshare.report import write_analysis_report

    try:
        result = analyze(demos, analysis_config(args), progress=True)
    except AnalysisError as exc:
        raise CommandError(f"cannot analyse the data: {exc}") from exc
    write_analysis_report(result, out, mode_names=mode_names)
    return result.report


def _analyze(args: argparse.Namespace) -> int:
    out = prepare_output_folder(args.out)
    demos = load_or_fail(args.data)
    report = run_analysis(demos, args, out)
    print_headline(report)
    print(f"report: {out / 'report.md'}")
    return 0


def print_headline(report: dict) -> None:
    q = report["quotients"]
    from mpcshare.report import fmt, fmt_p

    print(f"quotients without modes: median {fmt(q['p50'])}, p90 {fmt(q['p90'])}, max {fmt(q['max'])}")
    m = report["modes"]
    if m.get("agreement") is not None:
        print(f"HMM modes: {m['n_modes']}, agreement with labels {100 * m['agreement']:.1f} %, "
              f"ARI {m['ari']:.3f}")
    t = report["segmentation_test"]
    print(f"HMM vs random segmentation: median q {t['hmm_median_q']:.2f} vs {t['random_median_q']:.2f}, "
          f"{fmt_p(t['p_value'])}")
    for K, v in report["voluntary_share"].items():
        print(f"voluntary share at K = {K}: {100 * v['without_modes']:.1f} % without modes, "
              f"{100 * v['with_modes']:.1f} % with modes (paired {fmt_p(v['p_value'])})")


CORE_COMMANDS: tuple[Command, ...] = (
    Command("inspect", "summarise a data set, or print the one error that makes it unusable",
            _inspect_args, _inspect),
    Command("analyze", "predictability analysis: Lipschitz quotients, HMM modes, report",
            _analyze_args, _analyze),
)


def build_parser(commands: Sequence[Command]) -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mpcshare",
        description="Shared control from demonstrations: analyse, simulate, report.")
    from mpcshare import __version__

    parser.add_argument("--version", action="version", version=f"mpcshare {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for c in commands:
        p = sub.add_parser(c.name, help=c.help, description=c.help)
        c.add_arguments(p)
        p.set_defaults(_run=c.run)
    return parser


def main(argv: Sequence[str] | None = None, commands: Sequence[Command] = ()) -> int:
    """Parse ``argv`` and run the subcommand; ``commands`` extend :data:`CORE_COMMANDS`."""
    parser = build_parser(tuple(CORE_COMMANDS) + tuple(commands))
    args = parser.parse_args(argv)
    try:
        return int(args._run(args))
    except CommandError as exc:
        print(f"mpcshare {args.command}: {exc}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"mpcshare {args.command}: interrupted", file=sys.stderr)
        return 130
