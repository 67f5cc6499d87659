"""The root of the errors ``sim`` raises on purpose: :class:`SimError`.

``sim`` cannot import ``mpcshare`` (tests/test_layering.py), so it has its own root,
like ``learning.errors.LearningError`` and ``robot.errors.RobotError``;
``mpcshare.errors.PROJECT_ERRORS`` catches all of them (docs/design.md, "Errors").
Each error also derives from the built-in class callers already catch (ValueError,
TypeError).
"""

from __future__ import annotations

__all__ = ["SimError", "WearerConfigError", "WearerError"]


class SimError(Exception):
    """Root of the simulation's errors."""


class WearerError(SimError, TypeError):
    """A wearer (or wearer factory) that does not follow :class:`sim.wearer_protocol.Wearer`."""


class WearerConfigError(SimError, ValueError):
    """Invalid settings of :class:`sim.wearer.SimulatedWearer` or its intent (the message names which)."""
