"""The ``run`` subcommand: the shared controller on a real arm, over ROS 2 topics.

``mpcshare run --model MODEL --config ARM.toml [--duration S] [--sim-time]`` loads the bundle and the
configuration (:mod:`mpcshare.runtime.config`), checks them against each other, then runs
:class:`mpcshare.runtime.loop.RunLoop` at the model's rate until SIGINT or SIGTERM (or ``--duration``
seconds of the wall clock): a stop command is published, then the exit status is 0. ``--sim-time``
ticks on the ``/clock`` topic instead (``use_sim_time``; ``mpcshare sim --serve`` publishes it). ``--live
FILE.mcap`` streams every tick to Foxglove on 127.0.0.1 and records it (:mod:`mpcshare.runtime.live`). A bad
bundle or configuration is one line on stderr, exit status 1, and nothing is sent. Prints the arm's
caps (another arm than the SuperLimb), one line when it starts and one summary line at the end.
"""

from __future__ import annotations

import argparse
import json
import signal
import threading
from pathlib import Path

import numpy as np

from mpcshare.runtime.gc_policy import GC_POLICIES

from .base import Command, CommandError, positive_float

__all__ = ["RUN_COMMAND"]


def _add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--model", required=True, help="model bundle folder (from `mpcshare train`)")
    p.add_argument("--config", required=True, metavar="ARM.toml",
                   help="the arm's topics, joints, deadlines and network (examples/ros2/superlimb.toml, "
                        "examples/ros2/panda.toml)")
    p.add_argument("--duration", type=positive_float, default=None,
                   help="stop after this many seconds (default: run until SIGINT or SIGTERM)")
    p.add_argument("--sim-time", action="store_true",
                   help="tick on the /clock topic (rosgraph_msgs/Clock) instead of the wall clock, as a ROS 2 node "
                        "with use_sim_time: for `mpcshare sim --serve`")
    p.add_argument("--live", default=None, metavar="FILE.mcap",
                   help="stream the run to Foxglove (ws://127.0.0.1:PORT; needs foxglove-sdk: pip install "
                        "'mpcshare[live]') and record the same channels in FILE.mcap")
    p.add_argument("--live-port", type=int, default=8765, metavar="PORT",
                   help="the live view's port on 127.0.0.1 (default 8765; 0: any free port)")
    p.add_argument("--gc", choices=GC_POLICIES, default="managed",
                   help="the garbage collector while ticking: managed (default; setup's objects frozen, the young "
                        "generations collected in the ticks' slack) or python (Python's automatic collection)")
    p.add_argument("--timing", default=None, metavar="FILE.json",
                   help="write the ticks' timing at the end: periods, phases, garbage collections, and the cause "
                        "of each period longer than T + 2 ms")


def _run(args: argparse.Namespace) -> int:
    try:
        from mpcshare.runtime.transport import Transport
    except ImportError as exc:
        raise CommandError(f"needs the cyclonedds package (pip install 'mpcshare[ros]'): {exc}") from None
    from mpcshare.bundle import BundleError, load_bundle
    from mpcshare.runtime.config import RunConfigError, load_run_config
    from mpcshare.runtime.loop import RunLoop
    from mpcshare.runtime.setup import configured_arm, make_controller, rest_base_pose

    if args.timing is not None and not Path(args.timing).resolve().parent.is_dir():
        raise CommandError(f"--timing {args.timing}: no such folder")
    try:
        config = load_run_config(args.config)
        bundle = load_bundle(args.model)
        arm = configured_arm(config)
        controller = make_controller(config, bundle, arm)
    except (RunConfigError, BundleError) as exc:
        raise CommandError(str(exc)) from None
    if arm is not None:
        print(f"arm caps: {arm.summary}", flush=True)
    live = None
    if args.live is not None:
        from mpcshare.runtime.live import LiveView

        if not args.live.endswith(".mcap"):
            raise CommandError(f"--live {args.live}: the recording must be a .mcap file")
        try:
            live = LiveView(args.live, controller.robot,
                            list(bundle.vol_names), port=args.live_port, name=f"mpcshare run {config.name}")
        except RuntimeError as exc:
            raise CommandError(f"--live: {exc}") from None
        print(f"mpcshare run: live view on ws://127.0.0.1:{live.port}, recorded in {args.live}", flush=True)
    stop = threading.Event()
    previous = {s: signal.signal(s, lambda *_: stop.set()) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        transport = Transport(config.network)
        loop = RunLoop(config, controller, transport, obs_names=list(bundle.obs_names),
                       vol_names=list(bundle.vol_names), sim_time=args.sim_time, live=live,
                       rest_base_pose=rest_base_pose(), gc_policy=args.gc)
        net = "CYCLONEDDS_URI" if transport.user_config else \
            f"interface {config.network.interface}, peers {', '.join(config.network.peers)}"
        clock = "; ticks on /clock (sim time)" if args.sim_time else ""
        print(f"mpcshare run: {config.name} at {config.rate_hz:g} Hz, command on {config.command.topic} "
              f"({config.command.type}), status on {config.status_topic}; network: {net}{clock}", flush=True)
        summary = loop.run(args.duration, stop.is_set)
    finally:
        for s, h in previous.items():
            signal.signal(s, h)
        if live is not None:
            live.close()
    profile = {**loop.profile.report(), "gc_policy": loop.collector.report()}
    if args.timing is not None:
        try:
            with open(args.timing, "w") as f:
                json.dump(profile, f, indent=2)
        except OSError as exc:
            raise CommandError(f"--timing {args.timing}: cannot write ({exc.strerror or exc})") from None
    steps = np.array(summary.step_times) * 1e3
    timing = f"step median {np.median(steps):.2f} ms, p99 {np.percentile(steps, 99):.2f} ms" if steps.size else \
        "no step"
    print(f"mpcshare run: stopped after {summary.ticks} ticks ({summary.commands} commands, {summary.late_ticks} "
          f"late ticks skipped, {summary.resumes} resumes after a stop; {timing})"
          + (f"; protective stop: {summary.stop_reason}" if summary.stop_reason else ""), flush=True)
    if profile["causes"]:
        causes = ", ".join(f"{n} {c}" for c, n in sorted(profile["causes"].items(), key=lambda x: -x[1]))
        print(f"mpcshare run: {sum(profile['causes'].values())} periods over T + 2 ms ({causes}); max period "
              f"{profile['period_ms']['max']:.1f} ms", flush=True)
    if loop.live_error:
        print(f"mpcshare run: the live view stopped: {loop.live_error}", flush=True)
    return 0


RUN_COMMAND = Command("run", "the shared controller on a real arm over ROS 2 topics (DDS; needs cyclonedds)",
                      _add_arguments, _run)
