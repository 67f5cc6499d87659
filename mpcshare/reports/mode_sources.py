"""HMM task modes against the time-free mixture for the controller (``mpcshare train --modes-from``).

Where the analysis finds that modes help but the temporal model adds nothing, the demo also
trains a bundle on the mixture's modes and compares, on the same held-out trials: the
voluntary share (fraction of held-out windows the gate hands to the wearer), the gate's
accuracy against the quotient labels, and the online mode filter's cost (``ModeFilter.step``
[µs], median over ``n_steps`` observations drawn around the training data's mean, one
scale per channel as the model's scaler learnt).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

__all__ = ["filter_step_us", "mode_source_comparison", "mode_source_sentence"]


def filter_step_us(modes: Any, n_steps: int = 2000, seed: int = 0) -> float:
    """Median wall time of one online mode-filter step [µs] of a fitted ``TaskModes``."""
    rng = np.random.default_rng(seed)
    obs = modes.scaler_.mean_ + modes.scaler_.scale_ * rng.standard_normal((n_steps, modes.n_features_in_))
    f = modes.make_filter()
    times = np.empty(n_steps)
    for k, o in enumerate(obs):
        t0 = time.perf_counter()
        f.step(o)
        times[k] = time.perf_counter() - t0
    return float(1e6 * np.median(times))


def mode_source_comparison(sources: dict[str, Any]) -> dict[str, dict[str, float]]:
    """{source ("hmm", "mixture"): {voluntary_share, gate_accuracy, filter_step_us}}: each source a trained bundle
    (its held-out metrics) or a :class:`mpcshare.training.GateFit` (the same figures, without a predictor)."""
    def figures(b: Any) -> tuple[float, float]:
        if hasattr(b, "metrics"):
            return float(b.metrics["voluntary_share"]), float(b.metrics["gate"]["overall"]["accuracy"])
        return float(b.voluntary_share), float(b.gate_accuracy)

    out = {}
    for source, b in sources.items():
        share, accuracy = figures(b)
        out[source] = {"voluntary_share": share, "gate_accuracy": accuracy,
                       "filter_step_us": round(filter_step_us(b.modes), 2)}
    return out


def mode_source_sentence(cmp: dict[str, dict[str, float]]) -> str:
    """The comparison in one sentence (needs the keys ``"hmm"`` and ``"mixture"``)."""
    h, m = cmp["hmm"], cmp["mixture"]
    return (f"Trained on the time-free mixture's modes instead (`--modes-from mixture`), the gate hands "
            f"{100 * m['voluntary_share']:.1f} % of the held-out time to the wearer "
            f"(HMM {100 * h['voluntary_share']:.1f} %) "
            f"with accuracy {100 * m['gate_accuracy']:.1f} % (HMM {100 * h['gate_accuracy']:.1f} %); the online mode "
            f"filter takes {m['filter_step_us']:.0f} µs a step (HMM {h['filter_step_us']:.0f} µs).")
