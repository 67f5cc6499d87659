"""CPU seconds of one closed-loop episode of a real bundle, against another checkout; prints JSON.

Each measurement is a fresh process (``python -c`` with the checkout first on ``PYTHONPATH``, one BLAS and
one torch thread) that loads the bundle and the data, runs one short warm-up episode, then
:func:`mpcshare.evaluation.simulate_episode` (the comparison's and the rule choice's episode: controller,
MuJoCo loop, metrics) of each ``--runs`` strategy on ``--trial`` for ``--seconds``, and reports its
process CPU time and figures. With ``--baseline DIR`` (another checkout, e.g. ``git worktree add
/tmp/base <commit>``) the two checkouts alternate, ``--rounds`` times each: on a shared machine the
minimum over rounds is the comparable figure (``ratio`` = baseline / this checkout), and ``same_figures``
whether both gave the same RMS, effort and keep-out clearance to 12 significant digits.

Usage: ``python benchmarks/bench_episode.py --model OUT/model --data OUT/demos.npz [--baseline DIR]
[--runs gate voluntary] [--trial 3] [--seconds 30] [--rounds 3]`` (``OUT``: a ``mpcshare demo`` folder).
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
from pathlib import Path

_CHILD = """
import json, os, sys, time
import torch
torch.set_num_threads(1)
from learning.data import load
from mpcshare.bundle import load_bundle
from mpcshare.control.types import DEFAULT_BETA
from mpcshare.evaluation.episode import simulate_episode
from mpcshare.run_table import DEFAULT_RUNS
from sim.task.eating import MODE_NAMES
from sim.wearer_presets import wearer_preset
model, data, trial_id, seconds, names = sys.argv[1], sys.argv[2], int(sys.argv[3]), float(sys.argv[4]), sys.argv[5:]
bundle, demos = load_bundle(model), load(data)
trial = next(t for t in demos.trials if t.trial_id == trial_id)
def episode(name, duration):
    run = next(r for r in DEFAULT_RUNS if r.name == name)
    return simulate_episode(bundle, demos, trial, run, {}, beta=DEFAULT_BETA, duration_s=duration, seed=0,
                            wearer=wearer_preset("hemiparetic_mild"), mode_names=MODE_NAMES)[1]
episode(names[0], 2.0)
for name in names:
    c0 = time.process_time()
    m = episode(name, seconds)
    cpu = time.process_time() - c0
    print(json.dumps({"run": name, "cpu_s": cpu, "tracking_rmse_m": m["tracking_rmse_m"],
                      "voluntary_effort": m["voluntary_effort"], "keepout_min_clearance_m":
                      m["keepout_min_clearance_m"]}))
"""


def _measure(tree: Path, args: argparse.Namespace) -> list[dict]:
    env = {**os.environ, "PYTHONPATH": str(tree), "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1",
           "MKL_NUM_THREADS": "1", "MUJOCO_GL": os.environ.get("MUJOCO_GL", "egl")}
    out = subprocess.run([sys.executable, "-c", _CHILD, args.model, args.data, str(args.trial), str(args.seconds),
                          *args.runs], cwd=tree, env=env, capture_output=True, text=True, check=True)
    return [json.loads(line) for line in out.stdout.splitlines() if line.startswith("{")]


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--model", required=True, help="a bundle folder (e.g. a demo's model/)")
    p.add_argument("--data", required=True, help="the demonstrations it was trained on (e.g. the demo's demos.npz)")
    p.add_argument("--baseline", default=None, help="another checkout to compare with")
    p.add_argument("--runs", nargs="+", default=["gate"], help="run names of the run table (default gate)")
    p.add_argument("--trial", type=int, default=3, help="held-out trial id (default 3, the demo's second)")
    p.add_argument("--seconds", type=float, default=30.0, help="simulated seconds (default 30)")
    p.add_argument("--rounds", type=int, default=3, help="processes per checkout (default 3)")
    args = p.parse_args()
    from mpcshare.run_table import DEFAULT_RUNS

    scheduled = [r.name for r in DEFAULT_RUNS if r.schedule is not None]
    if bad := [n for n in args.runs if n not in {r.name for r in DEFAULT_RUNS} or n in scheduled]:
        p.error(f"--runs {bad}: not a run of the run table without a schedule; valid choices: "
                f"{', '.join(r.name for r in DEFAULT_RUNS if r.schedule is None)}")
    here = Path(__file__).resolve().parents[1]
    trees = {"this": here} | ({"baseline": Path(args.baseline).resolve()} if args.baseline else {})
    found: dict[str, list[list[dict]]] = {name: [] for name in trees}
    for _ in range(args.rounds):
        for name, tree in trees.items():
            found[name].append(_measure(tree, args))
    result: dict = {"trial": args.trial, "seconds": args.seconds, "rounds": args.rounds, "runs": {}}
    for i, run in enumerate(args.runs):
        row: dict = {}
        for name in trees:
            cpus = [rnd[i]["cpu_s"] for rnd in found[name]]
            row[name] = {"cpu_s_min": min(cpus), "cpu_s_all": cpus, "cpu_s_per_sim_s": min(cpus) / args.seconds,
                         "figures": {k: v for k, v in found[name][0][i].items() if k not in ("run", "cpu_s")}}
        if "baseline" in row:
            row["ratio"] = row["baseline"]["cpu_s_min"] / row["this"]["cpu_s_min"]
            a, b = row["baseline"]["figures"], row["this"]["figures"]
            row["same_figures"] = all(math.isclose(a[k], b[k], rel_tol=1e-12, abs_tol=0.0) for k in a)
        result["runs"][run] = row
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
