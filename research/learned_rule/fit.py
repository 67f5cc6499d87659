"""The learned rule fitted to a teacher's levels: multinomial logistic regression (scikit-learn) on the
standardised features of :mod:`.features`, classes balanced (each level weighs as much in all as any other)."""

from __future__ import annotations

import numpy as np

from research.learned_rule.policy import LearnedRule


def fit_rule(X: np.ndarray, level: np.ndarray, n_modes: int, C: float = 1.0) -> LearnedRule:
    """The rule imitating ``level`` (N,) (each an authority level α) from features ``X`` (N, F). One level
    only gives the constant rule. ValueError on mismatched shapes, non-finite features or no rows."""
    from sklearn.linear_model import LogisticRegression

    X, level = np.asarray(X, dtype=float), np.asarray(level, dtype=float)
    if X.ndim != 2 or level.shape != (X.shape[0],) or X.shape[0] == 0:
        raise ValueError(f"fit_rule needs X (N, F) and level (N,) with N > 0, got {X.shape} and {level.shape}")
    if not np.all(np.isfinite(X)) or not np.all(np.isfinite(level)):
        raise ValueError("fit_rule: features and levels must be finite")
    alphas, y = np.unique(level, return_inverse=True)
    mean, scale = X.mean(axis=0), X.std(axis=0)
    scale = np.where(scale > 1e-12, scale, 1.0)
    if alphas.size == 1:
        return LearnedRule(alphas, mean, scale, np.zeros((1, X.shape[1])), np.zeros(1), n_modes)
    model = LogisticRegression(C=C, class_weight="balanced", max_iter=2000)
    model.fit((X - mean) / scale, y)
    coef, intercept = model.coef_, model.intercept_
    if alphas.size == 2:  # scikit-learn's binary model: one row for class 1; as softmax: [0, w]
        coef, intercept = np.vstack([np.zeros_like(coef), coef]), np.concatenate([[0.0], intercept])
    return LearnedRule(alphas, mean, scale, coef, intercept, n_modes)
