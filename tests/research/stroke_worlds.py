"""Small worlds of per-step figures with stroke terms, for the splice searches' tests."""

from __future__ import annotations

import numpy as np


def stroke_world(seed: int, runs: int = 3, steps: int = 48, groups: int = 6):
    """(e², effort, group labels, b·b*, ‖b‖², Y) of runs whose stroke terms differ: run 0 (the wearer) saws
    well at high effort, the others less."""
    rng = np.random.default_rng(seed)
    e2 = rng.gamma(2.0, 1e-5, (runs, steps)) * rng.uniform(0.3, 3.0, (runs, 1))
    effort = rng.gamma(2.0, 0.02, (runs, steps)) * np.linspace(2.0, 0.3, runs)[:, None]
    labels = np.repeat(np.arange(groups), steps // groups)
    cutting = rng.random(steps) < 0.6
    intent = rng.normal(0, 1e-2, (steps, 2))
    gains = np.linspace(1.0, 0.1, runs)
    tips = [g * intent + rng.normal(0, 6e-3, (steps, 2)) for g in gains]
    dot = np.stack([np.where(cutting, np.sum(t * intent, axis=1), 0.0) for t in tips])
    power = np.stack([np.where(cutting, np.sum(t**2, axis=1), 0.0) for t in tips])
    return e2, effort, labels, dot, power, float(np.sum(intent[cutting] ** 2))
