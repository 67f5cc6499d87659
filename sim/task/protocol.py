"""What a task is to the simulator, the reports and the commands: :class:`Task`.

A task (dm_control style) is one object that carries everything specific to what the wearer and the
robot do together: the names and colours of its modes, the mode whose strokes are judged, its
success criterion, its figures per episode, the wearer's body zones and the shoulder map's layout.
The machinery it fills in is generic (:mod:`sim.task.metrics`, :mod:`robot.wearer_body`,
:mod:`robot.shoulder`); :mod:`sim.task.eating` is the task shipped.
"""

from __future__ import annotations

from typing import Any, Mapping, Protocol, Sequence, runtime_checkable

import numpy as np

from robot.shoulder import ShoulderMap
from robot.wearer_body import WearerBody

__all__ = ["Task"]


@runtime_checkable
class Task(Protocol):
    """A task the controller assists in (module docstring).

    Attributes:
        name: the task's name (its module's, ``sim.task.<name>``).
        mode_names: the data format's mode labels: label k is ``mode_names[k]``.
        mode_colours: mode name → colour (``#RRGGBB``), one in every plot and the video.
        stroke_mode: the mode whose strokes are judged (:meth:`episode_metrics`); None: none.
        stroke_band_hz: (low, high) [Hz], the band the strokes are judged in; None without a stroke mode.
        criterion: when the task is done right, in words (every report states it so).
        metric_keys: the keys of :meth:`episode_metrics`.
        body: the wearer's body zones: sizes, anchors [m] and speed caps [m/s].
        shoulder_channels: the roles of the voluntary channels, in the column order of ``shoulder_to_plate``.
        shoulder_to_plate: P (3, len(shoulder_channels)), plate axes × channel roles (read-only).
    """

    name: str
    mode_names: tuple[str, ...]
    mode_colours: Mapping[str, str]
    stroke_mode: str | None
    stroke_band_hz: tuple[float, float] | None
    criterion: str
    metric_keys: tuple[str, ...]
    body: WearerBody
    shoulder_channels: tuple[str, ...]
    shoulder_to_plate: np.ndarray

    def episode_metrics(self, tip: np.ndarray, intent: np.ndarray, dt: float, true_mode: np.ndarray | None,
                        mode_names: Sequence[str] | None = None, alpha: np.ndarray | None = None) -> dict[str, Any]:
        """The task's figures of one episode (keys :attr:`metric_keys`, JSON-able; None where undefined):
        tip and intent (N, 3) [m] every ``dt`` [s], the true mode labels (N,) or None, α (N,) or None."""
        ...

    def done(self, metrics: Mapping[str, Any]) -> bool:
        """Whether an episode's (or a pooled run's) figures meet :attr:`criterion`; False where undefined."""
        ...

    def shoulder_map(self, names: Sequence[str] = (), gain: float = 0.5, deadband_rad: float = 0.01) -> ShoulderMap:
        """The shoulder map of a sensor whose channels are ``names`` (:meth:`robot.shoulder.ShoulderMap.for_channels`
        with this task's roles and layout)."""
        ...
