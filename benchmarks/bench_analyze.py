"""Benchmark: ``analyze`` at the paper's scale (about an hour of demonstrations per subject).

    python benchmarks/bench_analyze.py [--subjects 3] [--minutes 60] [--data FILE.npz]
        [--baseline] [--skip-analyze]

Prints one JSON object: the wall time of :func:`learning.analysis.analyze` with the
default configuration (search included) and its per-step timings (``timings_s`` of the
report), the data size, and the cores. Target (issue 13): ≤ 3 minutes on 2 cores for
3 subjects × 60 min (about 107k windows at 10 Hz).

``--baseline`` adds, in the same process, the lever the analysis relies on: the
quotients of the segmentation test's groupings (no grouping and the ``n_random`` random
groupings of the HMM modes of the main analysis) computed in one pass by
``pointwise_quotients_multi`` and one ``pointwise_quotients`` call per grouping (the
path before), their times, ratio, and whether the results are identical.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time

import numpy as np


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--subjects", type=int, default=3)
    ap.add_argument("--minutes", type=float, default=60.0)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--data", default=None, help="demonstrations file (.npz) instead of generating")
    ap.add_argument("--baseline", action="store_true",
                    help="also time the segmentation test's groupings one call per grouping")
    ap.add_argument("--skip-analyze", action="store_true", help="only the --baseline comparison")
    a = ap.parse_args(argv)

    from learning.analysis import AnalysisConfig, analyze

    t0 = time.perf_counter()
    if a.data:
        from learning.data import load
        demos = load(a.data)
    else:
        from sim.demonstrator import generate_demonstrations
        demos = generate_demonstrations(a.subjects, a.minutes, seed=a.seed)
    out: dict = {"cores": len(os.sched_getaffinity(0)), "n_trials": len(demos.trials),
                 "data_s": round(time.perf_counter() - t0, 1)}
    config = AnalysisConfig()
    if not a.skip_analyze:
        t0 = time.perf_counter()
        res = analyze(demos, config)
        out["analyze_s"] = round(time.perf_counter() - t0, 1)
        out["timings_s"] = res.summary.timings_s
        out["n_windows"] = int(len(res.windows))
        out["target_s"] = 180.0
    if a.baseline:
        out["segmentation_groupings"] = _baseline(demos, config)
    print(json.dumps(out, indent=1))
    return out


def _baseline(demos, config) -> dict:
    """No grouping + n_random random groupings of the HMM modes: one pass vs one call each."""
    from learning.analysis.reference import random_labelings
    from learning.analysis.search import fit_modes
    from learning.lipschitz import pointwise_quotients, pointwise_quotients_multi
    from learning.preprocessing.preprocess import Preprocessor, Standardizer, causal_windows, downsample

    low = downsample(demos, config.target_hz) if demos.rate_hz != config.target_hz else demos
    pre = Preprocessor(obs=Standardizer(config.scope, field="obs").fit(low),
                       act=Standardizer(config.scope, field="act").fit(low),
                       target_hz=config.target_hz, window_s=config.window_s)
    std = pre.standardize(low)
    w = causal_windows(std, config.window_s, rms=True)
    Z, lengths = std.obs_sequences()
    _, labels = fit_modes(Z, lengths, config.n_modes, config)
    labs = np.vstack([np.zeros((1, len(w)), np.int64),
                      random_labelings(labels[w.source_index], config.n_random, config.random_method,
                                       config.seed)])
    t0 = time.perf_counter()
    Q = pointwise_quotients_multi(w.X, w.Y, labs)
    t_multi = time.perf_counter() - t0
    t0 = time.perf_counter()
    same = all(np.array_equal(pointwise_quotients(w.X, w.Y, g), Q[m]) for m, g in enumerate(labs))
    t_single = time.perf_counter() - t0
    return {"n_groupings": int(len(labs)), "n_windows": int(len(w)), "one_pass_s": round(t_multi, 1),
            "one_call_each_s": round(t_single, 1), "speedup": round(t_single / t_multi, 2),
            "identical": bool(same)}


if __name__ == "__main__":
    main(sys.argv[1:])
