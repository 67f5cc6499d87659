"""CPU seconds of a replayed closed-loop episode, this checkout against another, taking turns; prints JSON.

Each checkout runs in one process (its tree first on ``PYTHONPATH``, one torch and one BLAS thread) that loads
the bundle and the data and records the trial's front end with a ``voluntary`` episode
(:func:`mpcshare.evaluation.frontend_replay.simulate_cached`, as the comparison's and the rule choice's
workers do); then the two processes take turns, one replayed ``--run`` episode each, in the order ABBA over
``--pairs`` pairs, so that both see the same load. ``median_ratio``: the median over pairs of baseline CPU /
this CPU; ``identical``: whether both checkouts gave every array of every episode (but ``step_time``) and every
metric (but the timings) to the last bit (a SHA-256 of them).

Usage: ``python benchmarks/bench_episode_replayed.py --model OUT/model --data OUT/demos.npz --baseline DIR
[--run gate] [--seconds 30] [--seed 0] [--pairs 10]`` (``OUT``: a ``mpcshare demo`` folder; ``DIR``: another
checkout, e.g. ``git worktree add /tmp/base <commit>``).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

_CHILD = """
import hashlib, json, sys, time
import numpy as np, torch
torch.set_num_threads(1)
from learning.data import load
from mpcshare.bundle import load_bundle
from mpcshare.evaluation.frontend_replay import simulate_cached
from mpcshare.run_table import StrategyRun
from sim.task.eating import MODE_NAMES
model, data, seconds, seed, name = sys.argv[1], sys.argv[2], float(sys.argv[3]), int(sys.argv[4]), sys.argv[5]
bundle, demos = load_bundle(model), load(data)
trial = next(t for t in demos.trials if t.trial_id == bundle.heldout_trials[0])
def episode(run):
    return simulate_cached(bundle, demos, trial, StrategyRun(run, run), {}, beta=0.5, duration_s=seconds, seed=seed,
                           wearer=None, mode_names=MODE_NAMES)
episode("voluntary")
print("ready", flush=True)
for _ in sys.stdin:
    c0 = time.process_time()
    ep, metrics, _ = episode(name)
    cpu = time.process_time() - c0
    h = hashlib.sha256()
    for key, value in sorted(vars(ep).items()):
        if isinstance(value, np.ndarray) and key != "step_time":
            h.update(key.encode() + np.ascontiguousarray(value).tobytes())
    timing = ("step_p50_ms", "step_p99_ms", "realtime_factor")
    h.update(repr(sorted((k, v) for k, v in metrics.items() if k not in timing and "time" not in k)).encode())
    print(json.dumps({"cpu_s": cpu, "digest": h.hexdigest()}), flush=True)
"""


def _start(tree: Path, args: argparse.Namespace) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(tree), "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1", "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    proc = subprocess.Popen([sys.executable, "-c", _CHILD, args.model, args.data, str(args.seconds), str(args.seed),
                             args.run], cwd=tree, env=env, stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    if proc.stdout.readline().strip() != "ready":
        raise SystemExit(f"bench_episode_replayed: the checkout {tree} did not start (see its error above)")
    return proc


def _episode(proc: subprocess.Popen) -> dict:
    proc.stdin.write("go\n")
    proc.stdin.flush()
    return json.loads(proc.stdout.readline())


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--model", required=True, help="a bundle folder (e.g. a demo's model/)")
    p.add_argument("--data", required=True, help="the demonstrations it was trained on (e.g. the demo's demos.npz)")
    p.add_argument("--baseline", required=True, help="another checkout to compare with")
    p.add_argument("--run", default="gate", help="the strategy of the replayed episodes (default gate)")
    p.add_argument("--seconds", type=float, default=30.0, help="simulated seconds (default 30)")
    p.add_argument("--seed", type=int, default=0, help="the episodes' seed (default 0)")
    p.add_argument("--pairs", type=int, default=10, help="episodes per checkout (default 10)")
    args = p.parse_args()
    trees = [Path(args.baseline).resolve(), Path(__file__).resolve().parents[1]]
    procs = [_start(tree, args) for tree in trees]
    found: list[list[dict]] = [[], []]
    for k in range(args.pairs):
        for i in ((0, 1) if k % 2 == 0 else (1, 0)):
            found[i].append(_episode(procs[i]))
    for proc in procs:
        proc.stdin.close()
        proc.wait()
    cpu = [[r["cpu_s"] for r in f] for f in found]
    print(json.dumps({
        "run": args.run, "seconds": args.seconds, "seed": args.seed, "pairs": args.pairs,
        "baseline_cpu_s": cpu[0], "this_cpu_s": cpu[1], "median_baseline_s": statistics.median(cpu[0]),
        "median_this_s": statistics.median(cpu[1]),
        "median_ratio": statistics.median(b / t for b, t in zip(cpu[0], cpu[1])),
        "identical": len({r["digest"] for f in found for r in f}) == 1}, indent=2))


if __name__ == "__main__":
    main()
