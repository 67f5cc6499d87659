"""Skill scores of the control-rate forecast: checked against a direct computation, and written to training.md."""

from __future__ import annotations

import numpy as np

from mpcshare.reports.training import skill_lines, training_markdown
from mpcshare.training.fast import FastRows, preview_skill, skill_table


def _rows(n: int = 200, H1: int = 4, seed: int = 0):
    rng = np.random.default_rng(seed)
    truth = np.cumsum(rng.normal(size=(n, H1, 3)), axis=1)
    F = truth + 0.3 * rng.normal(size=truth.shape)
    prev = np.arange(n) - 2
    prev[:2] = -1
    mode = rng.integers(0, 2, n)
    rows = FastRows(phi=np.zeros((n, 1)), slow=truth + rng.normal(size=truth.shape), truth=truth, mode=mode,
                    trial=np.zeros(n, int), prev=prev)
    return F, rows


def test_skill_equals_a_direct_computation():
    F, rows = _rows()
    scale = np.array([0.01, 0.02, 0.03])
    t = skill_table(F, rows, scale, 2, 0.1)
    keep = rows.prev >= 0
    Fm, Y = F[keep] * scale, rows.truth[keep] * scale
    now, before = Fm[:, 0], (F[rows.prev[keep], 0] * scale)
    h = np.arange(F.shape[1])[None, :, None]
    hold = np.repeat(now[:, None], F.shape[1], axis=1)
    cv = now[:, None] + h * (now - before)[:, None]

    def rmse(P):
        return np.sqrt(np.mean((P - Y) ** 2, axis=(0, 2)))

    np.testing.assert_allclose(t["rmse"]["forecast"], rmse(Fm), rtol=1e-12)
    np.testing.assert_allclose(t["skill"]["vs_hold"][1:], (1 - rmse(Fm) / rmse(hold))[1:], rtol=1e-12)
    np.testing.assert_allclose(t["skill"]["vs_constant_velocity"][1:], (1 - rmse(Fm) / rmse(cv))[1:], rtol=1e-12)
    assert t["skill"]["vs_hold"][1] > 0  # the forecast is the truth plus small noise: it beats the hold
    sel = rows.mode[keep] == 1
    m1 = t["by_mode"]["1"]
    assert m1["n_steps"] == int(sel.sum())
    np.testing.assert_allclose(m1["rmse"]["hold"], np.sqrt(np.mean((hold[sel] - Y[sel]) ** 2, axis=(0, 2))))
    gate = preview_skill(t, 2)
    assert gate.shape == (2, F.shape[1]) and np.all(gate[:, 0] == 0)
    np.testing.assert_allclose(gate[1, 1:], m1["skill"]["vs_hold"][1:])


def test_training_md_has_the_skill_tables():
    F, rows = _rows()
    fast = skill_table(F, rows, np.ones(3), 2, 0.1)
    lines = skill_lines(fast)
    assert any(line.startswith("| 0.1 |") for line in lines) and any(line.startswith("| 1 |") for line in lines)
    metrics = {"training": {"K": 2.0, "percentile": 90.0, "reactive_share_train": 0.9, "total_s": 12.0},
               "heldout_reactive_share": 0.88, "predictor": {"rmse_reactive": 0.1, "rmse_all": 0.2},
               "gate": {"overall": {"accuracy": 0.9, "f1": 0.9, "brier": 0.1}}, "fast_forecast": fast}
    md = training_markdown(metrics)
    assert "skill vs hold" in md and "Skill per mode" in md
    assert "not trained" in training_markdown({**metrics, "fast_forecast": None})
