"""Scores of fitted per-mode gates on labelled rows: accuracy, F1 and Brier score.

``gate_metrics`` evaluates a fitted :class:`~learning.gates.gate.ModeGates` on (held-out)
windows with their modes and labels ``Z_t`` (1 = predictable), per mode and overall,
with scikit-learn's ``accuracy_score``, ``f1_score`` (of class 1) and ``brier_score_loss``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from sklearn.metrics import accuracy_score, brier_score_loss, f1_score
from sklearn.utils.validation import check_is_fitted

from learning.gates.gate import ModeGates, check_gate_inputs, check_gate_labels

__all__ = ["gate_metrics"]


def _scores(y: np.ndarray, p: np.ndarray, threshold: float) -> dict[str, Any]:
    n = int(y.size)
    if n == 0:
        return {"n": 0, "n_positive": 0, "accuracy": None, "f1": None, "brier": None}
    pred = (p >= threshold).astype(int)
    return {"n": n, "n_positive": int(y.sum()),
            "accuracy": float(accuracy_score(y, pred)),
            "f1": float(f1_score(y, pred, zero_division=0.0)),
            "brier": float(brier_score_loss(y, np.clip(p, 0.0, 1.0), pos_label=1))}


def gate_metrics(gates: ModeGates, windows: Any, modes: Any, labels: Any,
                 threshold: float = 0.5) -> dict[str, Any]:
    """Accuracy, F1 (of class 1 = predictable) and Brier score of the gates on (held-out) rows,
    per mode and overall, with counts. JSON-able; a mode without rows has None scores.

    Returns ``{"overall": {...}, "per_mode": {"0": {..., "constant": bool}, ...}}``.
    """
    check_is_fitted(gates, "gates_")
    X, m = check_gate_inputs(windows, modes, gates.n_modes_, gates.n_features_in_)
    y = check_gate_labels(labels, X.shape[0])
    p = gates.predict_proba(X, m) if X.shape[0] else np.zeros(0)
    per_mode = {}
    for j in range(gates.n_modes_):
        sel = m == j
        per_mode[str(j)] = {**_scores(y[sel], p[sel], threshold), "constant": j in gates.constant_modes_}
    return {"overall": _scores(y, p, threshold), "per_mode": per_mode, "threshold": float(threshold)}
