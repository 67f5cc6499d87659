"""The bundle's calibrated hand-over rule: which strategy it is for, its settings, and the calibration's record.

:class:`CalibratedRule` is written by the calibration (:mod:`mpcshare.calibration.rule_choice`) and read by the
controller, which builds the strategy's typed settings from it (its registry spec's ``settings`` class; an
unknown or invalid field raises there, naming it). Where the calibration was skipped, the rule says why
(``skipped``, :func:`skipped_rule`) and has no settings: the strategy runs with its defaults. It is stored in
``rule.json`` as ``{"rule": null}`` or ``{"rule": {"version", "strategy", "settings", "choice", "skipped"}}``;
``settings`` maps a field name to a JSON number, a list of them, or null; version 1 has no ``skipped``. Bundles of
format 1 and 2 kept it in ``metrics.json`` (keys ``rule_settings`` and ``rule_choice``, always for ``gate``), and
bundles until rule version 2 the reason of a skipped choice (``rule_choice_skipped``): :func:`rule_from_metrics`
moves them from there when such a bundle is loaded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Mapping

__all__ = ["RULE_VERSION", "CalibratedRule", "rule_from_json", "rule_from_metrics", "rule_to_json", "skipped_rule"]

#: Version of :class:`CalibratedRule`'s layout (2: ``skipped``); the versions :func:`rule_from_json` reads are 1 to it.
RULE_VERSION = 2


def _check_value(name: str, value: Any) -> Any:
    """A setting's value as stored: a finite number, a tuple of them, or None; ValueError naming ``name``."""
    if value is None:
        return None
    if isinstance(value, (list, tuple)):
        return tuple(_check_value(name, v) for v in value)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"rule setting {name!r} must be a finite number, a list of them or null, got {value!r}")
    return value


@dataclass(frozen=True)
class CalibratedRule:
    """strategy: the registry name the settings are for; settings: field → value of that strategy's settings
    (finite numbers, tuples of them, None); choice: the calibration's JSON record (every candidate's figures,
    why); version: :data:`RULE_VERSION`; skipped: None, or why the calibration was skipped (then no settings and no
    choice: the strategy's defaults). ValueError naming a wrong field."""

    strategy: str
    settings: Mapping[str, Any]
    choice: Mapping[str, Any] = field(default_factory=dict)
    version: int = RULE_VERSION
    skipped: str | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.strategy, str) or not self.strategy:
            raise ValueError(f"rule strategy must be a strategy's name, got {self.strategy!r}")
        if not isinstance(self.settings, Mapping) or not all(isinstance(k, str) for k in self.settings):
            raise ValueError(f"rule settings must map field names to values, got {self.settings!r}")
        if not isinstance(self.choice, Mapping):
            raise ValueError(f"rule choice must be a JSON object, got {type(self.choice).__name__}")
        if not isinstance(self.version, int) or not 1 <= self.version <= RULE_VERSION:
            raise ValueError(f"rule version {self.version!r}; this mpcshare reads versions 1 to {RULE_VERSION}")
        if self.skipped is not None and (not isinstance(self.skipped, str) or not self.skipped):
            raise ValueError(f"rule skipped must be null or why the calibration was skipped, got {self.skipped!r}")
        if self.skipped is not None and (self.settings or self.choice):
            raise ValueError("a skipped rule has no settings and no choice (the strategy's defaults run)")
        object.__setattr__(self, "settings", {k: _check_value(k, v) for k, v in self.settings.items()})


def skipped_rule(why: str, strategy: str = "gate") -> CalibratedRule:
    """The rule of a calibration that was skipped, ``why`` (one line): ``strategy`` keeps its default settings."""
    return CalibratedRule(strategy, {}, {}, skipped=why)


def rule_to_json(rule: CalibratedRule | None) -> dict[str, Any]:
    """``{"rule": null}`` or the rule as JSON (tuples as lists)."""
    if rule is None:
        return {"rule": None}
    settings = {k: list(v) if isinstance(v, tuple) else v for k, v in rule.settings.items()}
    return {"rule": {"version": rule.version, "strategy": rule.strategy, "settings": settings,
                     "choice": dict(rule.choice), "skipped": rule.skipped}}


def rule_from_json(d: Any) -> CalibratedRule | None:
    """The inverse of :func:`rule_to_json`; ValueError naming what is wrong."""
    if not isinstance(d, dict) or "rule" not in d:
        raise ValueError("expected a JSON object with key 'rule'")
    r = d["rule"]
    if r is None:
        return None
    if not isinstance(r, dict):
        raise ValueError(f"'rule' must be null or an object, got {type(r).__name__}")
    missing = [k for k in ("version", "strategy", "settings") if k not in r]
    if missing:
        raise ValueError(f"'rule' lacks {missing}")
    return CalibratedRule(r["strategy"], r["settings"], r.get("choice") or {}, r["version"], r.get("skipped"))


def rule_from_metrics(metrics: dict[str, Any]) -> CalibratedRule | None:
    """The migration of an older bundle: its ``metrics["rule_settings"]`` (the gate's) and
    ``metrics["rule_choice"]`` (formats 1 and 2), or its ``metrics["rule_choice_skipped"]`` (why the choice was
    skipped), removed from ``metrics`` and returned as a rule (None when it has none)."""
    settings = metrics.pop("rule_settings", None)
    choice = metrics.pop("rule_choice", None)
    skipped = metrics.pop("rule_choice_skipped", None)
    if settings is not None:
        return CalibratedRule("gate", settings, choice or {}, 1)
    return None if skipped is None else skipped_rule(str(skipped))
