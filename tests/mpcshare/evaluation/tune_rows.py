"""One row of ``tune.json`` for the tests of the sweep's statistics and report."""

from __future__ import annotations


def tune_row(strategy, seed, trial, rmse, matched_to=None, effort=0.1):
    return {"strategy": strategy, "matched_to": matched_to, "percentile": 90.0, "beta": 0.5, "trial": trial,
            "seed": seed, "tracking_rmse_m": rmse, "voluntary_effort": effort, "handovers": 1 + seed}
