"""Tests of learning.gates.metrics: the gates' accuracy, F1 and Brier score per mode and overall."""

from __future__ import annotations

import pytest
from sklearn.metrics import accuracy_score, brier_score_loss, f1_score

from learning.gates.gate import ModeGates
from learning.gates.metrics import gate_metrics
from tests.learning.gates.test_gate import separable


def test_gate_metrics_match_sklearn_and_count():
    X, m, y = separable(1200, seed=9, noise=0.1)
    g = ModeGates().fit(X, m, y, 4)  # mode 3 empty → constant 0
    Xt, mt, yt = separable(600, seed=10, noise=0.1)
    res = gate_metrics(g, Xt, mt, yt)
    p = g.predict_proba(Xt, mt)
    assert res["overall"]["n"] == 600 and res["overall"]["n_positive"] == int(yt.sum())
    assert res["overall"]["accuracy"] == pytest.approx(accuracy_score(yt, p >= 0.5))
    assert res["overall"]["f1"] == pytest.approx(f1_score(yt, p >= 0.5))
    assert res["overall"]["brier"] == pytest.approx(brier_score_loss(yt, p))
    sel = mt == 1
    assert res["per_mode"]["1"]["brier"] == pytest.approx(brier_score_loss(yt[sel], p[sel]))
    assert sum(r["n"] for r in res["per_mode"].values()) == 600
    assert res["per_mode"]["3"] == {"n": 0, "n_positive": 0, "accuracy": None, "f1": None,
                                    "brier": None, "constant": True}
