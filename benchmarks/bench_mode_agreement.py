"""Does mode discovery depend on luck? Agreement of TaskModes with the true modes over seeds.

For each of ``--seeds`` data sets of the generator (``sim.demonstrator``, default and a
weaker-cue variant; small: 1 subject × 4 min, preprocessed as the analysis does), fit
``--restarts`` single-restart HMMs (the restarts ``TaskModes`` would run, one by one) and
record each restart's training log-likelihood and agreement with the true modes. From
these, the agreement that choosing the best-likelihood restart among the first k gives,
for k = 1, 3, 5, … (what ``TaskModes(n_restarts=k)`` returns), and the spread of the
restarts' log-likelihoods; and, as a time-free baseline, the agreement of the
analysis's reference grouping (``learning.analysis.reference``, a Gaussian mixture on the same
features). Prints JSON.

    PYTHONPATH=. python benchmarks/bench_mode_agreement.py [--seeds 20] [--restarts 10]
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings

import numpy as np

from learning.analysis.reference import reference_segmentation
from learning.modes import TaskModes, mode_agreement
from learning.preprocessing.preprocess import Standardizer, downsample
from sim.demonstrator import GeneratorConfig, generate_demonstrations

FAMILIES = {"default": {}, "overlap 0.9": {"overlap": 0.9}}


def restarts(seed: int, n: int, gen: dict) -> tuple[np.ndarray, np.ndarray, float]:
    """(log-likelihood, agreement) of n single-restart fits (``TaskModes(n_restarts=1, seed=r)``,
    r = 0 … n−1: independent k-means++ initialisations) on one data set."""
    demos = downsample(generate_demonstrations(1, 4, seed=seed, config=GeneratorConfig(**gen)), 10.0)
    std = Standardizer("sensor", field="obs").fit(demos)
    Z = np.concatenate([std.transform(t.obs) for t in demos.trials])
    lengths = [len(t) for t in demos.trials]
    true = np.concatenate([t.mode for t in demos.trials])
    ll, agree = [], []
    for r in range(n):
        m = TaskModes(n_modes=4, n_restarts=1, seed=r).fit(Z, lengths)
        ll.append(m.loglik_)
        agree.append(float(mode_agreement(m.predict(Z, lengths), true)[0]))
    ref = reference_segmentation(m.transform(Z), m.predict(Z, lengths), "gmm", seed=0)
    return np.array(ll), np.array(agree), float(mode_agreement(ref, true)[0])


def summary(x: np.ndarray) -> dict:
    q = np.quantile(x, [0.0, 0.1, 0.5, 0.9, 1.0])
    return {"min": round(q[0], 3), "p10": round(q[1], 3), "median": round(q[2], 3), "p90": round(q[3], 3),
            "max": round(q[4], 3), "below_0.9": int(np.sum(x < 0.9))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--restarts", type=int, default=10)
    a = ap.parse_args()
    warnings.simplefilter("ignore")
    out = {}
    for name, gen in FAMILIES.items():
        runs = [restarts(s, a.restarts, gen) for s in range(a.seeds)]
        print(f"{name}: done", file=sys.stderr, flush=True)
        by_k = {}
        for k in sorted({1, 3, 5, a.restarts}):
            if k > a.restarts:
                continue
            chosen = np.array([ag[np.argmax(ll[:k])] for ll, ag, _ in runs])
            by_k[f"best_of_{k}"] = {**summary(chosen), "values": chosen.round(3).tolist()}
        every = np.concatenate([ag for _, ag, _ in runs])
        spread = np.array([ll.max() - ll.min() for ll, _, _ in runs])
        out[name] = {"agreement_chosen": by_k, "agreement_every_restart": summary(every),
                     "loglik_spread_per_dataset_nats": summary(spread),
                     "best_loglik_has_best_agreement": float(np.mean(
                         [ag[np.argmax(ll)] >= ag.max() - 1e-3 for ll, ag, _ in runs])),
                     "gmm_reference_agreement": summary(np.array([g for _, _, g in runs]))}
    print(json.dumps(out, indent=1))


if __name__ == "__main__":
    main()
