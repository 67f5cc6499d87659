"""Conflict scenarios: data transforms of a held-out trial that put the knife and the wearer at odds.

``mpcshare sim --scenario NAME`` runs every strategy on the transformed trials.
The hand is the centre of :func:`robot.wearer_body.hand_center` (the fork handle's upper
end); event times are shares of the simulated duration so that short runs see them too.

* ``push`` — a wearer command into the hand: for 6 s (from 20 % of the run, 1 s ramps) the
  intended knife path (the trial's knife channels, the wearer's intent) turns into the hand;
* ``sweep`` — the hand sweeps into the knife three times (at 25, 50, 75 %): the fork moves
  toward the knife's intended tip, through the hand's radius, at a peak of 0.4 m/s, holds
  0.3 s and returns (the controller sees the fork move, as it would);
* ``face`` — an approach to the face: for 4 s (from 30 %) the intent turns toward the head;
* ``marker_lost`` — the fork marker is lost for 1 s while the hand sweeps toward the knife
  (the controller reads NaN, the world's fork sweeps): the stale zone must grow;
* ``predictor_fault`` — for 6 s (from 20 %) the reactive predictor's output and forecast point
  into the hand (a wrapped predictor; strategies with α = 0 never see it).
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Sequence

import numpy as np

if TYPE_CHECKING:  # the command line imports this module for SCENARIOS: the world is imported when used
    from sim.scene import SceneConfig
    from sim.task import Task

FORK_CHANNELS = ("fork_x", "fork_y", "fork_z", "fork_roll", "fork_pitch", "fork_yaw")  # sim.closed_loop's
TIP_CHANNELS = ("knife_x", "knife_y", "knife_z")

__all__ = ["SCENARIOS", "Scenario", "ScenarioTrial"]

SCENARIOS: tuple[str, ...] = ("push", "sweep", "face", "marker_lost", "predictor_fault")
SWEEP_SPEED = 0.4  # [m/s] peak speed of the hand's sweep


@dataclass
class ScenarioTrial:
    """A transformed trial, the world's fork pose (T, 6) and the window [s] of a predictor fault (or None)."""

    trial: Any
    fork_truth: np.ndarray
    fault_window: tuple[float, float] | None = None


def _ramp(t: np.ndarray, t0: float, t1: float, ramp: float) -> np.ndarray:
    """0 → 1 (cosine, ``ramp`` s) at t0, 1 → 0 at t1."""
    up = np.clip((t - t0) / ramp, 0.0, 1.0)
    down = np.clip((t1 - t) / ramp, 0.0, 1.0)
    return 0.5 - 0.5 * np.cos(np.pi * np.minimum(up, down))


def _sweep_profile(t: np.ndarray, t0: float, dist: float, hold: float = 0.3) -> np.ndarray:
    """Displacement [m] of a sweep out and back: cosine segments with peak speed :data:`SWEEP_SPEED`."""
    T = math.pi * dist / (2.0 * SWEEP_SPEED)
    out = np.zeros_like(t)
    go = (t >= t0) & (t < t0 + T)
    out[go] = 0.5 * dist * (1.0 - np.cos(np.pi * (t[go] - t0) / T))
    out[(t >= t0 + T) & (t < t0 + T + hold)] = dist
    back = (t >= t0 + T + hold) & (t < t0 + 2 * T + hold)
    out[back] = 0.5 * dist * (1.0 + np.cos(np.pi * (t[back] - t0 - T - hold) / T))
    return out


