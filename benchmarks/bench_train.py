"""Wall time of ``mpcshare train`` and of the K sweep on the default data. Prints JSON.

    python benchmarks/bench_train.py [--minutes 10] [--subjects 3] [--seed 0] [--no-sweep]

Data: ``sim.demonstrator.generate_demonstrations(subjects, minutes, seed)`` (default: the
project's default data, 3 subjects × 10 min at 100 Hz). Measured in one process:

- ``train_s``: :func:`mpcshare.training.train_bundle` with the default ``TrainConfig``
  (90th percentile), plus ``save_bundle``; stage timings from the bundle's metrics;
- ``sweep_s``: :func:`mpcshare.training.sweep.run_sweep` over 100, 90, …, 50 with the files;
- ``baseline_matmul_s``: a fixed single-threaded NumPy workload (20 products of two
  1000×1000 float64 matrices) timed before and after, so that figures from a loaded,
  shared machine can be compared as ratios (``*_over_baseline``);
- ``load_avg``: the 1-minute load average at the start and end (``os.getloadavg``).

Targets (README, 2-core CPU): train ≤ 300 s, sweep ≤ 900 s.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

TARGETS_S = {"train_s": 300.0, "sweep_s": 900.0}


def baseline_matmul() -> float:
    """Seconds for 20 single-threaded 1000×1000 float64 matrix products."""
    from threadpoolctl import threadpool_limits

    rng = np.random.default_rng(0)
    a, b = rng.standard_normal((1000, 1000)), rng.standard_normal((1000, 1000))
    with threadpool_limits(1):
        t0 = time.perf_counter()
        for _ in range(20):
            a @ b
        return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--subjects", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--no-sweep", action="store_true")
    args = ap.parse_args()

    from mpcshare.bundle import save_bundle
    from mpcshare.reports.sweep import write_sweep
    from mpcshare.training import train_bundle
    from mpcshare.training.config import TrainConfig
    from mpcshare.training.sweep import run_sweep
    from sim.demonstrator import generate_demonstrations

    res: dict = {"machine": platform.machine(), "cpus": os.cpu_count(), "load_avg_start": os.getloadavg()[0],
                 "data": {"subjects": args.subjects, "minutes": args.minutes, "seed": args.seed}}
    demos = generate_demonstrations(args.subjects, args.minutes, seed=args.seed)
    base0 = baseline_matmul()
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        bundle = train_bundle(demos, TrainConfig(seed=args.seed), progress=False)
        save_bundle(bundle, Path(tmp) / "model")
        res["train_s"] = round(time.perf_counter() - t0, 2)
        res["train_stages_s"] = bundle.metrics["training"]["timings_s"]
        if not args.no_sweep:
            t0 = time.perf_counter()
            sweep = run_sweep(demos, TrainConfig(seed=args.seed), progress=False)
            t1 = time.perf_counter()
            write_sweep(sweep, Path(tmp) / "sweep")
            res["sweep_s"] = round(time.perf_counter() - t0, 2)
            res["sweep_stages_s"] = {**sweep.info["timings_s"], "files": round(time.perf_counter() - t1, 3)}
    base1 = baseline_matmul()
    res["baseline_matmul_s"] = [round(base0, 3), round(base1, 3)]
    base = 0.5 * (base0 + base1)
    for key in ("train_s", "sweep_s"):
        if key in res:
            res[f"{key.removesuffix('_s')}_over_baseline"] = round(res[key] / base, 1)
            res[f"{key.removesuffix('_s')}_within_target"] = res[key] <= TARGETS_S[key]
    res["load_avg_end"] = os.getloadavg()[0]
    print(json.dumps(res, indent=2))


if __name__ == "__main__":
    main()
