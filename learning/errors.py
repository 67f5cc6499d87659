"""The root of the errors ``learning`` raises on purpose: :class:`LearningError`.

``learning`` imports no other package of the project (tests/test_layering.py), so it has
its own root, like ``robot.errors.RobotError`` and ``sim.errors.SimError``;
``mpcshare.errors.PROJECT_ERRORS`` catches all of them (docs/design.md, "Errors"). Each
error also derives from the built-in class callers already catch (ValueError).
"""

from __future__ import annotations

__all__ = ["LearningError"]


class LearningError(Exception):
    """Root of the errors of the data format, the analysis and the learned models."""