class Scenario:
    """One conflict scenario (module docstring) for data with ``obs_names``/``act_names``, in ``scene`` (default
    ``SceneConfig()``) beside the body of ``task`` (default eating's)."""

    def __init__(self, name: str, obs_names: Sequence[str], act_names: Sequence[str],
                 scene: SceneConfig | None = None, task: Task | None = None) -> None:
        from sim.scene import SceneConfig
        from sim.task import EATING

        if name not in SCENARIOS:
            raise ValueError(f"unknown scenario {name!r}; valid choices: {', '.join(SCENARIOS)}")
        obs, act = list(obs_names), list(act_names)
        missing = [c for c in FORK_CHANNELS if c not in obs] + [c for c in TIP_CHANNELS if c not in act]
        if missing:
            raise ValueError(f"scenario {name!r} needs the channels {missing} (obs {obs}, act {act})")
        self.name = name
        self.fork_cols = [obs.index(c) for c in FORK_CHANNELS]
        self.tip_cols = [act.index(c) for c in TIP_CHANNELS]
        self.body = (task or EATING).body
        sc = scene or SceneConfig()
        self.head_plate = np.asarray(self.body.head_center) - np.asarray(sc.plate_position)

    def hands(self, fork: np.ndarray) -> np.ndarray:
        """(T, 3) hand centres [m] (plate frame) of fork poses (T, 6)."""
        from robot.wearer_body import hand_center

        return np.array([hand_center(self.body, f) for f in fork])

    def apply(self, trial: Any, duration_s: float | None = None) -> ScenarioTrial:
        """The transformed trial (a copy) over its first ``duration_s`` seconds (None: all)."""
        t = np.asarray(trial.t, dtype=float) - float(trial.t[0])
        span = float(t[-1]) if duration_s is None else min(float(t[-1]), float(duration_s))
        obs, act = np.array(trial.obs, dtype=float), np.array(trial.act, dtype=float)
        fork = obs[:, self.fork_cols].copy()
        window = None
        if self.name in ("push", "face"):
            t0, length = (0.2 * span, 6.0) if self.name == "push" else (0.3 * span, 4.0)
            t1 = min(t0 + length, span)
            w = _ramp(t, t0, t1, min(1.0, 0.25 * (t1 - t0)))[:, None]
            target = self.hands(fork) if self.name == "push" else np.broadcast_to(self.head_plate, (len(t), 3))
            act[:, self.tip_cols] = (1.0 - w) * act[:, self.tip_cols] + w * target
        elif self.name in ("sweep", "marker_lost"):
            starts = (0.25, 0.5, 0.75) if self.name == "sweep" else (0.5,)
            for share in starts:
                k0 = int(np.searchsorted(t, share * span))
                hand0 = self.hands(fork[k0:k0 + 1])[0]
                to_knife = act[k0, self.tip_cols] - hand0
                dist = float(np.linalg.norm(to_knife))
                if dist < 1e-6:
                    continue
                shift = _sweep_profile(t, t[k0], dist + self.body.hand_radius)
                fork[:, :3] += shift[:, None] * (to_knife / dist)[None, :]
            obs[:, self.fork_cols] = fork
            if self.name == "marker_lost":
                k0 = int(np.searchsorted(t, 0.5 * span))
                obs[k0:int(np.searchsorted(t, t[k0] + 1.0)), :] = np.nan
        else:  # predictor_fault
            t0 = 0.2 * span
            window = (t0, min(t0 + 6.0, span))
        new = copy.copy(trial)
        new.obs, new.act = obs, act
        return ScenarioTrial(new, fork, window)

    def wrap_bundle(self, bundle: Any, st: ScenarioTrial, act_names: Sequence[str]) -> Any:
        """``bundle`` itself, or (``predictor_fault``) a shallow copy whose predictor points into the hand."""
        if st.fault_window is None:
            return bundle
        names = list(bundle.act_names)
        tip = [names.index(c) for c in TIP_CHANNELS]
        pre = bundle.preprocessor.act
        hands = self.hands(st.fork_truth)
        rate = 1.0 / float(np.median(np.diff(st.trial.t)))
        fault = _FaultyPredictor(bundle.predictor, hands, rate, float(bundle.model_hz), st.fault_window, tip,
                                 np.asarray(pre.mean_, dtype=float), np.asarray(pre.scale_, dtype=float))
        out = copy.copy(bundle)
        out.predictor = fault
        return out


class _FaultyPredictor:
    """A predictor whose stream, inside the fault window, outputs the hand as the knife tip."""

    def __init__(self, inner: Any, hands: np.ndarray, rate_hz: float, model_hz: float,
                 window: tuple[float, float], tip: list[int], mean: np.ndarray, scale: np.ndarray) -> None:
        self.inner, self.hands, self.rate, self.model_hz = inner, hands, rate_hz, model_hz
        self.window, self.tip, self.mean, self.scale = window, tip, mean, scale

    def make_stream(self) -> "_FaultyStream":
        return _FaultyStream(self, self.inner.make_stream())


class _FaultyStream:
    def __init__(self, owner: _FaultyPredictor, inner: Any) -> None:
        self.owner, self.inner, self.calls = owner, inner, 0
        self.forecast = None

    def step(self, x: np.ndarray) -> np.ndarray:
        o = self.owner
        u = np.array(self.inner.step(x), dtype=float)
        f = getattr(self.inner, "forecast", None)
        t = self.calls / o.model_hz
        self.calls += 1
        self.forecast = None if f is None else np.array(f, dtype=float)
        if o.window[0] <= t < o.window[1]:
            k = min(int(round(t * o.rate)), len(o.hands) - 1)
            target = (o.hands[k] - o.mean[o.tip]) / o.scale[o.tip]
            u[o.tip] = target
            if self.forecast is not None:
                self.forecast[:, o.tip] = target
        return u

    def reset(self) -> None:
        self.calls = 0
        if callable(getattr(self.inner, "reset", None)):
            self.inner.reset()
