"""The learned rule in the arbiter, and a log of its features under any other policy.

:class:`LearnedRule`: class probabilities p = softmax(W·(x − μ)/σ + b) over authority levels α_c (0: the
wearer leads; in [0.5, 1]: the robot leads at that share), x the features of :mod:`.features`.
:class:`ImitationPolicy` evaluates it every ``period_s`` and moves to the most probable level c* from the
current c only when p_c* − p_c ≥ ``margin`` and the current level has been held ``min_dwell_s``; α then
moves along the hand-over ramp as the ``schedule`` replay's does (β = 1 − α for a share in [0.5, 1)), no
safety overrides (as the replay the rule imitates). :class:`FeatureLog` wraps any policy and records the
features per step; :func:`controller_with` builds a ``SharedController`` for
:func:`mpcshare.evaluation.episode.simulate_episode` whose arbiter runs a given policy.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from research.learned_rule.features import OnlineFeatures


@dataclass(frozen=True)
class LearnedRule:
    """The fitted model: ``alphas`` (C,) the level of each class, ``mean``/``scale`` (F,) the standardisation,
    ``coef`` (C, F), ``intercept`` (C,), ``n_modes`` the posterior's size the features assume."""

    alphas: np.ndarray
    mean: np.ndarray
    scale: np.ndarray
    coef: np.ndarray
    intercept: np.ndarray
    n_modes: int

    def __post_init__(self) -> None:
        c, f = np.shape(self.coef)
        if np.shape(self.alphas) != (c,) or np.shape(self.intercept) != (c,) or np.shape(self.mean) != (f,) \
                or np.shape(self.scale) != (f,) or np.any(np.asarray(self.scale) <= 0):
            raise ValueError(f"LearnedRule: coef {np.shape(self.coef)} needs alphas and intercept ({c},), mean and "
                             f"scale ({f},) with scale > 0; got {np.shape(self.alphas)}, {np.shape(self.intercept)}, "
                             f"{np.shape(self.mean)}, {np.shape(self.scale)}")
        a = np.asarray(self.alphas)
        if np.any(~((a == 0.0) | ((a >= 0.5) & (a <= 1.0)))):
            raise ValueError(f"LearnedRule: each level must be 0 or in [0.5, 1], got {a.tolist()}")

    def proba(self, x: np.ndarray) -> np.ndarray:
        """Class probabilities of feature rows ``x`` (N, F) or one row (F,)."""
        z = ((np.asarray(x, dtype=float) - self.mean) / self.scale) @ np.asarray(self.coef).T + self.intercept
        z = z - z.max(axis=-1, keepdims=True)
        e = np.exp(z)
        return e / e.sum(axis=-1, keepdims=True)

    def to_json(self) -> dict[str, Any]:
        """The parameters as lists."""
        return {k: np.asarray(getattr(self, k)).tolist() for k in ("alphas", "mean", "scale", "coef", "intercept")} \
            | {"n_modes": self.n_modes}


class ImitationPolicy:
    """The learned rule with hysteresis (module docstring); ``log``: a list that gets (t, features, α target)
    per step."""

    overrides = False

    def __init__(self, rule: LearnedRule, period_s: float = 0.1, margin: float = 0.1, min_dwell_s: float = 1.0,
                 log: list[tuple[float, np.ndarray, float]] | None = None) -> None:
        if not (period_s > 0 and 0 <= margin < 1 and min_dwell_s >= 0):
            raise ValueError(f"ImitationPolicy needs period_s > 0, 0 <= margin < 1, min_dwell_s >= 0; got "
                             f"{period_s}, {margin}, {min_dwell_s}")
        self.rule, self.period_s, self.margin, self.min_dwell_s = rule, period_s, margin, min_dwell_s
        self.features = OnlineFeatures(rule.n_modes)
        self.log = log
        self.reset()

    def reset(self) -> None:
        """Start with the wearer leading (the arbiter's α 0) or the level nearest 0."""
        self.features.reset()
        self._level = int(np.argmin(np.asarray(self.rule.alphas)))
        self._held_since = -np.inf
        self._next = -np.inf

    def decide(self, t: float, inputs: Any, arbiter: Any) -> Any:
        from mpcshare.control.strategies.base import Target

        x = self.features.update(t, inputs)
        if t >= self._next:
            self._next = t + self.period_s
            p = self.rule.proba(x)
            best = int(np.argmax(p))
            if best != self._level and p[best] - p[self._level] >= self.margin \
                    and t - self._held_since >= self.min_dwell_s:
                self._level, self._held_since = best, t
            elif not np.isfinite(self._held_since):
                self._held_since = t
        a = float(self.rule.alphas[self._level])
        if self.log is not None:
            self.log.append((float(t), x.copy(), a))
        return Target(a, f"learned rule: level {a:g}", ramp=True, beta=1.0 - a if 0.5 <= a < 1.0 else None)


class FeatureLog:
    """Any policy, its features logged per step as (t, features, the policy's α target)."""

    def __init__(self, policy: Any, n_modes: int, log: list[tuple[float, np.ndarray, float]]) -> None:
        self.policy, self.features, self.log = policy, OnlineFeatures(n_modes), log
        self.overrides = policy.overrides

    def reset(self) -> None:
        """Restart the policy and the features."""
        self.features.reset()
        self.policy.reset()

    def decide(self, t: float, inputs: Any, arbiter: Any) -> Any:
        x = self.features.update(t, inputs)
        target = self.policy.decide(t, inputs, arbiter)
        self.log.append((float(t), x.copy(), float(target.alpha)))
        return target


def controller_with(base: str, wrap: Callable[[Any], Any]) -> Callable[..., Any]:
    """A ``make_controller``: a ``SharedController`` built for strategy ``base`` (its options, e.g. a
    ``schedule``, as given), whose arbiter's policy is then replaced by ``wrap(the built policy)``."""

    def make(bundle: Any, **options: Any) -> Any:
        from mpcshare.control.controller import SharedController

        ctl = SharedController.from_bundle(bundle, **{**options, "strategy": base})
        ctl.arbiter.policy = wrap(ctl.arbiter.policy)
        ctl.arbiter.reset()
        return ctl

    return make


def log_arrays(log: list[tuple[float, np.ndarray, float]], times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(features (N, F), α target (N,)) at each of an episode's step ``times``: the last logged step at or
    before each (the arbiter decides once per step; RuntimeError when the log is empty)."""
    if not log:
        raise RuntimeError("no step was logged: the policy never decided")
    t = np.array([r[0] for r in log])
    k = np.clip(np.searchsorted(t, np.asarray(times, dtype=float) + 1e-9, side="right") - 1, 0, t.size - 1)
    return np.stack([log[i][1] for i in k]), np.array([log[i][2] for i in k])
