"""The ``import`` subcommand: ROS recordings (rosbag2 folders, ROS 1 ``.bag`` files) into a data set.

``mpcshare import BAG [BAG ...] --mapping MAP.toml --out DATA.npz`` reads each bag
(one bag = one trial), takes the channels the mapping names (TOML; format in
:mod:`learning.data.mapping`), resamples them onto one grid of ``--rate`` Hz over
the span where every mapped topic has data, validates the set and writes it
atomically (NPZ, or a CSV folder for an ``--out`` without ``.npz``). Bad input
(a missing topic, a field path the message type does not have, a non-numeric
field, no common span, a gap, an unreadable bag) is one line on stderr, exit
status 1, and no output file.
"""

from __future__ import annotations

import argparse
import time

from ..channel_map import simulator_line
from .base import Command, CommandError, positive_float
from .data import format_summary

__all__ = ["IMPORT_COMMAND"]


def _add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("bags", nargs="+", metavar="BAG",
                   help="a rosbag2 folder (MCAP or sqlite3 storage) or a ROS 1 .bag file; one bag = one trial")
    p.add_argument("--mapping", required=True, metavar="MAP.toml",
                   help="TOML file mapping channels to \"TOPIC FIELD.PATH\" in tables [obs], [act], [voluntary] "
                        "(example: examples/superlimb_mapping.toml)")
    p.add_argument("--out", required=True, help="output: DATA.npz (or a folder for CSV files)")
    p.add_argument("--rate", type=positive_float, default=100.0, help="sample rate of the data set [Hz] (default 100)")
    p.add_argument("--max-gap", type=positive_float, default=0.1,
                   help="longest interval without a message in a mapped topic [s] (default 0.1)")
    p.add_argument("--on-gap", choices=("error", "split"), default="error",
                   help="a longer gap is an error (default) or splits the trial there")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")


def _run(args: argparse.Namespace) -> int:
    from learning.data import DataFormatError, save
    from learning.data.mapping import load_mapping
    from learning.data.rosbag import import_bags

    t0 = time.perf_counter()
    try:
        mapping = load_mapping(args.mapping)
        result = import_bags(args.bags, mapping, rate_hz=args.rate, max_gap=args.max_gap, on_gap=args.on_gap,
                             progress=not args.no_progress)
    except DataFormatError as exc:
        raise CommandError(str(exc)) from None
    try:
        save(result.demos, args.out)
    except DataFormatError as exc:
        raise CommandError(f"cannot write {args.out}: {exc}") from None
    except OSError as exc:
        raise CommandError(f"cannot write {args.out}: {exc.strerror or exc}") from None
    split = {b: n for b, n in result.trials_per_bag.items() if n > 1}
    print(f"wrote {args.out}: {len(result.demos)} trial(s) from {len(args.bags)} bag(s), "
          f"{result.messages:,} messages in {result.seconds:.1f} s ({result.messages_per_second:,.0f} msg/s)"
          + (f"; split at gaps: {', '.join(f'{b} -> {n}' for b, n in split.items())}" if split else "")
          + f" ({time.perf_counter() - t0:.1f} s in all)")
    print(format_summary(result.demos))
    d = result.demos
    print("simulator: " + simulator_line(d.obs_names, d.act_names, d.vol_names if d.has_voluntary else [], d.rate_hz))
    return 0


IMPORT_COMMAND = Command("import", "read ROS bags (rosbag2 MCAP/sqlite3, ROS 1) into a data set through a "
                         "TOML channel mapping", _add_arguments, _run)
