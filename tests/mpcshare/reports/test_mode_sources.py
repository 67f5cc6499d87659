"""HMM against mixture modes for the controller (mpcshare.reports.mode_sources): the figures, the sentence,
the demo's summary."""

from dataclasses import replace

import numpy as np

from mpcshare.training.config import TrainConfig
from sim.demonstrator import GeneratorConfig, generate_demonstrations


def test_the_demo_compares_hmm_and_mixture_modes_for_the_controller():
    from mpcshare.reports.demo import demo_summary
    from mpcshare.reports.mode_sources import mode_source_comparison, mode_source_sentence
    from mpcshare.training import train_bundle

    demos = generate_demonstrations(2, 1.5, seed=1, config=GeneratorConfig(trial_minutes=0.5))
    small = TrainConfig(percentile=80, n_modes=3, hmm_restarts=1, max_epochs=2, patience=1, gate_max_samples=200)
    bundles = {src: train_bundle(demos, replace(small, modes_from=src), progress=False) for src in ("hmm", "mixture")}
    cmp = mode_source_comparison(bundles)
    for src, b in bundles.items():
        assert cmp[src]["voluntary_share"] == b.metrics["voluntary_share"]
        assert cmp[src]["gate_accuracy"] == b.metrics["gate"]["overall"]["accuracy"]
        assert 0 < cmp[src]["filter_step_us"] < 1e5
    # the gates alone (mpcshare.training.train_gates) give the same figures: the demo compares without training a
    # second predictor
    from mpcshare.training import train_gates
    for src, b in bundles.items():
        fit = train_gates(demos, replace(small, modes_from=src))
        assert (fit.voluntary_share, fit.gate_accuracy, fit.K) == (
            b.metrics["voluntary_share"], b.metrics["gate"]["overall"]["accuracy"], b.K)
        assert np.array_equal(fit.modes.transmat_, b.modes.transmat_)
        gates_only = mode_source_comparison({src: fit})[src]
        assert (gates_only["voluntary_share"], gates_only["gate_accuracy"]) == (
            cmp[src]["voluntary_share"], cmp[src]["gate_accuracy"])
    s = mode_source_sentence(cmp)
    assert f"{100 * cmp['mixture']['voluntary_share']:.1f} % of the held-out time" in s
    assert f"(HMM {100 * cmp['hmm']['gate_accuracy']:.1f} %)" in s
    # the demo's summary carries the sentence when the comparison was made
    seg = {"n_trials": 12, "reachable": True, "min_trials": 10, "alpha": 1e-3, "reference": "gmm",
           "hmm_median_q": 2.0, "random_median_q": 4.0, "reference_median_q": 2.1, "claims": {
               k: {"name": k, "compared": "x", "p_value": 1.0, "effect_size": 0.0, "made": made, "min_effect": 0.1,
                   "ci": {"low": 0.0, "high": 0.0, "level": 0.95}}
               for k, made in (("modes_help", True), ("temporal_model_adds", False))}}
    analysis = {"quotients": {"p50": 4.0, "p90": 8.0}, "modes": {"n_modes": 3}, "segmentation_test": seg}
    lines = demo_summary(analysis, bundles["hmm"].metrics, None, cmp)
    assert s in lines and any("--modes-from mixture" in x for x in lines)
    assert s not in demo_summary(analysis, bundles["hmm"].metrics, None)
