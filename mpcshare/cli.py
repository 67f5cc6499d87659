"""The ``mpcshare`` command line: the registry of subcommands, the parser and :func:`main`.

Console script ``mpcshare`` = :func:`main`; ``python -m mpcshare`` is the same.
Every subcommand is a :class:`~mpcshare.commands.base.Command` defined in its own
module and listed once in :data:`COMMANDS`; adding one is one line there.

Exit status: 0 success, 1 unusable input (a clear message on stderr), 2 usage error,
130 interrupted.
"""

from __future__ import annotations

import argparse
import sys
from typing import Sequence

from mpcshare.commands.analysis import ANALYZE_COMMAND
from mpcshare.commands.base import (
    Command,
    CommandError,
    load_or_fail,
    nonnegative_float,
    positive_float,
    positive_int,
    prepare_output_folder,
    remove_empty_output_folders,
)
from mpcshare.commands.data import GENERATE_COMMAND, INSPECT_COMMAND
from mpcshare.commands.demo import DEMO_COMMAND
from mpcshare.commands.ros_import import IMPORT_COMMAND
from mpcshare.commands.run import RUN_COMMAND
from mpcshare.commands.sim import SIM_COMMAND
from mpcshare.commands.train import TRAIN_COMMAND
from mpcshare.commands.tune import TUNE_COMMAND
from sim.offscreen_gl import prefer_offscreen_gl  # importing sim chooses offscreen GL, before any MuJoCo import

__all__ = ["COMMANDS", "Command", "CommandError", "build_parser", "main", "positive_int", "positive_float",
           "nonnegative_float", "prepare_output_folder", "load_or_fail"]

#: Every subcommand of ``mpcshare``, in the order ``mpcshare --help`` lists them.
COMMANDS: tuple[Command, ...] = (
    GENERATE_COMMAND,
    INSPECT_COMMAND,
    IMPORT_COMMAND,
    ANALYZE_COMMAND,
    TRAIN_COMMAND,
    SIM_COMMAND,
    TUNE_COMMAND,
    DEMO_COMMAND,
    RUN_COMMAND,
)


def build_parser(commands: Sequence[Command] = COMMANDS) -> argparse.ArgumentParser:
    """The argument parser with one sub-parser per command."""
    from mpcshare import __version__

    parser = argparse.ArgumentParser(
        prog="mpcshare",
        description="Shared control of a wearable robot arm, learnt from demonstrations. Commands: "
                    + ", ".join(c.name for c in commands) + ". Start with `mpcshare demo`.",
        epilog="`mpcshare COMMAND --help` shows a command's options and their defaults.")
    parser.add_argument("--version", action="version", version=f"mpcshare {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for c in commands:
        p = sub.add_parser(c.name, help=c.help, description=c.help)
        c.add_arguments(p)
        p.set_defaults(_run=c.run, _parser=p)
    return parser


def _merge(extra: Sequence[Command]) -> tuple[Command, ...]:
    """:data:`COMMANDS` plus ``extra``; an extra command replaces a registered one of the same name."""
    by_name = {c.name: c for c in extra}
    merged = [by_name.pop(c.name, c) for c in COMMANDS]
    return tuple(merged) + tuple(c for c in extra if c.name in by_name)


def main(argv: Sequence[str] | None = None, commands: Sequence[Command] = ()) -> int:
    """Parse ``argv`` (default: ``sys.argv[1:]``) and run the subcommand; return the exit status.

    ``commands`` are added to :data:`COMMANDS` (e.g. to test a command before it is
    registered); one with the name of a registered command replaces it.
    """
    parser = build_parser(_merge(commands))
    args, unknown = parser.parse_known_args(argv)
    if unknown:  # the subcommand's usage, not the top level's (exit status 2)
        args._parser.error(f"unrecognized arguments: {' '.join(unknown)}")
    prefer_offscreen_gl()
    remove_empty_output_folders(keep=True)  # forget any earlier command's folders (main called in-process)
    status = 1
    try:
        status = int(args._run(args))
    except CommandError as exc:
        print(f"mpcshare {args.command}: {exc}", file=sys.stderr)
        status = 1
    except KeyboardInterrupt:
        print(f"mpcshare {args.command}: interrupted", file=sys.stderr)
        status = 130
    finally:  # a failed command leaves no empty output folder behind
        remove_empty_output_folders(keep=status == 0)
    return status
