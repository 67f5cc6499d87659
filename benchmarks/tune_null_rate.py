"""The false-positive rate of ``tune``'s gate-against-placebo test under the null, by the placebo's design.

Under the null the setting's episode and each placebo draw of a pair are exchangeable: their tracking RMS are drawn
from one skewed law (log-normal, σ = ``--sigma``) around a pair effect that cancels. For each design the test of
:func:`mpcshare.evaluation.tuning.stats.gate_vs_random` runs on ``--reps`` null sweeps, and the share with
p < 0.05 is printed (one JSON object): ``pairs_1_draw`` (10 trial × seed pairs, one draw: the default),
``pairs_2_draws`` (the mean of 2 draws per pair), ``trial_x_draw`` (2 trials × 5 draws as 10 "pairs" sharing a
setting episode per trial). A design holds its level where the rate is ≤ 0.05 up to the Monte Carlo error
(``mc_se``).

Usage: ``python benchmarks/tune_null_rate.py [--reps 2000] [--sigma 0.5]``.
"""

from __future__ import annotations

import argparse
import json
import math

import numpy as np

from mpcshare.evaluation.tuning.stats import ALPHA_LEVEL, gate_vs_random


def _rows(setting: np.ndarray, placebo: np.ndarray) -> list[dict]:
    """Rows of one setting (``gate p90 b0.5``): setting[i] per pair, placebo[i, j] per pair and draw."""
    rows = []
    for i, (e, draws) in enumerate(zip(setting, placebo)):
        base = {"percentile": 90.0, "beta": 0.5, "trial": i, "seed": 0, "handovers": 4}
        rows.append({**base, "strategy": "gate", "matched_to": None, "draw": 0, "tracking_rmse_m": float(e)})
        rows += [{**base, "strategy": "random_handover", "matched_to": "gate", "draw": j, "tracking_rmse_m": float(x)}
                 for j, x in enumerate(draws)]
    return rows


def _rate(rng: np.random.Generator, reps: int, sigma: float, design: str) -> float:
    hits = 0
    for _ in range(reps):
        effect = rng.lognormal(0.0, 0.3, 10)  # the pair's own level (trial and seed), shared by both arms
        if design == "trial_x_draw":  # 2 setting episodes, each paired with 5 draws
            setting = np.repeat(rng.lognormal(0.0, sigma, 2), 5) * effect
            placebo = (rng.lognormal(0.0, sigma, 10) * effect)[:, None]
        else:
            draws = 1 if design == "pairs_1_draw" else 2
            setting = rng.lognormal(0.0, sigma, 10) * effect
            placebo = rng.lognormal(0.0, sigma, (10, draws)) * effect[:, None]
        p = gate_vs_random(_rows(setting, placebo))["gate p90 b0.5"]["vs_random_handover"]["p_value"]
        hits += p is not None and p < ALPHA_LEVEL
    return hits / reps


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--reps", type=int, default=2000)
    ap.add_argument("--sigma", type=float, default=0.5)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    out = {d: _rate(rng, args.reps, args.sigma, d) for d in ("pairs_1_draw", "pairs_2_draws", "trial_x_draw")}
    print(json.dumps({"alpha": ALPHA_LEVEL, "reps": args.reps, "sigma": args.sigma, **out,
                      "mc_se": math.sqrt(ALPHA_LEVEL * (1 - ALPHA_LEVEL) / args.reps)}))


if __name__ == "__main__":
    main()
