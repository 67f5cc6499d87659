"""Console entry point ``mpcshare``: the core subcommands plus those that need ``sim``.

``generate`` writes synthetic demonstrations; ``demo`` runs the main job on the
embedded default data set (generate → data summary and plots → predictability
analysis and its report), all into one output folder.
"""

from __future__ import annotations

import argparse
import sys
import time
from typing import Sequence

from learning.atomic import atomic_open
from learning.data import save
from mpcshare.cli import (Command, CommandError, add_analysis_arguments, format_summary, main as core_main,
                          positive_float, positive_int, prepare_output_folder, print_headline,
                          run_analysis)
from sim.demonstrator import MODE_NAMES, GeneratorConfig, generate_demonstrations

__all__ = ["main", "SIM_COMMANDS"]


def _generate_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--subjects", type=positive_int, default=3, help="number of subjects (default 3)")
    p.add_argument("--minutes", type=positive_float, default=10.0, help="minutes per subject (default 10)")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--rate", type=positive_float, default=100.0, help="sample rate [Hz] (default 100)")
    p.add_argument("--single-regime", action="store_true",
                   help="no mode structure: the knife is one smooth function of the fork")
    p.add_argument("--out", required=True, help="output: FILE.npz, or a folder for CSV files")


def _generate(args: argparse.Namespace) -> int:
    config = GeneratorConfig(rate_hz=args.rate, single_regime=args.single_regime)
    t0 = time.perf_counter()
    demos = generate_demonstrations(args.subjects, args.minutes, seed=args.seed, config=config)
    try:
        save(demos, args.out)
    except OSError as exc:  # e.g. --out names a folder that holds other files
        raise CommandError(f"cannot write {args.out}: {exc}") from exc
    print(f"wrote {args.out} ({time.perf_counter() - t0:.1f} s)")
    print(format_summary(demos, MODE_NAMES))
    return 0


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


SIM_COMMANDS: tuple[Command, ...] = (
    Command("generate", "write synthetic bimanual-eating demonstrations", _generate_args, _generate),
    Command("demo", "the main job on the default data: generate, summarise, analyse, report",
            _demo_args, _demo),
)


def main(argv: Sequence[str] | None = None) -> int:
    """The ``mpcshare`` console script."""
    return core_main(argv, commands=SIM_COMMANDS)


if __name__ == "__main__":
    sys.exit(main())
