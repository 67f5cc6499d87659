"""``mpcshare sim --serve``: the robot stand-in of ``mpcshare run``, in its own process, over ROS 2 topics.

The same episodes as ``mpcshare sim`` (the MuJoCo arm, the fork and shoulder of held-out trials, the
simulated wearer), but the controller is ``mpcshare run`` in another process: the closed-loop runner is
given a :class:`mpcshare.runtime.remote.RemoteController`, which publishes the arm's joint states, the
fork, the shoulder and the torso on the topics of ``--config`` (default ``examples/ros2/superlimb.toml``)
and follows the joint command that comes back, in the configuration's form (a ``JointTrajectory``, or a
``Float64MultiArray`` of positions, velocities or efforts: :mod:`mpcshare.runtime.stand_in_command`);
another arm is ``sim``'s ``--robot`` with a configuration naming its joints (``examples/ros2/panda.toml``).
By default it publishes ``/clock`` and steps in lockstep with ``mpcshare run --sim-time`` (reproducible);
``--realtime`` paces the physics with the wall clock for a ``run`` without ``--sim-time``. ``--drop
INPUT:START:END`` silences an input over a window of each episode, ``--restart INPUT:START:END`` deletes its
publisher at START and creates a new one at END. ``--live`` streams the steps to Foxglove on 127.0.0.1 and
records them in ``OUT/live.mcap`` (:mod:`mpcshare.runtime.live`). The run is the configuration's
``[controller]`` strategy; the run files and the comparison are those of ``mpcshare sim``.
"""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import Any, Callable

from mpcshare.commands.base import CommandError, positive_float
from mpcshare.control.types import DEFAULT_BETA

__all__ = ["DEFAULT_SERVE_CONFIG", "add_serve_arguments", "check_serve_arguments", "serve_controller"]

#: The configuration the stand-in serves by default (a source checkout's example).
DEFAULT_SERVE_CONFIG = Path(__file__).resolve().parents[2] / "examples" / "ros2" / "superlimb.toml"
_NOT_WITH_SERVE = ("video", "scenario", "no_keepout", "no_mpc_zones")


def add_serve_arguments(p: argparse.ArgumentParser) -> None:
    """The stand-in's options (module docstring)."""
    g = p.add_argument_group("robot stand-in for `mpcshare run` (ROS 2 topics)")
    g.add_argument("--serve", action="store_true",
                   help="be the arm for `mpcshare run` in another process: publish its inputs and follow its "
                        "commands over DDS (loopback by default) instead of running the controller here")
    g.add_argument("--config", default=None, metavar="ARM.toml",
                   help=f"with --serve: the topics, joints and network (default {DEFAULT_SERVE_CONFIG.name} of "
                        "examples/ros2)")
    g.add_argument("--realtime", action="store_true",
                   help="with --serve: pace the physics with the wall clock (for `run` without --sim-time) instead "
                        "of publishing /clock and stepping in lockstep")
    g.add_argument("--drop", action="append", default=[], metavar="INPUT:START:END",
                   help="with --serve: stop publishing INPUT (an [inputs] name: arm, fork, shoulder, ...) from START "
                        "to END seconds of each trial")
    g.add_argument("--restart", action="append", default=[], metavar="INPUT:START:END",
                   help="with --serve: delete INPUT's publisher at START and create a new one at END seconds")
    g.add_argument("--live", action="store_true",
                   help="with --serve: stream the episodes to Foxglove (ws://127.0.0.1:PORT; needs foxglove-sdk: pip "
                        "install 'mpcshare[live]') and record them in OUT/live.mcap")
    g.add_argument("--live-port", type=int, default=8765, metavar="PORT",
                   help="the live view's port on 127.0.0.1 (default 8765; 0: any free port)")
    g.add_argument("--serve-wait", type=positive_float, default=120.0, metavar="S",
                   help="with --serve: wait this long for `mpcshare run` to appear (default 120 s)")


