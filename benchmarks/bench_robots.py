"""The same eating closed loop on every arm preset and the SuperLimb; prints JSON and a Markdown table.

Every arm runs the same controller (``SharedController`` from the same bundle), the same held-out
trials, the same wearer and the same seed, measured in the same process, one after the other. Each
preset (:mod:`robot.presets`) stands where :mod:`sim.arm_mounts` puts it, with the speed and
acceleration caps :func:`mpcshare.arms.task_arm` chooses. Figures per arm and strategy: tracking RMS
and p95 [m], limit violations in the physics, control-step p50/p99 [ms], the ratio arm / SuperLimb of
the tracking RMS (target for ``reactive``: ≤ 1.5); per arm: the chosen caps, and the reach of the
task's targets (the share of the trials' demonstrated knife tips, every 20th, the torso at rest, that
the arm's inverse kinematics reaches within 2 mm). Single-threaded BLAS (the 7-joint MPC's dense
products are slowed many times by BLAS threads on a shared machine).

Usage: ``python benchmarks/bench_robots.py [--data-kind default|other_seed|other_structure]
[--bundle DIR --data FILE] [--trials 2] [--duration 30] [--runs reactive gate] [--arms panda ur5]``;
without ``--bundle`` a bundle is trained on the data kind (``benchmarks/bench_task.py``'s generators)
and, with ``--save-bundle DIR``, kept.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import json  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import pinocchio as pin  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench_task import bundle_and_data  # noqa: E402

from mpcshare.arms import task_arm  # noqa: E402
from mpcshare.bundle import save_bundle  # noqa: E402
from mpcshare.evaluation import DEFAULT_RUNS, compare_strategies  # noqa: E402
from robot.presets import ARM_PRESETS  # noqa: E402
from sim.scene import SceneConfig  # noqa: E402
from sim.task.eating import MODE_NAMES  # noqa: E402

KEYS = ("tracking_rmse_m", "tracking_p95_m", "limit_violations", "step_p50_ms", "step_p99_ms", "realtime_factor",
        "lag_s")
REACH_TOL = 2e-3  # [m]


def target_reach(robot, tips_plate: np.ndarray, plate: np.ndarray) -> float:
    """Share of the knife tips (k, 3) in the plate frame that the inverse kinematics reaches within REACH_TOL."""
    data = robot.model.createData()
    hits = 0
    for tip in tips_plate + plate:
        pin.framesForwardKinematics(robot.model, data, robot.inverse_kinematics(tip))
        hits += np.linalg.norm(data.oMf[robot.tip_frame_id].translation - tip) <= REACH_TOL
    return hits / len(tips_plate)


def markdown_table(result: dict, runs: list[str]) -> str:
    """One row per arm: joints, caps, reach, and per strategy RMS [mm] (× SuperLimb) and violations."""
    head = "| arm | joints | caps (velocity; acceleration) | targets reached | " + " | ".join(
        f"`{r}` RMS mm (× SuperLimb) | `{r}` violations" for r in runs) + " |"
    rows = [head, "|" + "---|" * (4 + 2 * len(runs))]
    for name, arm in result["arms"].items():
        cells = [name, str(arm["joints"]), arm.get("caps", "its own"), f"{arm['targets_reached']:.0%}"]
        for r in runs:
            ratio = result["ratio_over_superlimb"].get(name, {}).get(r)
            cells.append(f"{arm[r]['tracking_rmse_m'] * 1e3:.1f}" + ("" if ratio is None else f" ({ratio:.2f}×)"))
            cells.append(str(arm[r]["limit_violations"]))
        rows.append("| " + " | ".join(cells) + " |")
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--bundle")
    p.add_argument("--data")
    p.add_argument("--data-kind", default="default")
    p.add_argument("--save-bundle")
    p.add_argument("--trials", type=int, default=2)
    p.add_argument("--duration", type=float, default=30.0)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--runs", nargs="+", default=["reactive", "gate"], choices=[r.name for r in DEFAULT_RUNS])
    p.add_argument("--arms", nargs="+", default=list(ARM_PRESETS), choices=list(ARM_PRESETS))
    a = p.parse_args(argv)
    t0 = time.perf_counter()
    bundle, demos = bundle_and_data(a.bundle, a.data, a.data_kind)
    if a.save_bundle and not a.bundle:
        save_bundle(bundle, a.save_bundle)
    trials = list(bundle.heldout_trials[:a.trials])
    runs = [r for r in DEFAULT_RUNS if r.name in a.runs]
    cols = [list(demos.act_names).index(c) for c in ("knife_x", "knife_y", "knife_z")]
    tips = np.concatenate([tr.act[:, cols] for tr in demos.trials if tr.trial_id in trials])[::20]
    result: dict = {"data": a.data if a.bundle else a.data_kind, "trials": trials, "duration_s": a.duration,
                    "seed": a.seed, "tips_checked": len(tips), "arms": {}, "ratio_over_superlimb": {}}
    scenes: dict[str, tuple[SceneConfig, str | None]] = {"superlimb": (SceneConfig(), None)}
    for name in a.arms:
        arm = task_arm(name)
        scenes[name] = (arm.scene, arm.summary.split(" (braking")[0])
    for name, (scene, caps) in scenes.items():
        comp = compare_strategies(bundle, demos, trials, runs=runs, duration_s=a.duration, log=None, seed=a.seed,
                                  mode_names=MODE_NAMES, scene=scene)
        entry = {"joints": scene.robot.n, "tip_frame": scene.robot.tip_frame,
                 "targets_reached": target_reach(scene.robot, tips, np.asarray(scene.plate_position)),
                 **({} if caps is None else {"caps": caps}),
                 **{run: {k: m.get(k) for k in KEYS} for run, m in comp.strategies.items()}}
        result["arms"][name] = entry
        print(f"{name}: done ({time.perf_counter() - t0:.0f} s)", file=sys.stderr)
    base = result["arms"]["superlimb"]
    for name in a.arms:
        result["ratio_over_superlimb"][name] = {
            run: result["arms"][name][run]["tracking_rmse_m"] / base[run]["tracking_rmse_m"] for run in a.runs}
    ratios = [r.get("reactive") for r in result["ratio_over_superlimb"].values()]
    result["target_reactive_within_1_5x"] = None if None in ratios or not ratios else bool(max(ratios) <= 1.5)
    result["seconds"] = time.perf_counter() - t0
    result["table"] = markdown_table(result, a.runs)
    print(json.dumps(result, indent=1, default=float, ensure_ascii=False))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
