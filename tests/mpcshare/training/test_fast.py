"""Skill scores of the control-rate forecast (mpcshare.training.fast), checked against a direct computation."""

from __future__ import annotations

import numpy as np

from mpcshare.training.fast import preview_skill, skill_table
from tests.mpcshare.training.fast_rows import fast_rows as _rows


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
