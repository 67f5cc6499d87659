"""The task shipped: eating with a fork in the left hand while the SuperLimb holds the knife (:data:`TASK`).

**Modes** (the data format's labels, :data:`MODE_NAMES`): ``cutting`` (the fork holds the food, the
knife saws), ``repositioning``, ``collecting``, ``removing``; one colour each (:data:`MODE_COLOURS`).

**Sawing** is judged while cutting (:data:`STROKE_MODE`), in the stroke band 0.8–3 Hz
(:data:`STROKE_BAND_HZ`; the demonstrations saw at 1.6–2.6 Hz): the knife saws when its band
correlates with the intended stroke at ≥ 0.7 and reaches ≥ 0.6 of its amplitude (:func:`saws`).

**The body** (:data:`BODY`, sizes [m] the body part's own, the controller's margin on top): the hand a
4.5 cm sphere at the fork handle's upper end (a fist's half-breadth, hand breadth ≈ 0.09 m; Winter,
*Biomechanics and Motor Control of Human Movement*, 4th ed., table 4.1, for a 1.75 m adult); forearm
0.25 m long (0.146·H, Winter), radius 0.04; head radius 0.10 and trunk radius 0.14, as the scene draws
them. Speed caps toward a body part: 0.15 m/s (hand, forearm, torso) and 0.06 m/s (head and face), a
robot-assisted feeding system's figures away from and near the mouth (ADA, Nanavati et al., HRI 2024,
arXiv:2403.04134); a lost fork marker grows the hand and forearm zones at 2.0 m/s, ISO 13855's hand
and arm approach speed.

**The shoulder** (:data:`SHOULDER_CHANNELS`, :data:`SHOULDER_TO_PLATE`): the affected-side shoulder's
elevation → plate z, protraction → x (away from the wearer), abduction → y.
"""

from __future__ import annotations

from typing import Any, Mapping, Sequence

import numpy as np

from robot.shoulder import ShoulderMap
from robot.wearer_body import WearerBody

from .metrics import pickup_error, rms_by_mode, sawing_by_episode, sawing_fidelity, time_lag, wearer_share_by_mode

__all__ = ["BODY", "MODE_COLOURS", "MODE_NAMES", "METRIC_KEYS", "SAWING_CRITERION", "SAWING_MIN_AMPLITUDE",
           "SAWING_MIN_CORRELATION", "SHOULDER_CHANNELS", "SHOULDER_TO_PLATE", "STROKE_BAND_HZ", "STROKE_MODE",
           "TASK", "Eating", "episode_task_metrics", "saws"]

MODE_NAMES: tuple[str, ...] = ("cutting", "repositioning", "collecting", "removing")
#: one colour per mode, in every plot and the video
MODE_COLOURS: dict[str, str] = {"cutting": "#C44E52", "repositioning": "#4C72B0", "collecting": "#55A868",
                                "removing": "#DD8452"}
#: the mode whose strokes are judged
STROKE_MODE = "cutting"
STROKE_BAND_HZ = (0.8, 3.0)  # [Hz] the band of the sawing strokes
SAWING_MIN_CORRELATION = 0.7
SAWING_MIN_AMPLITUDE = 0.6
#: the sawing criterion in words, for every report and document that states it
SAWING_CRITERION = (f"a stroke correlation of at least {SAWING_MIN_CORRELATION:g} with the intended stroke and at "
                    f"least {SAWING_MIN_AMPLITUDE:g} of its amplitude, while cutting")

BODY = WearerBody(hand_offset=(-0.04, 0.07, 0.13), hand_radius=0.045, elbow=(0.10, 0.22, 0.28),
                  forearm_length=0.25, forearm_radius=0.04, head_center=(-0.03, 0.0, 0.80), head_radius=0.10,
                  torso_a=(-0.05, 0.0, 0.08), torso_b=(-0.05, 0.0, 0.55), torso_radius=0.14, hand_speed_cap=0.15,
                  head_speed_cap=0.06, hand_top_speed=2.0)

#: the roles of the shoulder channels, in the column order of :data:`SHOULDER_TO_PLATE`
SHOULDER_CHANNELS: tuple[str, ...] = ("shoulder_elevation", "shoulder_protraction", "shoulder_abduction")
#: rows: plate x, y, z; columns: elevation, protraction, abduction
SHOULDER_TO_PLATE = np.array([[0.0, 1.0, 0.0],
                              [0.0, 0.0, 1.0],
                              [1.0, 0.0, 0.0]])
SHOULDER_TO_PLATE.setflags(write=False)

#: keys of :func:`episode_task_metrics` (``comparison.json`` per strategy)
METRIC_KEYS = ("lag_s", "rms_at_lag_m", "saw_amplitude_ratio", "saw_correlation", "saw_by_episode",
               "strokes_intended", "strokes_executed", "stroke_share", "cutting_s", "rms_by_mode_m",
               "wearer_share_by_mode", "mode_steps", "pickups", "pickup_rms_m", "pickup_s", "pickup_error_share")


