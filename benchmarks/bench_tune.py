"""Speed of ``mpcshare tune``: the same sweep with 1 and with 2 local workers (issue 20).

Prints one JSON object: ``planned`` (what ``run_tune`` announced: the episodes it plans, then its estimate
once its first episodes have measured the costs, per worker count), ``ran`` (its last line: the episodes run and
those given the figures of one that decided alike), ``episodes``, ``seconds`` per worker
count, ``seconds_per_episode`` (1 worker), ``speedup`` (1 worker / 2 workers; target ≥ 1.8 on 2 free
cores) and ``same_rows`` (the rows equal but the timing keys).
The bundles are trained once (into ``--out``/bundles) and shared by both runs, so only the
episodes are timed. The machine may be shared: the speedup is only meaningful on idle cores.

Usage: ``python benchmarks/bench_tune.py [--data NPZ] [--out DIR] [--duration 10] [--seeds 2]``.
"""

from __future__ import annotations

import argparse
import json
import shutil
import time
from pathlib import Path

from learning.data import save
from mpcshare.evaluation.tuning.episodes import TIMING_KEYS
from mpcshare.evaluation.tuning.runner import run_tune
from mpcshare.training.config import TrainConfig
from sim.demonstrator import generate_demonstrations
from sim.task.eating import MODE_NAMES


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=None, help="data set (default: 8 generated trials of 1 min)")
    ap.add_argument("--out", default="bench-tune")
    ap.add_argument("--duration", type=float, default=10.0)
    ap.add_argument("--seeds", type=int, default=2)
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    data = args.data or out / "demos.npz"
    if args.data is None and not Path(data).exists():
        save(generate_demonstrations(8, 1.0, seed=0), data)
    kwargs = dict(percentiles=[90.0], betas=[0.0, 1.0], strategies=["gate"], n_trials=2,
                  seeds=list(range(args.seeds)), duration_s=args.duration, wearer="hemiparetic_mild",
                  config=TrainConfig(max_epochs=10), progress=False, log=None, mode_names=MODE_NAMES)
    run_tune(data, out / "prep", workers=1, **{**kwargs, "seeds": []})  # no episodes: trains the bundles only
    seconds, rows, said = {}, {}, {}
    for workers in (1, 2):
        folder = out / f"w{workers}"
        if folder.exists():
            shutil.rmtree(folder)
        folder.mkdir()
        (folder / "bundles").symlink_to((out / "prep" / "bundles").resolve())
        t0 = time.perf_counter()
        said[workers] = []
        res = run_tune(data, folder, workers=workers, **{**kwargs, "log": said[workers].append})
        seconds[workers] = time.perf_counter() - t0
        rows[workers] = [{k: v for k, v in r.items() if k not in TIMING_KEYS} for r in res["rows"]]
    print(json.dumps({"planned": {w: lines[:2] for w, lines in said.items()},
                      "ran": {w: lines[-1].split(": ")[-1] for w, lines in said.items()}, "episodes": len(rows[1]),
                      "seconds": seconds, "seconds_per_episode": seconds[1] / len(rows[1]),
                      "speedup": seconds[1] / seconds[2], "same_rows": rows[1] == rows[2]}))


if __name__ == "__main__":
    main()
