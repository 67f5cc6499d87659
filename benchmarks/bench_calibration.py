"""Calibration study of the "modes add information" claim (issue 13).

False claims: ≥ 50 regime-free data sets (``sim.regime_free.calibration_family``: linear
and nonlinear maps, latent dimension 1–5, noise levels, 6–20 trials of 1–2 min at 10 Hz)
through :func:`learning.analysis.analyze` at the default settings (the claim: one-sided
Wilcoxon over trials against the time-free reference, p < 0.001). Power: the default
demonstrations (``sim.demonstrator``) and weaker-cue variants (``overlap`` up, ``contrast``
down), 20 trials of 30 s per data set, several seeds each.

Prints one JSON object (false-claim rate, p-value histogram, claim rate per cue strength)
and writes the p-value histogram to the PNG path given.

    PYTHONPATH=. python benchmarks/bench_calibration.py calib_hist.png [--sets 50] [--power-seeds 5]
"""

from __future__ import annotations

import argparse
import json
import time
import warnings

import numpy as np

from learning.analysis import SIGNIFICANCE, AnalysisConfig, analyze
from sim.demonstrator import GeneratorConfig, generate_demonstrations
from sim.regime_free import calibration_family, generate_regime_free

CONFIG = AnalysisConfig(n_random=1, search_windows=(), search_modes=(), hmm_restarts=3)
BINS = np.array([0.0, 1e-3, 0.01, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0])
CUES = [("default", {}), ("overlap 0.75", {"overlap": 0.75}), ("overlap 0.9", {"overlap": 0.9}),
        ("overlap 0.97", {"overlap": 0.97}), ("contrast 0.75", {"contrast": 0.75}),
        ("contrast 0.3", {"contrast": 0.3})]


def _row(report: dict) -> dict:
    t = report["segmentation_test"]
    return {"n_trials": t["n_trials"], "p": t["p_value"], "effect": round(t["effect_size"], 4),
            "ci": [round(t["ci"]["low"], 4), round(t["ci"]["high"], 4)], "claimed": t["significant"],
            "reachable": t["reachable"], "random_p": t["random"]["p_value"],
            "agreement": report["modes"]["agreement"]}


def false_claims(n_sets: int, seed: int) -> list[dict]:
    rows = []
    for cfg, data_seed in calibration_family(n_sets, seed):
        r = _row(analyze(generate_regime_free(cfg, data_seed), CONFIG).report)
        r.update(latent_dim=cfg.latent_dim, maps=f"{cfg.obs_map}/{cfg.act_map}",
                 obs_noise=round(cfg.obs_noise, 4))
        rows.append(r)
    return rows


def power(seeds: int) -> dict[str, list[dict]]:
    out = {}
    for name, kw in CUES:
        gen = GeneratorConfig(trial_minutes=0.5, **kw)
        out[name] = [_row(analyze(generate_demonstrations(2, 5, seed=100 + s, config=gen), CONFIG).report)
                     for s in range(seeds)]
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("png", help="where to write the p-value histogram")
    ap.add_argument("--sets", type=int, default=50, help="regime-free data sets (default 50)")
    ap.add_argument("--power-seeds", type=int, default=5, help="data sets per cue strength (default 5)")
    ap.add_argument("--seed", type=int, default=0)
    a = ap.parse_args()
    warnings.simplefilter("ignore")
    t0 = time.perf_counter()
    rows = false_claims(a.sets, a.seed)
    t1 = time.perf_counter()
    pw = power(a.power_seeds)
    t2 = time.perf_counter()
    p = np.array([r["p"] for r in rows])
    hist = np.histogram(p, BINS)[0]
    rand_claims = sum(r["random_p"] < SIGNIFICANCE for r in rows)
    out = {
        "alpha": SIGNIFICANCE, "min_effect": CONFIG.min_effect, "reference": CONFIG.reference,
        "regime_free": {"n_sets": len(rows), "false_claims": int(sum(r["claimed"] for r in rows)),
                        "false_claim_rate": float(np.mean([r["claimed"] for r in rows])),
                        "unreachable": int(sum(not r["reachable"] for r in rows)),
                        "false_claim_rate_vs_random_groups": rand_claims / len(rows),
                        "p_histogram": {"bins": BINS.tolist(), "counts": hist.tolist()},
                        "effect_quantiles_5_50_95": np.quantile([r["effect"] for r in rows],
                                                                [0.05, 0.5, 0.95]).round(4).tolist(),
                        "sets": rows},
        "power": {name: {"claim_rate": float(np.mean([r["claimed"] for r in v])),
                         "median_effect": float(np.median([r["effect"] for r in v])),
                         "median_agreement": float(np.median([r["agreement"] for r in v])),
                         "runs": v} for name, v in pw.items()},
        "seconds": {"regime_free": round(t1 - t0, 1), "power": round(t2 - t1, 1)},
    }
    print(json.dumps(out, indent=1))
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.figure import Figure
    fig = Figure(figsize=(7, 4))
    ax = fig.subplots()
    ax.bar(range(len(hist)), hist, color="tab:blue")
    ax.set_xticks(range(len(hist)), [f"{lo:g}–{hi:g}" for lo, hi in zip(BINS[:-1], BINS[1:])],
                  rotation=45, fontsize=7)
    ax.set_ylabel("data sets")
    ax.set_title(f"p-values on {len(rows)} regime-free data sets ({out['regime_free']['false_claims']} "
                 f"claims at p < {SIGNIFICANCE:g})", fontsize=9)
    fig.tight_layout()
    fig.savefig(a.png, dpi=110)


if __name__ == "__main__":
    main()
