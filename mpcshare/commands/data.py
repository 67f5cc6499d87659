"""Data subcommands: ``inspect`` (summarise or reject a data set) and ``generate``
(synthetic demonstrations from :mod:`sim.demonstrator`, or with ``--world SEED`` a world of
the randomised family :mod:`sim.world_family`)."""

from __future__ import annotations

import argparse
import json
import time
from typing import Sequence

from learning.data import Demonstrations, save, saved_bytes_estimate
from mpcshare.channel_map import apply_map, parse_map, simulator_gaps, simulator_line
from mpcshare.commands.base import Command, CommandError, human_bytes, load_or_fail, positive_float, positive_int
from sim.demonstrator import DEFAULT_MINUTES, DEFAULT_SUBJECTS, GeneratorConfig, generate_demonstrations
from sim.task import EATING
from sim.world_family import world_demonstrations

__all__ = ["INSPECT_COMMAND", "GENERATE_COMMAND", "format_summary", "DATA_HELP"]

DATA_HELP = "an NPZ file or a CSV folder (format: docs/design.md, 'Data format')"


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
    p.add_argument("data", help=DATA_HELP)
    p.add_argument("--map", nargs="+", default=(), metavar="NAME=CHANNEL",
                   help="rename the data's CHANNEL to NAME first, as `train --map` and `sim --map` do")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")


def _inspect(args: argparse.Namespace) -> int:
    demos = load_or_fail(args.data)
    try:
        demos = apply_map(demos, parse_map(args.map))
    except ValueError as exc:
        raise CommandError(str(exc)) from None
    vol = demos.vol_names if demos.has_voluntary else []
    gaps = simulator_gaps(demos.obs_names, demos.act_names, vol, demos.rate_hz)
    if args.json:
        print(json.dumps({**demos.summary(), "simulator": {"can_drive": not gaps, "gaps": gaps}}, indent=2))
    else:
        print(f"{args.data}: usable (analysis and training)")
        print(format_summary(demos))
        print("simulator: " + simulator_line(demos.obs_names, demos.act_names, vol, demos.rate_hz))
    return 0


# ----------------------------------------------------------------- generate

def _generate_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--subjects", type=positive_int, default=DEFAULT_SUBJECTS,
                   help=f"number of subjects (default {DEFAULT_SUBJECTS})")
    p.add_argument("--minutes", type=positive_float, default=DEFAULT_MINUTES,
                   help=f"minutes per subject (default {DEFAULT_MINUTES:g})")
    p.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    p.add_argument("--rate", type=positive_float, default=100.0, help="sample rate [Hz] (default 100)")
    p.add_argument("--single-regime", action="store_true",
                   help="no mode structure: the knife is one smooth function of the fork")
    p.add_argument("--world", type=int, default=None, metavar="SEED",
                   help="a world of the randomised family (sim.world_family) instead of the project's generator: "
                        "its structure drawn from SEED; then --trials and --trial-seconds set the size")
    p.add_argument("--trials", type=positive_int, default=12, help="trials of a --world (default 12)")
    p.add_argument("--trial-seconds", type=positive_float, default=60.0,
                   help="seconds per trial of a --world (default 60)")
    p.add_argument("--out", required=True, help="output: FILE.npz, or a folder for CSV files")


def _generate(args: argparse.Namespace) -> int:
    t0 = time.perf_counter()
    names: Sequence[str] = EATING.mode_names  # the project's generator makes eating's demonstrations
    if args.world is not None:
        if args.single_regime:
            raise CommandError("--single-regime is a setting of the project's generator, not of a --world")
        demos, spec = world_demonstrations(args.world, args.trials, args.trial_seconds, args.rate)
        names = spec.mode_names
    else:
        config = GeneratorConfig(rate_hz=args.rate, single_regime=args.single_regime)
        demos = generate_demonstrations(args.subjects, args.minutes, seed=args.seed, config=config)
    print(f"writing about {human_bytes(saved_bytes_estimate(demos, args.out))} into {args.out} (fewer with "
          f"{'--trials or --trial-seconds' if args.world is not None else '--subjects or --minutes'})", flush=True)
    try:
        save(demos, args.out)
    except OSError as exc:  # e.g. --out names a folder that holds other files
        raise CommandError(f"cannot write {args.out}: {exc}") from exc
    print(f"wrote {args.out} ({time.perf_counter() - t0:.1f} s)")
    if args.world is not None:
        print(f"world {args.world}: modes {', '.join(f'{n} ({k})' for n, k in zip(names, spec.kinds))}; stroke "
              f"{spec.stroke_hz:.2f} Hz, {spec.stroke_amp_m * 1e3:.0f} mm; knife delay {spec.knife_delay_s:.2f} s")
    print(format_summary(demos, names))
    return 0


INSPECT_COMMAND = Command("inspect", "summarise a data set, or print the one error that makes it unusable",
                          _inspect_args, _inspect)
GENERATE_COMMAND = Command("generate", "write synthetic bimanual-eating demonstrations",
                           _generate_args, _generate)
