"""The arbitration strategies, one module each, in one registry.

``from mpcshare.control.strategies import REGISTRY``: an ordered mapping name →
:class:`~mpcshare.control.strategies.base.StrategySpec` (``name``, ``description``, ``tunable``,
``color``, ``factory``, ``user``, ``order``, ``role``). Every module of this package except ``base`` is
imported here and contributes its ``SPECS`` (a tuple of specs); the registry is ordered by
``order``. Adding a strategy is one module with ``SPECS`` (and its test): the Arbiter, the
command line, ``tune``, the reports and the plots read the registry.

Strategies (their modules hold the equations and sources): ``voluntary``, ``reactive``
(:mod:`.fixed`); ``mix25``, ``mix50``, ``mix75`` (:mod:`.mix`); ``gate`` (the default shared
strategy, :mod:`.gate`); ``paper_gate`` (Song & Asada, :mod:`.paper_gate`); ``blend``
(:mod:`.blend`); ``schedule`` (a replayed schedule, not a user's choice, :mod:`.replay`).
"""

from __future__ import annotations

import importlib
import pkgutil
from types import MappingProxyType
from typing import Mapping

from mpcshare.control.strategies.base import (
    ROLES,
    ArbiterView,
    Policy,
    StepInputs,
    StrategyContext,
    StrategySpec,
    Target,
)

__all__ = ["DEFAULT_STRATEGY", "REGISTRY", "ROLES", "ArbiterView", "Policy", "StepInputs", "StrategyContext",
           "StrategySpec", "Target", "by_role", "user_strategies"]

#: The default shared strategy.
DEFAULT_STRATEGY = "gate"


def _discover() -> Mapping[str, StrategySpec]:
    specs: list[StrategySpec] = []
    for info in pkgutil.iter_modules(__path__):
        if info.name == "base" or info.name.startswith("_"):
            continue
        module = importlib.import_module(f"{__name__}.{info.name}")
        found = getattr(module, "SPECS", None)
        if not isinstance(found, tuple) or not all(isinstance(s, StrategySpec) for s in found):
            raise TypeError(f"strategy module {module.__name__} must define SPECS, a tuple of StrategySpec")
        specs += found
    names = [s.name for s in specs]
    dup = sorted({n for n in names if names.count(n) > 1})
    if dup:
        raise ValueError(f"strategies registered twice: {dup}")
    return MappingProxyType({s.name: s for s in sorted(specs, key=lambda s: (s.order, s.name))})


REGISTRY: Mapping[str, StrategySpec] = _discover()


def user_strategies() -> tuple[str, ...]:
    """The names a user may choose (every registered strategy but replays such as ``schedule``)."""
    return tuple(n for n, s in REGISTRY.items() if s.user)


def by_role(role: str) -> tuple[str, ...]:
    """The registered strategies of ``role`` (one of :data:`ROLES`), in registry order. Raises ValueError
    for another role."""
    if role not in ROLES:
        raise ValueError(f"role {role!r} is not one of {', '.join(ROLES)}")
    return tuple(n for n, s in REGISTRY.items() if s.role == role)
