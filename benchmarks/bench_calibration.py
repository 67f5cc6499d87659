"""Calibration study of the analysis's two claims (issues 13 and 22).

False claims: ≥ 50 regime-free data sets (``sim.regime_free.calibration_family``: linear
and nonlinear maps, latent dimension 1–5, noise levels, 6–20 trials of 1–2 min at 10 Hz)
through :func:`learning.analysis.analyze`, for both claims: "modes help" (``modes_help``:
one-sided Wilcoxon over trials against random groups of equal sizes, p < 0.001, effect >
``HELP_EFFECT``) and "the temporal model adds information" (``temporal_model_adds``: against
a time-free reference grouping and random groups, p < 0.001, effect > ln 1.1). Every reference
of :data:`learning.analysis.reference.REFERENCES` is tested on the same HMM modes, so the choice of
the default is made on these numbers. Power: data with hidden regimes against cue
strength — the default demonstrations (``sim.demonstrator``) and weaker-cue variants
(``overlap`` up, ``contrast`` down), 20 trials of 30 s; and three regimes that change
the action map while the observation shows them only through a weak cue
(``sim.hidden_regime``, cue/noise 0.25–2), 12 trials of 1 min.

Prints one JSON object (false-claim rate per reference, p-value histogram of the
default reference, claim rate per family and cue strength) and writes the p-value
histogram to the PNG path given. Progress goes to stderr.

    PYTHONPATH=. python benchmarks/bench_calibration.py calib_hist.png [--sets 50] [--power-seeds 5]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings

import numpy as np

from learning.analysis import SIGNIFICANCE, AnalysisConfig, analyze
from learning.analysis.reference import REFERENCES, reference_segmentation, trial_test
from learning.lipschitz import pointwise_quotients
from sim.demonstrator import GeneratorConfig, generate_demonstrations
from sim.hidden_regime import HiddenRegimeConfig, generate_hidden_regime
from sim.regime_free import calibration_family, generate_regime_free

CONFIG = AnalysisConfig(n_random=1, search_windows=(), search_modes=(), hmm_restarts=3)
BINS = np.array([0.0, 1e-3, 0.01, 0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0])
DEMO_CUES = [("default (overlap 0.6)", {}), ("overlap 0.75", {"overlap": 0.75}),
             ("overlap 0.9", {"overlap": 0.9}), ("overlap 0.97", {"overlap": 0.97}),
             ("contrast 0.75", {"contrast": 0.75}), ("contrast 0.3", {"contrast": 0.3})]
HIDDEN_CUES = (0.075, 0.15, 0.3, 0.6)  # against noise 0.3
CLAIMS = ("modes_help", "temporal_model_adds")  # the report's two claims (segmentation_test.claims)
KEYS = (*REFERENCES, "random", *CLAIMS)


def _tests(res) -> dict:
    """The claim's test against every reference, on the HMM modes of one analysis."""
    w, out = res.windows, {}
    t = res.summary.segmentation_test
    out[t.reference] = {"p": t.reference_p_value, "effect": round(t.effect_size, 4),
                        "claimed": bool(t.reachable and t.reference_p_value < SIGNIFICANCE
                                        and t.effect_size > t.min_effect)}
    F = res.mode_model.transform(res.features)
    for ref in REFERENCES:
        if ref in out:
            continue
        g = reference_segmentation(F, res.sample_modes, ref, CONFIG.seed)
        q = pointwise_quotients(w.X, w.Y, g[w.source_index])
        tt = trial_test(res.q_modes, q, w.trial, alpha=SIGNIFICANCE, min_effect=CONFIG.min_effect)
        out[ref] = {"p": tt.p_value, "effect": round(tt.effect, 4), "claimed": tt.claimed}
    rand = bool(t.reachable and t.random_p_value < SIGNIFICANCE and t.random_effect_size > t.min_effect)
    for v in out.values():  # the claim: beyond the reference and beyond random groups
        v["claimed"] = bool(v["claimed"] and rand)
    claims = {k: {"p": c.p_value, "effect": round(c.effect_size, 4), "claimed": c.made}
              for k, c in t.claims.items()}
    return {"n_trials": t.n_trials, "reachable": t.reachable, "agreement": res.summary.modes.agreement,
            "random": {"p": t.random_p_value, "effect": round(t.random_effect_size, 4), "claimed": rand},
            **out, **claims}