def saws(correlation: float | None, amplitude_ratio: float | None) -> bool:
    """The sawing criterion (:data:`SAWING_CRITERION`): correlation ≥ :data:`SAWING_MIN_CORRELATION` and
    amplitude ratio ≥ :data:`SAWING_MIN_AMPLITUDE`; False when either is None (no cutting)."""
    if correlation is None or amplitude_ratio is None:
        return False
    return correlation >= SAWING_MIN_CORRELATION and amplitude_ratio >= SAWING_MIN_AMPLITUDE


def episode_task_metrics(tip: np.ndarray, intent: np.ndarray, dt: float, true_mode: np.ndarray | None,
                         mode_names: Sequence[str] | None = None, alpha: np.ndarray | None = None) -> dict:
    """The eating figures of one episode (keys :data:`METRIC_KEYS`, JSON-able; None where undefined):
    the lag (:func:`sim.task.metrics.time_lag`), the pick-ups (:func:`sim.task.metrics.pickup_error`, with
    ``alpha``), and with ``true_mode`` (N,) labels into ``mode_names`` the RMS and wearer's share per mode and
    the sawing figures over the steps of the mode named :data:`STROKE_MODE`
    (:func:`sim.task.metrics.sawing_fidelity`) and per cutting episode (``saw_by_episode``: one
    ``{"start_s", "cutting_s", "saw_correlation", "saw_amplitude_ratio"}`` per episode of at least
    :data:`sim.task.metrics.MIN_EPISODE_S`, :func:`sim.task.metrics.sawing_by_episode`; [] without one).
    """
    names = tuple(mode_names) if mode_names is not None and len(mode_names) else None
    lag, rms_lag = time_lag(tip, intent, dt)
    out: dict = {"lag_s": None if not np.isfinite(lag) else lag,
                 "rms_at_lag_m": None if not np.isfinite(rms_lag) else rms_lag,
                 "saw_amplitude_ratio": None, "saw_correlation": None, "saw_by_episode": [], "strokes_intended": 0,
                 "strokes_executed": 0, "stroke_share": None, "cutting_s": 0.0, "rms_by_mode_m": {},
                 "wearer_share_by_mode": {}, "mode_steps": {}}
    if alpha is not None:
        out.update(pickup_error(tip, intent, alpha, dt))
    else:
        out.update(pickups=0, pickup_rms_m=None, pickup_s=0.0, pickup_error_share=None)
    if true_mode is None or not np.any(np.asarray(true_mode) >= 0):
        return out
    out["rms_by_mode_m"] = rms_by_mode(tip, intent, true_mode, names)
    if alpha is not None:
        out["wearer_share_by_mode"], out["mode_steps"] = wearer_share_by_mode(alpha, true_mode, names)
    if names is not None and STROKE_MODE in names:
        cutting = np.asarray(true_mode) == names.index(STROKE_MODE)
        f = sawing_fidelity(tip, intent, cutting, dt, STROKE_BAND_HZ)
        out["saw_by_episode"] = [{"start_s": start, "cutting_s": e.cutting_s, "saw_correlation": e.correlation,
                                  "saw_amplitude_ratio": e.amplitude_ratio}
                                 for start, e in sawing_by_episode(tip, intent, cutting, dt, STROKE_BAND_HZ)]
        out.update(saw_amplitude_ratio=f.amplitude_ratio, saw_correlation=f.correlation,
                   strokes_intended=f.strokes_intended, strokes_executed=f.strokes_executed,
                   stroke_share=f.stroke_share, cutting_s=f.cutting_s)
    return out


class Eating:
    """The eating task (:class:`sim.task.Task`; module docstring)."""

    name = "eating"
    mode_names = MODE_NAMES
    mode_colours = MODE_COLOURS
    stroke_mode = STROKE_MODE
    stroke_band_hz = STROKE_BAND_HZ
    criterion = SAWING_CRITERION
    metric_keys = METRIC_KEYS
    body = BODY
    shoulder_channels = SHOULDER_CHANNELS
    shoulder_to_plate = SHOULDER_TO_PLATE

    def episode_metrics(self, tip: np.ndarray, intent: np.ndarray, dt: float, true_mode: np.ndarray | None,
                        mode_names: Sequence[str] | None = None, alpha: np.ndarray | None = None) -> dict[str, Any]:
        """:func:`episode_task_metrics`."""
        return episode_task_metrics(tip, intent, dt, true_mode, mode_names, alpha)

    def done(self, metrics: Mapping[str, Any]) -> bool:
        """Whether the knife sawed while cutting: :func:`saws` of the row's correlation and amplitude ratio."""
        return saws(metrics.get("saw_correlation"), metrics.get("saw_amplitude_ratio"))

    def shoulder_map(self, names: Sequence[str] = (), gain: float = 0.5, deadband_rad: float = 0.01) -> ShoulderMap:
        """:meth:`robot.shoulder.ShoulderMap.for_channels` with :data:`SHOULDER_CHANNELS` and
        :data:`SHOULDER_TO_PLATE`."""
        return ShoulderMap.for_channels(names, SHOULDER_CHANNELS, SHOULDER_TO_PLATE, gain, deadband_rad)

    def __repr__(self) -> str:
        return "Eating()"


#: the task object (:func:`sim.task.task_named` finds a task module by this name)
TASK = Eating()
