"""One row of ``tune.json`` for the tests of the sweep's statistics and report, and the tiny sweep the tune
fixtures run."""

from __future__ import annotations


def tune_row(strategy, seed, trial, rmse, matched_to=None, effort=0.1, handovers=None):
    return {"strategy": strategy, "matched_to": matched_to, "percentile": 90.0, "beta": 0.5, "trial": trial,
            "seed": seed, "tracking_rmse_m": rmse, "voluntary_effort": effort,
            "handovers": 2 + seed if handovers is None else handovers}


#: the tiny sweep the tune fixtures run (tests/mpcshare/evaluation/conftest.py)
SWEEP = ["--percentiles", "90", "70", "--betas", "0", "1", "--strategies", "gate", "--trials", "1",
         "--duration", "2", "--seeds", "2", "--draws", "2", "--epochs", "3", "--quiet", "--workers", "1"]
