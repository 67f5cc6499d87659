"""Plot of one closed-loop episode: the knife tip against the wearer's intent, α and β, the shoulder,
and a close-up of the sawing: the stroke band (0.8–3 Hz) of the tip and of the intent over the
4 s where the intent saws hardest (the band's energy, so no mode labels are needed).

Works on an :class:`sim.closed_loop.Episode` or on a run file loaded with
``Episode.load``. Drawn with :class:`matplotlib.figure.Figure` (no pyplot state).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from mpcshare.reports.style import legend_outside
from sim.task.eating import STROKE_BAND_HZ

__all__ = ["plot_episode"]


def _sawing_window(t: np.ndarray, intent_band: np.ndarray, seconds: float = 4.0,
                   allowed: np.ndarray | None = None) -> tuple[slice, int] | None:
    """(window, axis): the ``seconds`` where the intent saws hardest along one axis, scored by the
    stroke-band energy times the number of sign changes (a rhythm, not one fast move); only windows
    wholly inside ``allowed`` (e.g. the cutting steps) when there is one, shortened to its longest
    stretch (down to 1 s) when that is shorter than ``seconds``; None: too short."""
    dt = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    n = int(round(seconds / dt)) if dt > 0 else 0
    if n < 2 or t.size < n:
        return None
    ok = None if allowed is None or len(allowed) != t.size else np.asarray(allowed, dtype=bool)
    if ok is not None:
        edges = np.flatnonzero(np.diff(np.r_[0, ok.astype(int), 0]))  # starts and ends of the stretches
        longest = int((edges[1::2] - edges[0::2]).max()) if edges.size else 0
        ok = ok if longest * dt >= 1.0 else None  # no second of it: score every window
        n = n if ok is None else min(n, longest)
    box = np.ones(n)
    inside = None if ok is None else np.convolve(~ok, box, mode="valid") == 0
    best = (-1.0, 0, 0)
    for axis in range(intent_band.shape[1]):
        x = intent_band[:, axis]
        crossings = np.r_[0.0, (np.sign(x[1:]) != np.sign(x[:-1])).astype(float)]
        score = np.convolve(x ** 2, box, mode="valid") * np.convolve(crossings, box, mode="valid")
        if inside is not None:
            score = np.where(inside, score, -1.0)
        k = int(np.argmax(score))
        if score[k] > best[0]:
            best = (float(score[k]), k, axis)
    return slice(best[1], best[1] + n), best[2]


def plot_episode(episode: Any, path: str | Path, title: str = "", cutting: np.ndarray | None = None,
                 band: tuple[float, float] | None = STROKE_BAND_HZ) -> Path:
    """Panels over time: tip x/y/z with intent and reference [m], α and β, shoulder angles [rad];
    then the sawing close-up (module docstring) in the stroke ``band`` [Hz] (a task's
    ``stroke_band_hz``; None: no close-up, the task has no strokes), taken inside the
    ``cutting`` steps (bool per control step) when given, so that a repositioning jump is not mistaken for a
    stroke."""
    from sim.task.metrics import bandpass

    t = np.asarray(episode.t, dtype=float)
    fig = Figure(figsize=(11.5, 10), constrained_layout=True)
    grid = fig.add_gridspec(6, 1, height_ratios=[1, 1, 1, 0.8, 0.8, 1.1])
    axes = [fig.add_subplot(grid[0])]
    axes += [fig.add_subplot(grid[i], sharex=axes[0]) for i in range(1, 5)]
    saw_ax = fig.add_subplot(grid[5])
    for i, axis in enumerate("xyz"):
        ax = axes[i]
        ax.plot(t, episode.tip_intent[:, i], color="0.3", lw=1.2, label="intent (demonstration)")
        ax.plot(t, episode.tip_reference[:, i], color="#DD8452", lw=0.9, ls="--", label="reference")
        ax.plot(t, episode.tip[:, i], color="#4C72B0", lw=1.0, label="knife tip")
        ax.set_ylabel(f"{axis} [m]")
    legend_outside(axes[0])
    axes[3].plot(t, episode.alpha, color="#55A868", label="α (robot)")
    axes[3].plot(t, episode.beta, color="#C44E52", lw=0.8, label="β (wearer)")
    axes[3].set_ylim(-0.05, 1.05)
    axes[3].set_ylabel("weight")
    legend_outside(axes[3])
    for i, name in enumerate(episode.shoulder_names):
        axes[4].plot(t, episode.voluntary[:, i], lw=0.8, label=name.removeprefix("shoulder_"))
    axes[4].set_ylabel("shoulder [rad]")
    legend_outside(axes[4])
    dt = float(np.median(np.diff(t))) if t.size > 1 else 0.0
    ok = np.isfinite(episode.tip).all(axis=1) & np.isfinite(episode.tip_intent).all(axis=1)
    found = None
    if band is not None and dt > 0 and ok.all() and t.size > 60:
        tip_b, intent_b = bandpass(episode.tip, dt, band), bandpass(episode.tip_intent, dt, band)
        found = _sawing_window(t, intent_b, allowed=cutting)
    if found is not None:
        window, axis = found
        saw_ax.plot(t[window], 1e3 * intent_b[window, axis], color="0.3", lw=1.2, label="intended stroke")
        saw_ax.plot(t[window], 1e3 * tip_b[window, axis], color="#4C72B0", lw=1.0, label="knife tip")
        saw_ax.set_ylabel(f"{'xyz'[axis]}, {band[0]:g}–{band[1]:g} Hz [mm]")
        saw_ax.set_title("sawing: the stroke band where the intent saws hardest", fontsize=8)
        legend_outside(saw_ax)
    else:
        why = "no strokes in this task" if band is None else "too short for the stroke band"
        saw_ax.text(0.5, 0.5, why, ha="center", va="center", transform=saw_ax.transAxes)
    saw_ax.set_xlabel("time [s]")
    if title:
        fig.suptitle(title, fontsize=10)
    path = Path(path)
    fig.savefig(path, dpi=100)
    return path
