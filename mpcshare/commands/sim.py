"""The ``sim`` subcommand: closed-loop comparison of strategies on held-out trials.

``mpcshare sim --model MODEL_DIR [--data DATA] --out DIR`` loads a bundle, takes the
held-out trials (of ``--data``, default: the data set the bundle was trained on,
as recorded by ``mpcshare train``), simulates each run of the run table
(:mod:`mpcshare.run_table`: every registered strategy, the gate with the MPC, the ``oracle_preview``
upper bound, the placebo ``random_handover`` and the upper bound ``oracle_handover``) on each
trial in MuJoCo
beside the simulated wearer, and writes ``comparison.json``, ``comparison.md``,
``comparison.png``, the run files (``runs/*.npz``; with ``--mcap`` also as ``runs/*.mcap``
for Foxglove) and, with ``--video``, a video of the gate on the first trial. ``--serve``: the controller is
``mpcshare run`` in another process, over ROS 2 topics (:mod:`mpcshare.commands.sim_serve`). ``--robot PRESET``
(or ``FILE --tip-frame NAME --mount X Y Z``) simulates another arm (:mod:`mpcshare.commands.robot_options`).
``--map NAME=CHANNEL`` renames the data's channels (:mod:`mpcshare.channel_map`; on top of the map the
bundle was trained with); data or a bundle that cannot drive the simulator is one line, exit status 1.
``--task NAME`` (:mod:`mpcshare.commands.task_option`): the task the bundle was trained for, by default; another
is refused in one line.
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any

from learning.data import Demonstrations
from mpcshare.channel_map import apply_map, bundle_map, parse_map, simulator_gaps
from mpcshare.commands.base import (
    Command,
    CommandError,
    human_bytes,
    load_or_fail,
    positive_float,
    positive_int,
    prepare_output_folder,
)
from mpcshare.commands.robot_options import add_robot_arguments, scene_from_args
from mpcshare.commands.sim_serve import add_serve_arguments, check_serve_arguments, serve_controller
from mpcshare.commands.task_option import add_task_argument, task_for_bundle
from mpcshare.conflicts import SCENARIOS
from mpcshare.control.types import DEFAULT_BETA
from mpcshare.run_table import ALL_RUNS, DEFAULT_RUNS, RUN_NAMES
from sim.task import EATING, Task
from sim.wearer_presets import DEFAULT_WEARER_PRESET, WEARER_PRESETS

if TYPE_CHECKING:  # annotations only: importing the bundle module pulls in torch
    from mpcshare.bundle import ModelBundle

__all__ = ["SIM_COMMAND", "align_channels", "add_sim_arguments", "add_wearer_argument", "announce_output_size",
           "cutting_steps", "run_comparison"]



def add_wearer_argument(p: argparse.ArgumentParser) -> None:
    """``--wearer PRESET``: the simulated wearer (``sim.wearer_presets``), shared by ``sim`` and ``demo``."""
    p.add_argument("--wearer", choices=list(WEARER_PRESETS), default=DEFAULT_WEARER_PRESET,
                   help=f"the simulated wearer's preset (default {DEFAULT_WEARER_PRESET}: a hemiparetic wearer "
                        f"commanding through the affected shoulder)")


def add_sim_arguments(p: argparse.ArgumentParser) -> None:
    """Options shared by ``sim`` and ``demo``."""
    p.add_argument("--trials", type=positive_int, default=None,
                   help="simulate at most this many held-out trials (default: all)")
    p.add_argument("--duration", type=positive_float, default=None,
                   help="simulate only the first DURATION seconds of each trial (default: whole trials)")
    default_names = [r.name for r in DEFAULT_RUNS]
    others = [n for n in RUN_NAMES if n not in default_names]
    p.add_argument("--runs", nargs="+", choices=RUN_NAMES, default=default_names, metavar="RUN",
                   help=f"strategies to simulate (default: {len(default_names)}: {', '.join(default_names)}"
                        f"{'; also ' + ', '.join(others) if others else ''}; the "
                        "strategies of the registry, gate_mpc, oracle_preview, random_handover: the gate's share and "
                        "hand-overs at random times, 5 draws, oracle_handover: the best replay of error-minimising "
                        "schedules, an upper bound)")
    p.add_argument("--beta", type=float, default=DEFAULT_BETA,
                   help=f"β while the robot acts (default {DEFAULT_BETA:g})")
    p.add_argument("--sim-seed", type=int, default=0, help="seed of the torso sway and the wearer (default 0)")
    p.add_argument("--video", action="store_true", help="render the gate on the first trial (offscreen OpenGL)")
    p.add_argument("--scenario", choices=SCENARIOS, default=None,
                   help="a conflict scenario applied to every trial (mpcshare.conflicts): push (a command into the "
                        "hand), sweep (the hand sweeps into the knife), face (an approach to the face), marker_lost "
                        "(the fork marker lost while the hand nears the knife), predictor_fault (the predictor "
                        "points into the hand)")
    p.add_argument("--no-keepout", action="store_true",
                   help="run without the keep-out of the wearer's body zones (for comparison only)")
    p.add_argument("--no-mpc-zones", action="store_true",
                   help="the MPC (gate_mpc) without the zones over its horizon: the QP's keep-out rows alone hold them")
    add_wearer_argument(p)


def _add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--model", required=True, help="model bundle folder (from `mpcshare train`)")
    p.add_argument("--data", default=None,
                   help="an NPZ file or CSV folder (default: the data the bundle was trained on)")
    p.add_argument("--map", nargs="+", default=(), metavar="NAME=CHANNEL",
                   help="use the data's CHANNEL as the bundle's channel NAME (e.g. fork_x=obs_3; roles: "
                        "docs/design.md, 'Data format'), on top of the map the bundle was trained with")
    p.add_argument("--out", required=True, help="output folder")
    p.add_argument("--mcap", action="store_true",
                   help="also write each run as runs/*.mcap (opens in Foxglove); its size is printed first")
    p.add_argument("--mcap-rate", type=positive_float, default=None, metavar="HZ",
                   help="with --mcap: the arm's joint states at about HZ (default: every physics step, 1000 Hz; "
                        "100 makes them about 3x smaller)")
    add_task_argument(p, default=None, default_words="the task the bundle was trained for")
    add_sim_arguments(p)
    add_robot_arguments(p)
    add_serve_arguments(p)


def align_channels(demos: Demonstrations, bundle: ModelBundle, mapping: dict[str, str] | None = None,
                   task: Task = EATING) -> Demonstrations:
    """The data's trials renamed by ``mapping`` (NAME → the data's CHANNEL, :mod:`mpcshare.channel_map`) with
    their obs columns in the bundle's order. Raises CommandError in one line where the map does not fit the
    data, where the bundle or the data cannot drive the simulator (saying which ``--map`` would; the shoulder
    roles ``task``'s), or where the data lacks an obs channel of the bundle."""
    try:
        demos = apply_map(demos, dict(mapping or {}))
    except ValueError as exc:
        raise CommandError(f"--map {exc}") from None
    gaps = simulator_gaps(bundle.obs_names, bundle.act_names, bundle.vol_names, task=task)
    if gaps:
        raise CommandError("the bundle's channels cannot drive the simulator (train it again with the --map "
                           "named here): " + "; ".join(gaps))
    gaps = simulator_gaps(demos.obs_names, demos.act_names, (), demos.rate_hz)
    if gaps:
        raise CommandError("the data cannot drive the simulator: " + "; ".join(gaps))
    missing = [n for n in bundle.obs_names if n not in demos.obs_names]
    if missing:
        raise CommandError(f"the data has no obs channel(s) {missing} that the bundle needs "
                           f"(data obs: {list(demos.obs_names)}); map them with --map NAME=CHANNEL")
    order = [demos.obs_names.index(n) for n in bundle.obs_names]
    trials = [type(tr)(obs=tr.obs[:, order], act=tr.act, t=tr.t, trial_id=tr.trial_id, subject=tr.subject,
                       mode=tr.mode, voluntary=tr.voluntary) for tr in demos.trials]
    return Demonstrations(trials, demos.rate_hz, list(bundle.obs_names), list(demos.act_names),
                          list(demos.vol_names))


def announce_output_size(runs: list[Any], demos: Demonstrations, trial_ids: list[int], args: argparse.Namespace,
                         out: Path, scene: Any = None) -> None:
    """Say how much the run files will take (``scene``: the arm's world, None: the SuperLimb's), after the
    options are checked and before anything is written, and how to make them smaller."""
    from mpcshare.evaluation import output_size

    mcap = getattr(args, "mcap", False)
    npz, mcap_bytes = output_size(runs, demos, trial_ids, args.duration, mcap, getattr(args, "mcap_rate", None),
                                  scene=scene)
    what = f"about {human_bytes(npz)} of run files (NPZ)"
    if mcap:
        what += f" and {human_bytes(mcap_bytes)} of MCAP"
    thin = "--trials, --duration or --runs" + (", --mcap-rate HZ" if mcap else "")
    print(f"writing {what} into {out / 'runs'} (fewer with {thin})", flush=True)


def cutting_steps(demos: Demonstrations, trial_id: int, task: Task = EATING) -> Any:
    """Where trial ``trial_id``'s demonstration is in ``task``'s stroke mode (eating's: cuts; bool per sample),
    or None without mode labels or a stroke mode."""
    trial = next(tr for tr in demos.trials if tr.trial_id == trial_id)
    if trial.mode is None or task.stroke_mode is None:
        return None
    return trial.mode == task.mode_names.index(task.stroke_mode)


def run_comparison(bundle: ModelBundle, demos: Demonstrations, out: Path, args: argparse.Namespace,
                   trial_ids: list[int], make_controller: Any = None, task: Task = EATING) -> dict[str, Any]:
    """Simulate the chosen runs on ``trial_ids`` and write the comparison files; returns comparison.json's object.
    ``make_controller``: the controllers' factory (default: the bundle's ``SharedController``); ``task``: whose
    mode names, figures and criterion."""
    from mpcshare.conflicts import Scenario
    from mpcshare.control.keepout import KeepOutSettings
    from mpcshare.control.types import ControllerConfig
    from mpcshare.evaluation import compare_strategies, render_clip
    from mpcshare.reports.comparison import write_comparison
    from sim.wearer_presets import wearer_preset

    if abs(demos.rate_hz - bundle.rate_hz) > 1e-9 * bundle.rate_hz:
        raise CommandError(f"the data is at {demos.rate_hz:g} Hz, the bundle was trained at {bundle.rate_hz:g} Hz")
    runs = [r for r in ALL_RUNS if r.name in args.runs]
    wearer_name = getattr(args, "wearer", DEFAULT_WEARER_PRESET)
    wearer = wearer_preset(wearer_name)
    scene = scene_from_args(args)
    if scene is not None:
        arm = scene.robot
        print(f"arm: {arm.name} ({arm.n} joints, tip {arm.tip_frame}) from {arm.source}")
    print(f"simulating {len(runs)} strategies x {len(trial_ids)} trial(s) "
          f"({'whole trials' if args.duration is None else f'{args.duration:g} s each'}), wearer {wearer_name}")
    scenario_name = getattr(args, "scenario", None)
    try:
        scenario = None if scenario_name is None else Scenario(scenario_name, demos.obs_names, demos.act_names,
                                                               task=task)
    except ValueError as exc:  # e.g. data without the fork's angles
        raise CommandError(f"--scenario {exc}") from None
    options = None
    if getattr(args, "no_keepout", False):
        options = {"config": ControllerConfig(keepout=None)}
    elif getattr(args, "no_mpc_zones", False):
        options = {"config": ControllerConfig(keepout=KeepOutSettings(mpc_zones=False))}
    if scenario is not None or options is not None:
        guard = "off" if getattr(args, "no_keepout", False) else "on" if options is None else "on, MPC without zones"
        print(f"scenario: {scenario_name or 'none'}; keep-out {guard}")
    announce_output_size(runs, demos, trial_ids, args, out, scene)
    comp = compare_strategies(bundle, demos, trial_ids, runs=runs, duration_s=args.duration, out=out,
                              seed=args.sim_seed, beta=args.beta, mode_names=task.mode_names, task=task,
                              mcap=getattr(args, "mcap", False), wearer=wearer, scene=scene,
                              mcap_rate_hz=getattr(args, "mcap_rate", None), scenario=scenario,
                              controller_options=options, make_controller=make_controller)
    shown = next((r for r in runs if r.name == "gate"), next((r for r in runs if r.schedule is None), None))
    if args.video and shown is None:
        print("no video: only replayed schedules were run (add --runs gate)")
    elif args.video and shown is not None:
        video, message = render_clip(bundle, demos, trial_ids[0], out / f"{shown.name}_trial.mp4",
                                     strategy=shown.strategy, use_mpc=shown.use_mpc, seed=args.sim_seed,
                                     beta=args.beta, wearer=wearer, scene=scene, scenario=scenario,
                                     controller_options=options, task=task,
                                     seconds=10.0 if args.duration is None else min(10.0, args.duration))
        comp.video = None if video is None else str(Path(video).relative_to(out))
        print(f"video: {video}" if video else f"no video: {message}")
    return write_comparison(comp, out, cutting=cutting_steps(demos, trial_ids[0], task), task=task)


def _run(args: argparse.Namespace) -> int:
    from mpcshare.bundle import BundleError, load_bundle

    check_serve_arguments(args)
    out = prepare_output_folder(args.out)
    try:
        given = parse_map(args.map)
    except ValueError as exc:
        raise CommandError(str(exc)) from None
    try:
        bundle = load_bundle(args.model)
    except BundleError as exc:
        raise CommandError(str(exc)) from None
    task = task_for_bundle(args.task, bundle)
    data = args.data or bundle.config.get("data_path")
    if not data:
        raise CommandError("the bundle does not record its training data; pass --data")
    if args.data is None and not Path(data).exists():
        raise CommandError(f"the bundle's training data {data} is gone; pass --data")
    demos = load_or_fail(str(data))
    demos = align_channels(demos, bundle, bundle_map(bundle.config.get("channel_map"), demos, given), task)
    ids = set(demos.trial_ids)
    # the bundle's held-out trials, those its rule's choice did not run on first; other data (--data) without
    # them: all of its trials
    from mpcshare.calibration.trials import bundle_evaluation_trials

    trial_ids = [t for t in bundle_evaluation_trials(bundle) if t in ids]
    if not trial_ids and args.data is not None:
        trial_ids = sorted(ids)
    if not trial_ids:
        raise CommandError(f"none of the bundle's held-out trials {bundle.heldout_trials} is in {data}")
    trial_ids = trial_ids[:args.trials] if args.trials else trial_ids
    t0 = time.perf_counter()
    make = remote = None
    if args.serve:
        make, remote, args.runs = serve_controller(args, bundle)
    try:
        obj = run_comparison(bundle, demos, out, args, trial_ids, make, task)
    finally:
        if remote is not None:
            remote.close()
    if remote is not None:
        print(f"mpcshare sim --serve: {remote.missing} control steps without a command from `mpcshare run`"
              + (f"; the live view stopped: {remote.live_error}" if remote.live_error else ""))
    from mpcshare.reports.comparison import comparison_findings
    from mpcshare.reports.headline import headline_lines, trials_words

    rule = getattr(bundle, "rule", None)
    choice = None if rule is None else rule.choice
    heads = headline_lines(obj["strategies"], markdown=False, rule_choice=choice,
                           trials=trials_words(obj["trials"], obj["duration_s"]), rule_check=obj.get("rule_check"),
                           task=task)
    for line in heads + comparison_findings(obj["strategies"], task):
        print(line)
    print(f"done in {time.perf_counter() - t0:.0f} s; open {out / 'comparison.md'}")
    return 0


SIM_COMMAND = Command("sim", "closed-loop MuJoCo comparison of strategies on held-out trials",
                      _add_arguments, _run)
