"""Typed exceptions raised when the controller is misconfigured (never inside the loop)."""

from __future__ import annotations


class ControllerConfigError(ValueError):
    """Invalid controller configuration: shapes, limits, gains, solver name."""


class FrameNotFoundError(ControllerConfigError, KeyError):
    """The end-effector frame named for the controller does not exist in the model."""

    def __str__(self) -> str:  # KeyError would quote the message
        return str(self.args[0]) if self.args else ""


class UnsupportedModelError(ControllerConfigError):
    """The Pinocchio model has joints the controller cannot handle (nq ≠ nv)."""
