"""The ``demo`` subcommand: the main job on the default data set, into one folder.

generate (3 subjects × 10 min by default) → data summary and a plot of a trial →
the predictability analysis with its report (see ``mpcshare analyze``).
"""

from __future__ import annotations

import argparse
import time

from learning.atomic import atomic_open
from learning.data import save
from sim.demonstrator import MODE_NAMES, GeneratorConfig, generate_demonstrations

from .analysis import add_analysis_arguments, print_headline, run_analysis
from .base import Command, positive_float, positive_int, prepare_output_folder
from .data import format_summary

__all__ = ["DEMO_COMMAND"]


def _demo_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--out", default="mpcshare-out", help="output folder (default ./mpcshare-out)")
    p.add_argument("--subjects", type=positive_int, default=3, help="subjects in the default data (default 3)")
    p.add_argument("--minutes", type=positive_float, default=10.0, help="minutes per subject (default 10)")
    p.add_argument("--data-seed", type=int, default=0, help="seed of the default data (default 0)")
    add_analysis_arguments(p)


def _demo(args: argparse.Namespace) -> int:
    from mpcshare.report import plot_demonstrations, write_json_atomic

    out = prepare_output_folder(args.out)
    t0 = time.perf_counter()
    print(f"[1/3] generating {args.subjects} subjects x {args.minutes:g} min of demonstrations")
    demos = generate_demonstrations(args.subjects, args.minutes, seed=args.data_seed,
                                    config=GeneratorConfig(rate_hz=100.0))
    save(demos, out / "demos.npz")
    summary = demos.summary()
    summary["mode_names"] = list(MODE_NAMES)
    write_json_atomic(summary, out / "data_summary.json")
    with atomic_open(out / "data_summary.md") as f:
        f.write("# Demonstrations\n\n```\n" + format_summary(demos, MODE_NAMES)
                + "\n```\n\n![a trial](data_trial.png)\n")
    print("[2/3] plotting the data")
    plot_demonstrations(demos, out / "data_trial.png", mode_names=MODE_NAMES)
    print("[3/3] predictability analysis")
    report = run_analysis(demos, args, out, mode_names=MODE_NAMES)
    print_headline(report)
    print(f"done in {time.perf_counter() - t0:.0f} s; open {out / 'report.md'}")
    return 0


DEMO_COMMAND = Command("demo", "the main job on the default data: generate, summarise, analyse, report",
                       _demo_args, _demo)
