"""The learned parts of :class:`~mpcshare.control.controller.SharedController`'s step (its module
docstring, item 1): the gate and the streaming predictor on a 10 Hz model tick (:func:`models_tick`),
and the control-rate forecast every step (:func:`fast_step`). A learned part that raises never stops
the loop: the fault is reported (``internal_error``) and its output dropped (α falls to 0)."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from mpcshare.control.fastpath import FastPath
from mpcshare.control.forecast import TipTrajectory
from mpcshare.control.setup import BundleLayout

__all__ = ["TickState", "fast_step", "models_tick"]


class TickState(NamedTuple):
    """What a model tick leaves to the arbitration until the next tick."""

    mode_proba: np.ndarray  # (K,) the mode posterior
    novelty: float  # the window's novelty score
    window_ready: bool  # whether the anti-aliased 10 Hz window is full
    gate_proba: float | None  # the gate's probability of the most probable mode (None: no window or it failed)


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