def _log(msg: str) -> None:
    print(msg, file=sys.stderr, flush=True)


def false_claims(n_sets: int, seed: int) -> list[dict]:
    rows = []
    for k, (cfg, data_seed) in enumerate(calibration_family(n_sets, seed)):
        r = _tests(analyze(generate_regime_free(cfg, data_seed), CONFIG))
        r.update(latent_dim=cfg.latent_dim, maps=f"{cfg.obs_map}/{cfg.act_map}",
                 obs_noise=round(cfg.obs_noise, 4))
        rows.append(r)
        _log(f"regime-free {k + 1}/{n_sets}: {r['maps']} m={cfg.latent_dim} trials={r['n_trials']} "
             + " ".join(f"{ref} p={r[ref]['p']:.2g} e={r[ref]['effect']}" for ref in REFERENCES))
    return rows


def power(seeds: int) -> dict[str, list[dict]]:
    out = {}
    for name, kw in DEMO_CUES:
        gen = GeneratorConfig(trial_minutes=0.5, **kw)
        out[f"demonstrations, {name}"] = v = [
            _tests(analyze(generate_demonstrations(2, 5, seed=100 + s, config=gen), CONFIG))
            for s in range(seeds)]
        _log(f"{name}: " + "; ".join(f"{ref} {sum(r[ref]['claimed'] for r in v)}/{len(v)}"
                                     for ref in KEYS))
    hidden = AnalysisConfig(**{**CONFIG.__dict__, "n_modes": 3, "scope": "channel"})
    for cue in HIDDEN_CUES:
        cfg = HiddenRegimeConfig(cue=cue)
        out[f"hidden regime, cue/noise {cue / cfg.noise:g}"] = v = [
            _tests(analyze(generate_hidden_regime(cfg, seed=200 + s), hidden)) for s in range(seeds)]
        _log(f"hidden cue {cue}: " + "; ".join(f"{ref} {sum(r[ref]['claimed'] for r in v)}/{len(v)}"
                                               for ref in KEYS))
    return out


def _rates(rows: list[dict]) -> dict:
    return {k: float(np.mean([r[k]["claimed"] for r in rows])) for k in KEYS}


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
    if not rows:
        raise SystemExit("--sets must be >= 1")
    t1 = time.perf_counter()
    pw = power(a.power_seeds) if a.power_seeds > 0 else {}
    t2 = time.perf_counter()
    ref = CONFIG.reference
    p = np.array([max(r[ref]["p"], r["random"]["p"]) for r in rows])  # p of the claim
    hist = np.histogram(p, BINS)[0]
    out = {
        "alpha": SIGNIFICANCE, "min_effect": CONFIG.min_effect, "default_reference": ref,
        "regime_free": {
            "n_sets": len(rows), "false_claim_rate": _rates(rows),
            "false_claims_default": int(sum(r[ref]["claimed"] for r in rows)),
            "false_claims": {k: int(sum(r[k]["claimed"] for r in rows)) for k in CLAIMS},
            "unreachable": int(sum(not r["reachable"] for r in rows)),
            "p_histogram_default": {"bins": BINS.tolist(), "counts": hist.tolist()},
            "p_histogram_by_claim": {k: np.histogram([r[k]["p"] for r in rows], BINS)[0].tolist() for k in CLAIMS},
            "effect_quantiles_5_50_95": {
                k: np.quantile([r[k]["effect"] for r in rows], [0.05, 0.5, 0.95]).round(4).tolist()
                for k in KEYS},
            "sets": rows},
        "power": {name: {"claim_rate": _rates(v),
                         "median_effect": {k: float(np.median([r[k]["effect"] for r in v])) for k in KEYS},
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
    ax.set_title(f"p-values ({ref} reference) on {len(rows)} regime-free data sets: "
                 f"{out['regime_free']['false_claims_default']} claims at p < {SIGNIFICANCE:g}", fontsize=9)
    fig.tight_layout()
    fig.savefig(a.png, dpi=110)


if __name__ == "__main__":
    main()
