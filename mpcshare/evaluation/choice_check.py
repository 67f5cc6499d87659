"""The closed-loop choice's prediction of its rule beside what an evaluation realises.

The choice (:mod:`mpcshare.calibration.rule_choice`) records in the bundle's rule (``rule.choice["predicted"]``)
the chosen candidate's figures on its own trials: line ratio, effort (× the wearer alone), tracking RMS [m],
mean stroke correlation while cutting and whether it saws; and, with two choice trials or more, its line ratio
left one trial out (``rule.choice["cross_validated"]``: the rule chosen on the other trials, scored on the one
left out). :func:`choice_check` sets them beside the pooled figures of the evaluation's run of the rule's
strategy, and flags the line ratio when |realised − predicted| > :data:`LINE_RATIO_TOLERANCE`, where the
predicted line ratio is the one left one trial out when there is one (the figure on the trials the rule was
chosen on is the least of many candidates' on them, so it is biased low), else the one on the choice trials.
Pure: no simulation.
"""

from __future__ import annotations

import math
from typing import Any, Mapping, Sequence

__all__ = ["LINE_RATIO_TOLERANCE", "choice_check", "rule_run"]

#: the gap in line ratio, realised − predicted, beyond which the check says the two differ (issue target)
LINE_RATIO_TOLERANCE = 0.1


def _finite(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool) and math.isfinite(x)


def rule_run(strategy: str, runs: Sequence[Mapping[str, Any]]) -> str | None:
    """The name of the run that runs the rule: the plain run (no oracle, no schedule) of ``strategy``, the one
    named after it first; None when there is none. ``runs``: the evaluation's runs as dicts
    (:class:`mpcshare.run_table.StrategyRun` fields)."""
    plain = [r["name"] for r in runs if r.get("strategy") == strategy and not r.get("oracle")
             and not r.get("schedule")]
    return strategy if strategy in plain else (plain[0] if plain else None)


def choice_check(rule: Any, strategies: Mapping[str, Mapping[str, Any]],
                 runs: Sequence[Mapping[str, Any]]) -> dict[str, Any] | None:
    """``{"run", "strategy", "predicted", "realised", "cross_validated_line_ratio", "basis", "line_ratio_gap",
    "differs"}``
    for the bundle's ``rule`` (a :class:`~mpcshare.bundle.rule.CalibratedRule` or None) against the evaluation's
    pooled ``strategies`` (run name → metrics, with ``line_ratio``) and its ``runs``. ``predicted`` and
    ``realised`` hold ``line_ratio``, ``effort_vs_voluntary``, ``tracking_rmse_m`` and ``saw_correlation`` (None
    where undefined; ``predicted``: on the choice trials); ``cross_validated_line_ratio``: the choice's
    leave-one-trial-out prediction (``rule.choice["cross_validated"]``; None where it has none); ``basis``:
    ``"left one trial out"`` where there is one, else ``"choice trials"``; ``line_ratio_gap`` = realised − the
    line ratio of ``basis`` (None where either is undefined); ``differs``: the gap's size exceeds
    :data:`LINE_RATIO_TOLERANCE`. None without a rule, a recorded prediction or a run of its strategy."""
    predicted = None if rule is None else (getattr(rule, "choice", None) or {}).get("predicted")
    name = None if not predicted else rule_run(rule.strategy, runs)
    if name is None or name not in strategies:
        return None
    m, alone = strategies[name], strategies.get("voluntary") or {}
    effort = m.get("voluntary_effort")
    realised = {"line_ratio": m.get("line_ratio"),
                "effort_vs_voluntary": effort / alone["voluntary_effort"]
                if _finite(effort) and _finite(alone.get("voluntary_effort")) and alone["voluntary_effort"] > 0
                else None,
                "tracking_rmse_m": m.get("tracking_rmse_m"), "saw_correlation": m.get("saw_correlation")}
    keys = ("line_ratio", "effort_vs_voluntary", "tracking_rmse_m", "saw_correlation")
    realised = {k: float(realised[k]) if _finite(realised[k]) else None for k in keys}
    guess = {k: float(predicted[k]) if _finite(predicted.get(k)) else None for k in keys}
    cv = (rule.choice.get("cross_validated") or {}).get("line_ratio")
    cv = float(cv) if _finite(cv) else None
    basis, line = ("left one trial out", cv) if cv is not None else ("choice trials", guess["line_ratio"])
    gap = realised["line_ratio"] - line if realised["line_ratio"] is not None and line is not None else None
    return {"run": name, "strategy": rule.strategy, "predicted": guess, "realised": realised,
            "cross_validated_line_ratio": cv, "basis": basis,
            "line_ratio_gap": gap, "differs": gap is not None and abs(gap) > LINE_RATIO_TOLERANCE}
