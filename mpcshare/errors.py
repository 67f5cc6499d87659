"""The project's errors: :class:`MpcshareError`, the root of mpcshare's, and :data:`PROJECT_ERRORS`.

The layering (docs/design.md, checked by a test) lets no module be imported by all four packages:
``learning`` and ``robot`` import nothing of the project, ``sim`` never imports
``mpcshare``. So each package has its own root, and every error class of the project
derives from exactly one of them (and from the built-in class callers already catch):

- ``learning.errors.LearningError``: ``DataFormatError``, ``AnalysisError``;
- ``robot.errors.RobotError``: ``ControllerConfigError`` (``FrameNotFoundError``,
  ``UnsupportedModelError``);
- ``sim.errors.SimError``: ``WearerError``, ``WearerConfigError``;
- :class:`MpcshareError`: ``ControllerSetupError`` (``ControllerTypeError``), ``TrainingError``,
  ``BundleError``, ``CommandError``, ``RayMissing``.

``except PROJECT_ERRORS`` catches every error the project raises on purpose.
This module imports nothing heavy: the online controller imports it.
"""

from __future__ import annotations

from learning.errors import LearningError
from robot.errors import RobotError
from sim.errors import SimError

__all__ = ["PROJECT_ERRORS", "ControllerSetupError", "ControllerTypeError", "MpcshareError"]


class MpcshareError(Exception):
    """Root of mpcshare's errors (the product: controller, bundles, training, commands)."""


class ControllerSetupError(MpcshareError, ValueError):
    """Misuse at the construction of the shared controller: channels, strategy, β, settings, learned parts."""


class ControllerTypeError(ControllerSetupError, TypeError):
    """An argument of the shared controller of the wrong kind (the message names the expected one)."""


#: every root: ``except PROJECT_ERRORS`` catches all errors the project raises on purpose
PROJECT_ERRORS: tuple[type[Exception], ...] = (MpcshareError, LearningError, RobotError, SimError)
