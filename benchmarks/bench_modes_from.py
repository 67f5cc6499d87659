"""HMM task modes against the time-free mixture (``mpcshare train --modes-from``) for the controller.
Prints JSON.

    PYTHONPATH=. python benchmarks/bench_modes_from.py [--subjects 3] [--minutes 10] [--seed 0]

Data: the project's default demonstrations (``sim.demonstrator``, 3 subjects × 10 min). For
each source of the modes (``hmm``, ``mixture``) one bundle is trained with the default
``TrainConfig`` (only ``modes_from`` differs) and the held-out metrics of the bundle are
reported: the voluntary share (fraction of held-out windows the gate hands to the wearer),
gate accuracy against the quotient labels, the predictor's RMSE where the gate acts; the
agreement of the held-out modes with the true labels (Hungarian matching); and the online
mode filter's cost, ``ModeFilter.step`` on the held-out standardised samples [µs a step,
median and p99 over 3 passes]. The analysis's claim "the temporal model adds information"
decides which one the controller needs; this measures what the choice costs.
"""

from __future__ import annotations

import argparse
import json
import time
import warnings
from dataclasses import replace

import numpy as np

from learning.modes import mode_agreement
from mpcshare.training import prepare_training_data, train_bundle
from mpcshare.training.config import MODES_FROM, TrainConfig
from sim.demonstrator import generate_demonstrations


def filter_cost_us(modes, obs: np.ndarray, passes: int = 3) -> dict:
    """Median and p99 wall time of one ``ModeFilter.step`` [µs] over the rows of ``obs``."""
    times = []
    for _ in range(passes):
        f = modes.make_filter()
        for o in obs:
            t0 = time.perf_counter()
            f.step(o)
            times.append(time.perf_counter() - t0)
    t = 1e6 * np.array(times)
    return {"median": round(float(np.median(t)), 2), "p99": round(float(np.percentile(t, 99)), 2)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--subjects", type=int, default=3)
    ap.add_argument("--minutes", type=float, default=10.0)
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    warnings.simplefilter("ignore")
    demos = generate_demonstrations(a.subjects, a.minutes, seed=a.seed)
    out = {}
    for source in MODES_FROM:
        config = replace(TrainConfig(), modes_from=source)
        t0 = time.perf_counter()
        b = train_bundle(demos, config, progress=False)
        seconds = time.perf_counter() - t0
        m = b.metrics
        held = prepare_training_data(demos, config).heldout  # the same split and modes (seeded)
        obs, _ = held.std.obs_sequences()
        true = np.concatenate([t.mode for t in held.std.trials])
        out[source] = {
            "voluntary_share": round(m["voluntary_share"], 4),
            "gate_accuracy": round(m["gate"]["overall"]["accuracy"], 4),
            "gate_f1": round(m["gate"]["overall"]["f1"], 4),
            "rmse_gated": m["predictor"].get("rmse_gated"),
            "K": b.K, "novelty_threshold": round(b.novelty_threshold, 3),
            "heldout_mode_agreement": round(float(mode_agreement(held.modes, true)[0]), 4),
            "expected_durations_samples": np.round(b.modes.expected_durations_, 2).tolist(),
            "filter_step_us": filter_cost_us(b.modes, obs),
            "train_s": round(seconds, 1)}
    print(json.dumps({"data": {"subjects": a.subjects, "minutes": a.minutes, "seed": a.seed}, **out}, indent=1))


if __name__ == "__main__":
    main()
