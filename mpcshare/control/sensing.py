"""The sensing stage of :class:`~mpcshare.control.controller.SharedController`'s step (its module docstring,
item 1): the fork sample through the front end (:func:`sense`; any object with the
:class:`~mpcshare.control.frontend.StreamingFrontEnd`'s ``step(t, obs) -> FrontEndOutput`` and ``reset()`` can
stand in for it, e.g. one that replays recorded outputs), the gate and the streaming predictor on a 10 Hz model
tick (:func:`models_tick`) and the control-rate forecast every step (:func:`fast_step`). A learned part that
raises never stops the loop: the fault is reported (``internal_error``) and its output dropped (α falls to 0)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from mpcshare.control.bundle_inputs import BundleLayout
from mpcshare.control.fastpath import FastPath
from mpcshare.control.forecast import TipTrajectory
from mpcshare.control.frontend import FrontEndOutput
from mpcshare.control.records import TickState

__all__ = ["TickState", "fast_step", "models_tick", "sense"]


def models_tick(t: float, tick: Any, *, stream: Any, gates: Any, layout: BundleLayout, fast: FastPath | None,
                forecast: TipTrajectory, oracle: bool, faults: list[tuple[str, str]]) -> TickState:
    """Gate and predictor on a 10 Hz tick at time t [s] (the gate held until the next tick, the predictor's
    forecast F = f_std·σ + μ of the act channels made a tip trajectory, or handed to ``fast``).

    ``stream``: the predictor's stream (``step(concat(o_t, p_t))``); ``gates``: the bundle's gates
    (``proba_one(window, mode)``); ``oracle``: the trajectory is a known preview, left as it is.
    """
    try:
        x = np.concatenate([tick.sample, tick.mode_proba])
        u_std = np.asarray(stream.step(x), dtype=float)
        f_std = getattr(stream, "forecast", None)
        f_std = u_std[None, :] if f_std is None else np.asarray(f_std, dtype=float)
        F = f_std * layout.act_scale + layout.act_mean
        if fast is not None:
            fast.on_tick(f_std)
        elif not oracle:
            forecast.update(t, F[:, layout.tip_index])
    except Exception as exc:  # noqa: BLE001 — a learned part must not stop the loop
        if fast is not None:
            fast.on_tick(None)
        elif not oracle:
            forecast.reset()
        faults.append(("internal_error", f"reactive predictor failed: {exc}"))
    gate_proba = None
    if tick.window is not None:
        try:
            gate_proba = float(gates.proba_one(tick.window, int(np.argmax(tick.mode_proba))))
        except Exception as exc:  # noqa: BLE001 — a learned part must not stop the loop
            faults.append(("internal_error", f"gate failed: {exc}"))
    return TickState(tick.mode_proba, tick.novelty, tick.window is not None, gate_proba)


def fast_step(t: float, fe: Any, mode_proba: np.ndarray, fast: FastPath, forecast: TipTrajectory,
              faults: list[tuple[str, str]]) -> None:
    """The control-rate forecast of this step (from the front end's fork state ``fe`` and the mode
    posterior) becomes the tip trajectory ``forecast``; on a failure the trajectory is reset."""
    try:
        F = fast.step(fe.fork_position, fe.fork_velocity, mode_proba, fe.tick is not None)
        if F is not None:
            forecast.update(t, F)
    except Exception as exc:  # noqa: BLE001 — a learned part must not stop the loop
        forecast.reset()
        faults.append(("internal_error", f"control-rate forecast failed: {exc}"))


def sense(t: float, obs: Any, faults: list[tuple[str, str]], *, frontend: Any, d_o: int,
          stale_after_s: float, keepout: Any = None, pose: np.ndarray | None = None) -> FrontEndOutput | None:
    """The controller's front-end stage: the fork sample ``obs`` (d_o,) at t [s] checked (a wrong shape is
    dropped, NaN or missing reported), ``frontend`` stepped and, with ``keepout`` (a
    :class:`mpcshare.control.keepout.KeepOut`), the body zones moved with the base pose ``pose`` (4, 4).
    Faults are appended to ``faults``; None: no fork sample was ever measured (the controller holds)."""
    o = np.asarray(obs, dtype=float) if obs is not None else None
    if o is not None and o.shape != (d_o,):
        faults.append(("invalid_observation_shape", f"obs has shape {o.shape}, expected ({d_o},)"))
        o = None
    elif o is None or not all(map(math.isfinite, o.tolist())):
        faults.append(("missing_observation", "fork sample missing or NaN: Kalman prediction substituted"))
    try:
        fe = frontend.step(t, o)
    except ValueError as exc:
        faults.append(("no_observation", f"{exc}: holding"))
        return None
    if keepout is not None:
        keepout.update(t, o, fe.fork_velocity, fe.stale, pose, faults)
    if fe.stale and not fe.predicting_for_s > stale_after_s:
        faults.append(("missing_observation", "fork sample repeated (stale): Kalman prediction substituted"))
    return fe
