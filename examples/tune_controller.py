"""Tune the shared controller in the closed loop from Python: what ``mpcshare tune`` does.

Generates a small synthetic data set (or takes ``--data``), sweeps K × β for the gate
against its matched random hand-overs on held-out trials × paired seeds, writes
``tune.json``, ``tune.md`` and ``pareto.png`` into ``--out`` and prints whether the gate
beats chance and the recommended setting.

Usage: ``python examples/tune_controller.py [--data DATA.npz] [--out examples-out/tune] [--workers 2]``.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from learning.data import save
from mpcshare.evaluation.tuning.runner import run_tune
from mpcshare.reports.tune import build_result, chance_sentences, write_tune
from mpcshare.training.config import TrainConfig
from sim.demonstrator import generate_demonstrations
from sim.task.eating import MODE_NAMES


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0],
                                 formatter_class=argparse.ArgumentDefaultsHelpFormatter)
    ap.add_argument("--data", default=None, help="data set (None: 8 synthetic trials of 1 min)")
    ap.add_argument("--out", default="examples-out/tune", help="output folder (git ignores examples-out/)")
    ap.add_argument("--workers", type=int, default=2, help="local worker processes")
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(f"writing into {out.resolve()}")
    data = args.data
    if data is None:
        data = out / "demos.npz"
        save(generate_demonstrations(8, 1.0, seed=0), data)
    run = run_tune(data, out, percentiles=[90.0, 70.0], betas=[0.0, 0.5], strategies=["gate"], n_trials=2,
                   seeds=[0, 1], duration_s=10.0, wearer="hemiparetic_mild", config=TrainConfig(max_epochs=20),
                   workers=args.workers, mode_names=MODE_NAMES)
    result = build_result(run["rows"], trials=run["trials"], seeds=[0, 1], duration_s=10.0,
                          wearer="hemiparetic_mild", bundles=run["bundles"])
    write_tune(result, out)
    print("\n".join(chance_sentences(result)))
    print(f"recommended: {result['recommended']['setting']} ({result['recommended']['criterion']})")


if __name__ == "__main__":
    main()
