"""The same eating closed loop on two arms: the SuperLimb (3 joints) and the Franka Panda (7 joints,
example-robot-data, on the table beside the plate: ``tests/sim/second_arm.py``); prints JSON.

Both arms run the same controller (``SharedController`` from the same bundle), the same held-out trials,
the same wearer and the same seed, measured in the same process, one after the other. Figures per arm
and strategy: tracking RMS and p95 [m], limit violations in the physics, control-step p50/p99 [ms], and
the ratio Panda / SuperLimb of the tracking RMS (target for ``reactive``: ≤ 1.5). Single-threaded BLAS
(the 7-joint MPC's dense products are slowed many times by BLAS threads on a shared machine).

Usage: ``python benchmarks/bench_robots.py [--data-kind default|other_seed|other_structure]
[--bundle DIR --data FILE] [--trials 2] [--duration 30] [--runs reactive gate]``; without ``--bundle``
a bundle is trained on the data kind (``benchmarks/bench_task.py``'s generators) and, with
``--save-bundle DIR``, kept.
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

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench_task import bundle_and_data  # noqa: E402

from mpcshare.bundle import save_bundle  # noqa: E402
from mpcshare.experiments import DEFAULT_RUNS, compare_strategies  # noqa: E402
from sim.demonstrator import MODE_NAMES  # noqa: E402
from sim.scene import SceneConfig  # noqa: E402
from tests.sim.second_arm import panda  # noqa: E402

KEYS = ("tracking_rmse_m", "tracking_p95_m", "limit_violations", "step_p50_ms", "step_p99_ms", "realtime_factor",
        "lag_s")


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
    a = p.parse_args(argv)
    t0 = time.perf_counter()
    bundle, demos = bundle_and_data(a.bundle, a.data, a.data_kind)
    if a.save_bundle and not a.bundle:
        save_bundle(bundle, a.save_bundle)
    trials = list(bundle.heldout_trials[:a.trials])
    runs = [r for r in DEFAULT_RUNS if r.name in a.runs]
    scenes = {"superlimb": SceneConfig(), "panda": SceneConfig(robot=panda())}
    result: dict = {"data": a.data if a.bundle else a.data_kind, "trials": trials, "duration_s": a.duration,
                    "seed": a.seed, "arms": {}, "ratio_panda_over_superlimb": {}}
    for name, scene in scenes.items():
        comp = compare_strategies(bundle, demos, trials, runs=runs, duration_s=a.duration, log=None, seed=a.seed,
                                  mode_names=MODE_NAMES, scene=scene)
        result["arms"][name] = {"joints": scene.robot.n, "tip_frame": scene.robot.tip_frame,
                                **{run: {k: m.get(k) for k in KEYS} for run, m in comp.strategies.items()}}
        print(f"{name}: done ({time.perf_counter() - t0:.0f} s)", file=sys.stderr)
    for run in a.runs:
        sl, pa = result["arms"]["superlimb"][run], result["arms"]["panda"][run]
        result["ratio_panda_over_superlimb"][run] = pa["tracking_rmse_m"] / sl["tracking_rmse_m"]
    ratio = result["ratio_panda_over_superlimb"].get("reactive")
    result["target_reactive_within_1_5x"] = None if ratio is None else bool(ratio <= 1.5)
    result["seconds"] = time.perf_counter() - t0
    print(json.dumps(result, indent=1, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
