"""Typed exceptions raised when the controller is misconfigured (never inside the loop).

:class:`RobotError` is the root of the errors ``robot`` raises on purpose: ``robot`` imports
no other package of the project (tests/test_layering.py), so it has its own root, like
``learning.errors.LearningError`` and ``sim.errors.SimError``; ``mpcshare.errors.PROJECT_ERRORS``
catches all of them (docs/design.md, "Errors").
"""

from __future__ import annotations

__all__ = ["ControllerConfigError", "FrameNotFoundError", "RobotError", "UnsupportedModelError"]


class RobotError(Exception):
    """Root of the robot stack's errors (descriptions, QP, MPC)."""


class ControllerConfigError(RobotError, ValueError):
    """Invalid controller configuration: shapes, limits, gains, solver name."""


class FrameNotFoundError(ControllerConfigError, KeyError):
    """The end-effector frame named for the controller does not exist in the model."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class UnsupportedModelError(ControllerConfigError):
    """The Pinocchio model has joints the controller cannot handle (nq ≠ nv)."""
