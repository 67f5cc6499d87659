"""The wearer protocol: what the closed loop needs from a simulated person.

:func:`sim.closed_loop.run_episode` drives any object with the members of :class:`Wearer`, or builds one per
episode with a :class:`WearerFactory`, ``factory(intent, rate_hz, seed=seed)``, from the trial's intended knife
tip (``knife_x/y/z``, a row per control step). A class whose ``__init__`` takes ``(intent, rate_hz, *, seed)``
is itself a factory: ``run_episode(controller, trial, wearer=MyWearer)``. Per episode the loop reads:

- ``reset()``, once before the first step;
- ``intent`` (≥ N, 3) [m], plate frame: the intended tip per control step (recorded as ``tip_intent``, the
  metrics' reference; the arm starts at the configuration nearest ``intent[0]``);
- ``step(k, tip, alpha_cue)`` → shoulder angles θ (n,) [rad] (n = 3, or the channels of its shoulder map), given
  the measured tip (3,) [m] and the previous command's α (None before the first, NaN after a step without one);
- ``info()`` → JSON-able settings for the episode's ``info``, with ``shoulder_gain`` and
  ``shoulder_deadband_rad`` (:func:`sim.metrics.conflict_mask` maps θ back to a tip velocity with them), and
  ``shoulder_matrix`` (its P) where it is not the task's ``sim.task.eating.SHOULDER_TO_PLATE``.

A wearer that lacks a member is refused before the first step with :class:`sim.errors.WearerError`.
:class:`sim.wearer.SimulatedWearer` is the project's wearer; its settings (:class:`sim.wearer.WearerConfig`, the
presets of :mod:`sim.wearer_presets`) are factories of it.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np

from sim.errors import WearerError

__all__ = ["INFO_KEYS", "Wearer", "WearerFactory", "make_wearer"]

#: keys every ``Wearer.info()`` holds (read by the episode metrics)
INFO_KEYS = ("shoulder_gain", "shoulder_deadband_rad")


@runtime_checkable
class Wearer(Protocol):
    """A simulated person in the closed loop (module docstring)."""

    intent: np.ndarray

    def reset(self) -> None: ...

    def step(self, k: int, tip: np.ndarray, alpha_cue: float | None = None) -> np.ndarray: ...

    def info(self) -> dict[str, Any]: ...


class WearerFactory(Protocol):
    """Builds the wearer of one episode from its intent (n, 3) [m] sampled at ``rate_hz`` [Hz]."""

    def __call__(self, intent: np.ndarray, rate_hz: float, *, seed: int) -> Wearer: ...


def _is_wearer(obj: Any) -> bool:
    """An instance (not a class) with the protocol's methods."""
    return not isinstance(obj, type) and all(callable(getattr(obj, m, None)) for m in ("reset", "step", "info"))


def make_wearer(wearer: Wearer | WearerFactory, intent: np.ndarray, rate_hz: float, seed: int) -> Wearer:
    """The episode's wearer, reset: ``wearer`` itself when it is one, else ``wearer(intent, rate_hz, seed=seed)``.

    Raises :class:`sim.errors.WearerError` naming what is missing when the result does not
    follow the protocol, or its ``intent`` is shorter than ``intent`` (n steps), not (·, 3)
    or not finite, or its ``info()`` lacks :data:`INFO_KEYS`.
    """
    built = wearer if _is_wearer(wearer) else None
    if built is None:
        if not callable(wearer):
            raise WearerError(f"wearer must follow sim.wearer_protocol.Wearer (reset, step, info, intent) or be a "
                              f"factory called as f(intent, rate_hz, seed=seed), got {type(wearer).__name__}")
        built = wearer(intent, rate_hz, seed=seed)
        if not _is_wearer(built):
            raise WearerError(f"the wearer factory {wearer!r} returned a {type(built).__name__}, which lacks "
                              f"reset, step or info (sim.wearer_protocol.Wearer)")
    built.reset()
    own = np.asarray(getattr(built, "intent", None), dtype=float)
    n = np.asarray(intent).shape[0]
    if own.ndim != 2 or own.shape[1] != 3 or own.shape[0] < n or not np.isfinite(own[:n]).all():
        raise WearerError(f"{type(built).__name__}.intent must be finite (≥ {n}, 3) tip positions [m], "
                          f"got shape {own.shape}")
    info = built.info()
    if not isinstance(info, dict) or any(k not in info for k in INFO_KEYS):
        raise WearerError(f"{type(built).__name__}.info() must return a dict with {list(INFO_KEYS)}, got {info!r}")
    return built