def check_serve_arguments(args: argparse.Namespace) -> None:
    """CommandError for a stand-in option without ``--serve`` or a ``sim`` option the stand-in cannot honour."""
    if not args.serve:
        given = [f"--{n}" for n in ("config", "drop", "restart", "realtime", "live") if getattr(args, n)]
        if given:
            raise CommandError(f"{', '.join(given)} {'needs' if len(given) == 1 else 'need'} --serve")
        return
    bad = [f"--{n.replace('_', '-')}" for n in _NOT_WITH_SERVE if getattr(args, n, None)]
    if bad:
        raise CommandError(f"--serve runs the controller of `mpcshare run`: {', '.join(bad)} cannot apply to it")


def serve_controller(args: argparse.Namespace, bundle: Any) -> tuple[Callable[..., Any], Any, list[str]]:
    """(the controller factory for :func:`mpcshare.commands.sim.run_comparison`, the remote controller, the run
    names to simulate) once ``mpcshare run`` listens; CommandError naming what is wrong."""
    try:
        from mpcshare.runtime.transport import Transport
    except ImportError as exc:
        raise CommandError(f"--serve needs the cyclonedds package (pip install 'mpcshare[ros]'): {exc}") from None
    from mpcshare.run_table import ALL_RUNS
    from mpcshare.runtime.config import RunConfigError, load_run_config
    from mpcshare.runtime.remote import RemoteController, parse_outage

    path = args.config or DEFAULT_SERVE_CONFIG
    try:
        config = load_run_config(path)
        outages = [parse_outage(x) for x in args.drop] + [parse_outage(x, restart=True) for x in args.restart]
    except RunConfigError as exc:
        raise CommandError(str(exc)) from None
    except ValueError as exc:
        raise CommandError(f"--drop/--restart {exc}") from None
    c = config.controller
    run = next((r for r in ALL_RUNS if r.strategy == c.strategy and r.use_mpc == c.mpc and not r.oracle
                and r.schedule is None), None)
    if run is None:
        raise CommandError(f"{path}, [controller]: no simulated run has strategy {c.strategy!r} with mpc = {c.mpc}")
    if abs(args.beta - c.beta) > 1e-12 and args.beta != DEFAULT_BETA:
        raise CommandError(f"--beta {args.beta:g} differs from {path}'s [controller] beta {c.beta:g}")
    args.beta = c.beta
    try:
        transport = Transport(config.network)
        remote = RemoteController(config, transport, obs_names=list(bundle.obs_names),
                                  vol_names=list(bundle.vol_names), sim_time=not args.realtime, outages=outages)
    except RunConfigError as exc:
        raise CommandError(str(exc)) from None
    mode = "wall clock" if args.realtime else "sim time: /clock, run with --sim-time"
    print(f"mpcshare sim --serve: the arm of {path} ({mode}); waiting for `mpcshare run --config {path}`", flush=True)
    if not remote.wait_for_run(args.serve_wait):
        raise CommandError(f"no `mpcshare run` answered on {config.command.topic} within {args.serve_wait:g} s "
                           f"(domain {config.network.domain_id})")

    def make(_bundle: Any, **options: Any) -> Any:
        from robot.default_arm import as_description

        robot = options.get("robot") or as_description(None)
        try:
            remote.bind(robot)
        except RunConfigError as exc:
            raise CommandError(str(exc)) from None
        if args.live and remote.live is None and remote.live_error is None:
            from mpcshare.runtime.live import LiveView

            try:
                remote.live = LiveView(Path(args.out) / "live.mcap", robot, list(bundle.vol_names),
                                       port=args.live_port, name="mpcshare sim --serve")
            except RuntimeError as exc:
                raise CommandError(f"--live: {exc}") from None
            print(f"mpcshare sim --serve: live view on ws://127.0.0.1:{remote.live.port}, recorded in "
                  f"{Path(args.out) / 'live.mcap'}", flush=True)
        return remote

    return make, remote, [run.name]
